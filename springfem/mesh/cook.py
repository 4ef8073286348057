"""Cook's membrane: the tapered panel (0,0)-(48,44)-(48,60)-(0,44) mm, extruded.

Cook's membrane (Cook 1974; in 3D e.g. Puso & Solberg 2006) is the standard bending-shear
test of nearly incompressible elements: the left edge ``x = 0`` is clamped and a shear
traction acts on the right edge ``x = 48``; the top right corner's vertical displacement
is the quantity compared. The mesh is a structured grid of ``divisions`` cells, each split
into six tets, mapped bilinearly onto the panel, with the nodes moved at random (``jitter``
of a cell along each axis, nodes on a face only within it) so that no element is aligned
with another.

Examples
--------
>>> m = cook_membrane_mesh((4, 4, 1), thickness=10.0)
>>> m.n_points, m.n_tets
(50, 96)
>>> round(float(m.volumes().sum()), 9)  # (44 + 16) / 2 * 48 * 10: the panel's volume
14400.0
>>> bool((m.volumes() > 0).all())
True
"""

from __future__ import annotations

import numpy as np

from ..errors import MeshError
from .generate import box_mesh
from .tetmesh import TetMesh

#: Corners of the panel (mm): bottom left, bottom right, top right, top left.
CORNERS = ((0.0, 0.0), (48.0, 44.0), (48.0, 60.0), (0.0, 44.0))


def cook_membrane_mesh(
    divisions: tuple[int, int, int] = (16, 16, 2),
    thickness: float = 10.0,
    jitter: float = 0.2,
    seed: int = 0,
) -> TetMesh:
    """Jittered structured tets of Cook's membrane, extruded along z.

    Parameters
    ----------
    divisions
        Cells along x (48 mm), along the tapered height and through the thickness.
    thickness
        Extrusion depth (mm); the panel spans ``0 <= z <= thickness``.
    jitter
        Random move of each node, up to this fraction of its cell along each grid axis
        (in ``[0, 0.3]``; nodes on a face move only within it, so the panel keeps its shape).
    seed
        Seed of the random moves (the mesh is a function of the arguments).

    Returns
    -------
    TetMesh
        Positively oriented; the regions ``x_min`` (the clamped edge) and ``x_max`` (the
        loaded edge) come from :mod:`springfem.regions` as for any mesh.

    Raises
    ------
    MeshError
        Non-positive divisions or thickness, or a jitter outside ``[0, 0.3]``.
    """
    nx, ny, nz = (int(d) for d in divisions)
    if min(nx, ny, nz) < 1 or not thickness > 0:
        raise MeshError(
            f"Cook's membrane needs positive divisions and thickness, got {list(divisions)}, "
            f"{thickness}"
        )
    if not 0.0 <= jitter <= 0.3:
        raise MeshError(f"Cook's membrane jitter must be in [0, 0.3] of a cell, got {jitter}")
    unit = box_mesh((1.0, 1.0, 1.0), (nx, ny, nz), split="six")
    st = unit.points.copy()
    h = 1.0 / np.array([nx, ny, nz], dtype=float)
    move = np.random.default_rng(seed).uniform(-jitter, jitter, st.shape) * h
    on_face = np.isclose(st, 0.0) | np.isclose(st, 1.0)
    st = st + np.where(on_face, 0.0, move)
    s, t, w = st.T
    (x0, y0), (x1, y1), (x2, y2), (x3, y3) = CORNERS
    bottom = np.column_stack([x0 + s * (x1 - x0), y0 + s * (y1 - y0)])
    top = np.column_stack([x3 + s * (x2 - x3), y3 + s * (y2 - y3)])
    xy = bottom + t[:, None] * (top - bottom)
    points = np.column_stack([xy, thickness * w])
    mesh = TetMesh(
        points=points,
        tets=unit.tets.copy(),
        source=f"Cook's membrane divisions {[nx, ny, nz]} thickness {thickness} seed {seed}",
    )
    if not (mesh.volumes() > 0).all():  # pragma: no cover - jitter <= 0.3 keeps them
        raise MeshError("Cook's membrane: the jitter inverted a tet; lower it")
    return mesh
