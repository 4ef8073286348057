"""Mesh validation: reject what can't be solved, repair or note what can.

Examples
--------
>>> import numpy as np
>>> m = TetMesh(np.array([[0, 0, 0], [0, 1, 0], [1, 0, 0], [0, 0, 1.0]]), np.array([[0, 1, 2, 3]]))
>>> validate_mesh(m).notes
['mesh: reoriented 1 inverted tets']
"""

from __future__ import annotations

import numpy as np

from ..errors import MeshError, format_ids
from .tetmesh import TetMesh, mean_ratio_quality, tet_volumes
from .topology import topology_notes

#: Largest coordinate magnitude (m): squared lengths and volumes stay finite in float64.
MAX_COORDINATE = 1e100
#: Mean-ratio quality below which a tet is reported as a sliver (a note, not an error).
SLIVER_QUALITY = 1e-2


def validate_mesh(mesh: TetMesh, name: str = "mesh", rel_volume_tol: float = 1e-12) -> TetMesh:
    """Check and repair a mesh in place; raise :class:`MeshError` for what can't be repaired.

    Rejected: non-finite coordinates or coordinates beyond :data:`MAX_COORDINATE`, no tets,
    node indices out of range, zero-volume tets (``|V| <= rel_volume_tol l^3`` with ``l``
    the tet's longest edge), duplicate tets, coincident nodes used by tets, non-manifold
    facets (a triangle shared by three or more tets) and folds (two tets on the same side of
    their shared triangle): both mean overlapping tets.

    Repaired or reported (in ``mesh.notes``): inverted tets are reoriented, unreferenced
    nodes are removed; sliver tets (mean-ratio quality below :data:`SLIVER_QUALITY`),
    disconnected parts and non-manifold nodes (parts touching only at a node or an edge)
    are noted. Those three are legal meshes both models can solve, but each part needs its
    own boundary conditions, and slivers lower the stable explicit time step.

    Parameters
    ----------
    mesh
        The mesh, changed in place.
    name
        Its name in notes and errors (the file name).
    rel_volume_tol
        Zero-volume threshold relative to the cube of the longest edge.

    Returns
    -------
    TetMesh
        ``mesh`` itself, repaired, with float64 points and int64 tets.

    Raises
    ------
    MeshError
        Naming the offending nodes or tets.
    """
    pts, tets = mesh.points, mesh.tets
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise MeshError(f"{name}: points must have shape (n, 3), got {pts.shape}")
    bad = np.flatnonzero(~np.isfinite(pts).all(axis=1))
    if bad.size:
        raise MeshError(f"{name}: non-finite coordinates at nodes {format_ids(bad)}")
    bad = np.flatnonzero((np.abs(pts) > MAX_COORDINATE).any(axis=1))
    if bad.size:
        raise MeshError(
            f"{name}: coordinates beyond ±{MAX_COORDINATE:g} at nodes {format_ids(bad)}; "
            "use other units (mesh.scale)"
        )
    if tets.ndim != 2 or tets.shape[1] != 4 or tets.shape[0] == 0:
        raise MeshError(f"{name}: contains no tetrahedra")
    if tets.min() < 0 or tets.max() >= len(pts):
        bad = np.flatnonzero((tets < 0).any(axis=1) | (tets >= len(pts)).any(axis=1))
        raise MeshError(f"{name}: tets {format_ids(bad)} reference nodes that do not exist")
    repeated = np.flatnonzero(
        (np.sort(tets, axis=1)[:, 1:] == np.sort(tets, axis=1)[:, :-1]).any(1)
    )
    if repeated.size:
        raise MeshError(f"{name}: zero-volume tets {format_ids(repeated)} (a node repeated)")
    key = np.sort(tets, axis=1)
    _, first, inverse, counts = np.unique(
        key, axis=0, return_index=True, return_inverse=True, return_counts=True
    )
    dup = np.flatnonzero(counts[inverse.ravel()] > 1)
    if dup.size:
        raise MeshError(f"{name}: duplicate tets {format_ids(dup)} (same four nodes)")
    vol = tet_volumes(pts, tets)
    zero = np.flatnonzero(np.abs(vol) <= rel_volume_tol * _longest_edges(pts, tets) ** 3)
    if zero.size:
        raise MeshError(f"{name}: zero-volume tets {format_ids(zero)}")
    used = np.zeros(len(pts), dtype=bool)
    used[tets.ravel()] = True
    upts = np.flatnonzero(used)
    rounded = np.round(pts[upts] / (np.ptp(pts, axis=0).max() * 1e-12 + 1e-300))
    _, uidx, uinv, ucnt = np.unique(
        rounded, axis=0, return_index=True, return_inverse=True, return_counts=True
    )
    if (ucnt > 1).any():
        grp = np.flatnonzero(ucnt[uinv.ravel()] > 1)
        raise MeshError(
            f"{name}: duplicate nodes {format_ids(upts[grp])} (coincident coordinates; merge them)"
        )
    inverted = vol < 0
    if inverted.any():
        tets = tets.copy()
        tets[inverted] = tets[inverted][:, [0, 2, 1, 3]]
        mesh.notes.append(f"{name}: reoriented {int(inverted.sum())} inverted tets")
    mesh.notes.extend(topology_notes(tets, name))
    q = mean_ratio_quality(pts, tets)
    slivers = np.flatnonzero(q < SLIVER_QUALITY)
    if slivers.size:
        worst = slivers[np.argsort(q[slivers], kind="stable")]
        mesh.notes.append(
            f"{name}: {slivers.size} sliver tet{'s' if slivers.size > 1 else ''} (mean-ratio "
            f"quality below {SLIVER_QUALITY:g}, "
            f"worst {q[worst[0]]:.2g}): {format_ids(worst)}"
        )
    if not used.all():
        n_unused = int((~used).sum())
        remap = -np.ones(len(pts), dtype=np.int64)
        remap[used] = np.arange(used.sum())
        pts = pts[used]
        tets = remap[tets]
        mesh.node_sets = {k: remap[v][remap[v] >= 0] for k, v in mesh.node_sets.items()}
        mesh.facet_sets = {
            k: remap[v][(remap[v] >= 0).all(axis=1)] for k, v in mesh.facet_sets.items()
        }
        mesh.notes.append(f"{name}: removed {n_unused} nodes not used by any tet")
    mesh.points = np.ascontiguousarray(pts, dtype=np.float64)
    mesh.tets = np.ascontiguousarray(tets, dtype=np.int64)
    if hasattr(mesh, "_boundary"):
        del mesh._boundary
    return mesh


def _longest_edges(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Longest edge length of each tet."""
    x = points[tets]
    l2 = [((x[:, a] - x[:, b]) ** 2).sum(axis=1) for a, b in _EDGES]
    return np.sqrt(np.max(l2, axis=0))


_EDGES = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))
