"""Tets across a thin wall: is a mesh too coarse through its thickness for linear tets?

A linear tet has one constant strain and one fibre frame, so a wall one tet thick cannot
bend through its thickness and loses a fibre helix that turns through it: every linear-tet
model on it (P1, the locking-free P1 variants, the spring elements) is far from a converged
solution however good its element is. Measured on a left ventricle of cardiac-geometries
(2,838 tets, about one tet across, Holzapfel–Ogden, 2 kPa): P1 58 %, nodal-strain P1 and
the default spring element 54 % off the P2/P1 reference, which itself moves 105 % when
given the elements' fibres (docs/tissue.rst#thin-walls-one-tet-across).

The estimate walks a ray from each boundary facet's centroid along its inward normal,
tet to tet through shared faces, until it leaves the body: the path length is the wall's
thickness there, and its ratio to the mean extent along the ray of the tets it crossed is
the number of tet layers across (1 for a wall whose every tet reaches both faces, 2 for
two layers of such tets). A solid body has many layers under most of its surface; a wall
meshed one tet across has about one under most of it.

Examples
--------
>>> from springfem.mesh import box_mesh
>>> plate = box_mesh((10.0, 10.0, 1.0), (10, 10, 1))  # one tet layer across
>>> float(np.median(tets_across(plate))), thin_wall_note(plate) is not None
(1.0, True)
>>> thin_wall_note(box_mesh((1.0, 1.0, 1.0), (6, 6, 6))) is None  # a solid cube
True
"""

from __future__ import annotations

import numpy as np

from .tetmesh import _FACES, TetMesh

#: A wall with fewer tet layers than this under a boundary facet is "thin" there.
THIN_LAYERS = 1.75
#: The note is given when at least this share of the boundary area is thin.
THIN_SHARE = 0.5
#: Most tets a ray crosses before it counts as deep inside a solid body.
MAX_STEPS = 64


def face_neighbours(tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The tet across each face and that face's index in it.

    Parameters
    ----------
    tets
        ``(m, 4)`` node indices; face ``i`` of a tet is the one opposite its vertex ``i``.

    Returns
    -------
    neighbour : numpy.ndarray
        ``(m, 4)``: the tet across face ``i``, ``-1`` on the boundary.
    face : numpy.ndarray
        ``(m, 4)``: the local index of the shared face in that tet (``-1`` on the boundary).

    Examples
    --------
    >>> nb, f = face_neighbours(np.array([[0, 1, 2, 3], [1, 2, 3, 4]]))
    >>> nb.tolist(), f.tolist()
    ([[1, -1, -1, -1], [-1, -1, -1, 0]], [[3, -1, -1, -1], [-1, -1, -1, 0]])
    """
    tets = np.asarray(tets, dtype=np.int64)
    m = len(tets)
    key = np.sort(tets[:, _FACES].reshape(-1, 3), axis=1)  # row 4 t + i: face i of tet t
    _, ids = np.unique(key, axis=0, return_inverse=True)
    ids = ids.ravel()
    order = np.argsort(ids, kind="stable")
    same = ids[order[1:]] == ids[order[:-1]]
    a, b = order[:-1][same], order[1:][same]
    neighbour = np.full(4 * m, -1, dtype=np.int64)
    face = np.full(4 * m, -1, dtype=np.int64)
    neighbour[a], neighbour[b] = b // 4, a // 4
    face[a], face[b] = b % 4, a % 4
    return neighbour.reshape(m, 4), face.reshape(m, 4)


def _barycentric_gradients(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """``(m, 4, 3)``: the gradient of each vertex's barycentric coordinate."""
    x = points[tets]
    J = (x[:, 1:] - x[:, :1]).transpose(0, 2, 1)  # columns x_j - x_0
    try:
        G = np.linalg.inv(J)  # rows: grad lambda_1..3
    except np.linalg.LinAlgError:  # a flat tet: no ray crosses it sensibly, but go on
        G = np.linalg.pinv(J)
    return np.concatenate([-G.sum(axis=1, keepdims=True), G], axis=1)


def wall_rays(mesh: TetMesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Walk a ray inward from every boundary facet until it leaves the body.

    Parameters
    ----------
    mesh
        The mesh (positively oriented tets).

    Returns
    -------
    length : numpy.ndarray
        ``(k,)`` path length through the body from each boundary facet along its inward
        normal (``inf`` for a ray still inside after :data:`MAX_STEPS` tets).
    height : numpy.ndarray
        ``(k,)`` mean extent of the tets crossed along the ray.
    area : numpy.ndarray
        ``(k,)`` facet areas.
    """
    points = np.asarray(mesh.points, dtype=float)
    tets = np.asarray(mesh.tets, dtype=np.int64)
    neighbour, shared = face_neighbours(tets)
    grads = _barycentric_gradients(points, tets)
    tet, face = np.nonzero(neighbour < 0)  # the boundary facets
    corners = points[tets[tet[:, None], _FACES[face]]]
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0],
                                         corners[:, 2] - corners[:, 0]), axis=1)  # fmt: skip
    g = grads[tet, face]
    d = g / np.linalg.norm(g, axis=1, keepdims=True)  # inward: lambda_face grows
    p = corners.mean(axis=1)
    k = len(tet)
    length, heights, steps = np.zeros(k), np.zeros(k), np.zeros(k, dtype=np.int64)
    live = np.arange(k)
    cur, entry = tet.copy(), face.copy()
    for _ in range(MAX_STEPS):
        if live.size == 0:
            break
        e = cur[live]
        lam = np.einsum("kij,kj->ki", grads[e], p[live] - points[tets[e, 0]])
        lam[:, 0] = 1.0 - lam[:, 1:].sum(axis=1)
        rate = np.einsum("kij,kj->ki", grads[e], d[live])
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(rate < 0.0, -np.maximum(lam, 0.0) / rate, np.inf)
        t[np.arange(live.size), entry[live]] = np.inf
        out = np.argmin(t, axis=1)
        step = t[np.arange(live.size), out]
        step = np.where(np.isfinite(step), step, 0.0)
        p[live] += step[:, None] * d[live]
        length[live] += step
        depth = np.einsum("kij,kj->ki", points[tets[e]], d[live])
        heights[live] += depth.max(axis=1) - depth.min(axis=1)
        steps[live] += 1
        nxt = neighbour[e, out]
        cur[live], entry[live] = nxt, shared[e, out]
        live = live[nxt >= 0]
    length[live] = np.inf
    return length, heights / np.maximum(steps, 1), area


def tets_across(mesh: TetMesh) -> np.ndarray:
    """Tet layers across the body under each boundary facet: thickness / tet extent.

    Parameters
    ----------
    mesh
        The mesh.

    Returns
    -------
    numpy.ndarray
        ``(k,)``, one per boundary facet (``inf`` deep inside a large solid body).

    Examples
    --------
    >>> from springfem.mesh import box_mesh
    >>> float(np.median(tets_across(box_mesh((8.0, 8.0, 1.0), (8, 8, 2)))))  # two layers
    2.0
    """
    length, height, _ = wall_rays(mesh)
    return length / np.maximum(height, 1e-300)


def thin_wall_note(
    mesh: TetMesh, layers: float = THIN_LAYERS, share: float = THIN_SHARE
) -> str | None:
    """One line when the mesh is too coarse across a thin wall for linear tets, else ``None``.

    Parameters
    ----------
    mesh
        The mesh.
    layers
        Fewer tet layers than this under a boundary facet make the wall thin there.
    share
        The note is given when at least this share of the boundary area is thin.

    Returns
    -------
    str or None
        E.g. ``"thin wall: 93 % of the surface has fewer than 1.75 tets across (median
        1.0); linear tets ..."``.
    """
    length, height, area = wall_rays(mesh)
    across = length / np.maximum(height, 1e-300)
    thin = across < layers
    part = float(area[thin].sum() / area.sum()) if area.sum() > 0 else 0.0
    if part < share:
        return None
    return (
        f"thin wall: {100 * part:.0f} % of the surface has fewer than {layers:g} tets across "
        f"(median {np.median(across):.1f}); linear tets (P1, the spring elements) cannot bend "
        "through it, and rule-based fibres lose their turn through it: refine to 2 or more "
        "tets across, or use P2"
    )
