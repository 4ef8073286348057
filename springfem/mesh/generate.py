"""Box meshes: every hexahedron of a grid split into five or six tets, or the Delaunay
tets of a jittered grid (an unstructured mesh of the same box).

Examples
--------
>>> m = box_mesh((1.0, 1.0, 1.0), (2, 2, 2), split="six")
>>> m.n_points, m.n_tets
(27, 48)
>>> round(float(m.volumes().sum()), 12)
1.0
>>> d = box_mesh((1.0, 1.0, 1.0), (3, 3, 3), split="delaunay", seed=0)
>>> round(float(d.volumes().sum()), 12), bool((d.volumes() > 0).all())
(1.0, True)
"""

from __future__ import annotations

from typing import Literal, get_args

import numpy as np

from ..errors import MeshError
from .tetmesh import TetMesh, tet_volumes
from .validate import MAX_COORDINATE

Split = Literal["five", "six", "five-mirrored", "six-mirrored", "delaunay"]
#: A Delaunay tet below this fraction of a grid cell's volume is flat (dropped).
MIN_DELAUNAY_VOLUME = 1e-6

# Hexahedron corners, local index -> (i, j, k) offsets.
_HEX_CORNERS = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]
)
# Six tets around the main diagonal 0-6 (Kuhn/Freudenthal split): conforming when every
# hexahedron is split the same way.
_SIX = np.array(
    [[0, 1, 2, 6], [0, 2, 3, 6], [0, 3, 7, 6], [0, 7, 4, 6], [0, 4, 5, 6], [0, 5, 1, 6]]
)
# Five tets: four corner tets and the central tet on the even corners 0, 2, 5, 7. Face
# diagonals alternate between opposite faces, so neighbours must use the mirrored split.
_FIVE_EVEN = np.array([[1, 0, 2, 5], [3, 2, 0, 7], [4, 5, 7, 0], [6, 7, 5, 2], [0, 2, 5, 7]])
_FIVE_ODD = np.array([[0, 1, 3, 4], [2, 3, 1, 6], [5, 4, 6, 1], [7, 6, 4, 3], [1, 3, 4, 6]])


def box_mesh(
    size: tuple[float, float, float],
    divisions: tuple[int, int, int],
    split: Split = "six",
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0),
    jitter: float = 0.3,
    seed: int = 0,
) -> TetMesh:
    """Box mesh: each hexahedron split into five or six tets, or Delaunay tets.

    Parameters
    ----------
    size
        Box edge lengths.
    divisions
        Number of hexahedra along x, y, z.
    split
        ``six``: six tets around the main diagonal of every hexahedron (all alike).
        ``six-mirrored``: the same split mirrored across every other hexahedron along each
        axis, so each 2x2x2 block is symmetric. ``five``: five tets per hexahedron; a
        conforming five-tet mesh must alternate the two mirror-image splits, so ``five``
        starts with the even split at the origin and ``five-mirrored`` with the odd one
        (the mirror image of ``five``). ``delaunay``: an unstructured mesh, the Delaunay
        tets of the grid's nodes moved at random (see ``jitter``), so that no element is
        aligned with the axes.
    origin
        Coordinates of the box corner with the smallest coordinates.
    jitter, seed
        ``delaunay`` only: interior nodes move by up to ``jitter`` of a cell along each
        axis, nodes on a face only within it (the box and its faces are kept exactly);
        ``seed`` of the random moves (the mesh is a function of the arguments).

    Returns
    -------
    TetMesh
        With node sets ``x_min`` … ``z_max`` left to :mod:`springfem.regions`.
    """
    if split not in get_args(Split):
        raise MeshError(f"mesh split {split!r} is not one of {', '.join(get_args(Split))}")
    nx, ny, nz = (int(d) for d in divisions)
    if min(nx, ny, nz) < 1:
        raise MeshError(f"mesh divisions must be positive integers, got {list(divisions)}")
    if min(size) <= 0 or not np.all(np.isfinite(size)):
        raise MeshError(f"mesh size must be positive and finite, got {list(size)}")
    axes = [np.linspace(o, o + s, n + 1) for o, s, n in zip(origin, size, (nx, ny, nz))]
    _check_box_axes(axes, size, origin, (nx, ny, nz))
    X, Y, Z = np.meshgrid(*axes, indexing="ij")
    points = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    if split == "delaunay":
        return _delaunay_box(points, size, origin, (nx, ny, nz), jitter, seed)

    def node(i, j, k):
        return (i * (ny + 1) + j) * (nz + 1) + k

    I3, J3, K3 = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    I, J, K = I3.ravel(), J3.ravel(), K3.ravel()
    if split.startswith("six"):
        if split == "six-mirrored":
            # mirror the corner offsets of odd hexahedra along each axis
            off = np.stack(
                [
                    np.where(
                        (I % 2)[:, None] == 1, 1 - _HEX_CORNERS[None, :, 0], _HEX_CORNERS[:, 0]
                    ),
                    np.where(
                        (J % 2)[:, None] == 1, 1 - _HEX_CORNERS[None, :, 1], _HEX_CORNERS[:, 1]
                    ),
                    np.where(
                        (K % 2)[:, None] == 1, 1 - _HEX_CORNERS[None, :, 2], _HEX_CORNERS[:, 2]
                    ),
                ],
                axis=-1,
            )
        else:
            off = np.broadcast_to(_HEX_CORNERS, (I.size, 8, 3))
        corners = node(I[:, None] + off[..., 0], J[:, None] + off[..., 1], K[:, None] + off[..., 2])
        tets = np.take_along_axis(
            corners[:, None, :].repeat(6, axis=1), _SIX[None].repeat(I.size, axis=0), axis=2
        ).reshape(-1, 4)
    else:
        corners = node(
            I[:, None] + _HEX_CORNERS[:, 0],
            J[:, None] + _HEX_CORNERS[:, 1],
            K[:, None] + _HEX_CORNERS[:, 2],
        )
        parity = (I + J + K + (1 if split == "five-mirrored" else 0)) % 2
        local = np.where(parity[:, None, None] == 0, _FIVE_EVEN[None], _FIVE_ODD[None])
        tets = np.take_along_axis(corners[:, None, :].repeat(5, axis=1), local, axis=2).reshape(
            -1, 4
        )
    tets = tets.astype(np.int64)
    vol = tet_volumes(points, tets)
    flip = vol < 0
    tets[flip] = tets[flip][:, [0, 2, 1, 3]]
    desc = f"box {[float(s) for s in size]} divisions {[nx, ny, nz]} split {split}"
    return TetMesh(points=points, tets=tets, source=desc)


def _delaunay_box(points, size, origin, divisions, jitter: float, seed: int) -> TetMesh:
    """The Delaunay tets of the grid ``points`` moved at random (see :func:`box_mesh`)."""
    from scipy.spatial import Delaunay

    if not 0.0 <= jitter < 0.5:
        raise MeshError(f"mesh jitter must be in [0, 0.5) of a cell, got {jitter}")
    rng = np.random.default_rng(seed)
    lo = np.asarray(origin, float)
    hi = lo + np.asarray(size, float)
    h = np.asarray(size, float) / np.asarray(divisions, float)
    move = rng.uniform(-jitter, jitter, points.shape) * h
    on_face = np.isclose(points, lo) | np.isclose(points, hi)
    pts = points + np.where(on_face, 0.0, move)
    tets = Delaunay(pts).simplices.astype(np.int64)
    vol = tet_volumes(pts, tets)
    keep = np.abs(vol) > MIN_DELAUNAY_VOLUME * float(np.prod(h))
    tets, vol = tets[keep], vol[keep]
    tets[vol < 0] = tets[vol < 0][:, [0, 2, 1, 3]]
    desc = f"jittered Delaunay box {list(divisions)} seed {seed}"
    return TetMesh(pts, tets, source=desc)


def _check_box_axes(axes: list[np.ndarray], size, origin, divisions) -> None:
    """Refuse box parameters whose nodes float64 can't hold apart or whose tets it can't measure.

    The same criteria as :func:`validate_mesh` (finite coordinates within
    :data:`MAX_COORDINATE`, no zero-volume tet), checked on the grid lines before the mesh
    is built.
    """
    desc = f"size {list(map(float, size))}, origin {list(map(float, origin))}"
    for a, name in zip(axes, "xyz"):
        if not np.isfinite(a).all() or np.abs(a).max() > MAX_COORDINATE:
            raise MeshError(
                f"mesh {desc}: {name} coordinates beyond ±{MAX_COORDINATE:g}; use other units"
            )
        if not (np.diff(a) > 0).all():
            raise MeshError(
                f"mesh {desc}, divisions {list(divisions)}: grid lines along {name} coincide in "
                "float64 (cells too small for the coordinates); move the origin or coarsen"
            )
    h_min = np.array([np.diff(a).min() for a in axes])
    h_max = np.array([np.diff(a).max() for a in axes])
    v_min = float(np.prod(h_min)) / 6.0  # the smallest tet of a five or six split
    if not (v_min >= np.finfo(float).tiny and v_min > 1e-12 * float(np.sum(h_max**2)) ** 1.5):
        raise MeshError(
            f"mesh {desc}, divisions {list(divisions)}: zero-volume tets (cells of "
            f"{h_min.tolist()} m can't be measured in float64); use other units"
        )
