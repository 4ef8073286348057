"""Uniform refinement of a tetrahedral mesh: each tet into 8 (edge midpoints).

Every edge gets its midpoint; each tet becomes its four corner tets plus four tets of the
inner octahedron, split along its shortest diagonal (the better-shaped choice). The
children fill their parent exactly, so volumes and the boundary surface are preserved and
the mesh size halves. Named regions follow: a tet's children keep its cell sets and cell
data, a boundary triangle's four children keep its facet sets, and a node set gains the
midpoints of edges with both ends in it.

Examples
--------
>>> from springfem.mesh.generate import box_mesh
>>> m = box_mesh((1.0, 1.0, 1.0), (1, 1, 1), split="six")
>>> r = refine_uniform(m)
>>> r.n_tets, r.n_points
(48, 27)
>>> round(float(r.volumes().sum()), 12)
1.0
"""

from __future__ import annotations

import numpy as np

from .tetmesh import TetMesh, tet_volumes

_EDGES = np.array([[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]])


def _edge_midpoints(points: np.ndarray, tets: np.ndarray):
    """Unique edges, their midpoint node ids and a lookup ``(a, b) -> id``."""
    n = points.shape[0]
    pairs = np.sort(tets[:, _EDGES].reshape(-1, 2), axis=1)
    keys = pairs[:, 0].astype(np.int64) * n + pairs[:, 1]
    unique, inverse = np.unique(keys, return_inverse=True)
    ends = np.stack([unique // n, unique % n], axis=1)
    mid_ids = n + np.arange(unique.size)

    def lookup(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        return mid_ids[np.searchsorted(unique, lo.astype(np.int64) * n + hi)]

    return ends, inverse.reshape(-1, 6) + n, lookup


def refine_uniform(mesh: TetMesh) -> TetMesh:
    """Split every tet of ``mesh`` into 8 at its edge midpoints.

    Parameters
    ----------
    mesh
        A positively oriented tetrahedral mesh.

    Returns
    -------
    TetMesh
        The refined mesh: the old nodes first (same indices), then one node per edge;
        children ``8 i .. 8 i + 7`` of tet ``i``; regions and cell data carried over.
    """
    pts = np.asarray(mesh.points, float)
    tets = np.asarray(mesh.tets, np.int64)
    ends, mid, lookup = _edge_midpoints(pts, tets)
    points = np.vstack([pts, 0.5 * (pts[ends[:, 0]] + pts[ends[:, 1]])])
    v = tets
    m01, m02, m03, m12, m13, m23 = (mid[:, k] for k in range(6))
    corners = [
        (v[:, 0], m01, m02, m03),
        (m01, v[:, 1], m12, m13),
        (m02, m12, v[:, 2], m23),
        (m03, m13, m23, v[:, 3]),
    ]
    # The inner octahedron has three diagonals (m01-m23, m02-m13, m03-m12); the four tets
    # around a diagonal (a, b) use the ring of the other four midpoints in cyclic order.
    diagonals = [
        (m01, m23, (m02, m12, m13, m03)),
        (m02, m13, (m01, m12, m23, m03)),
        (m03, m12, (m01, m02, m23, m13)),
    ]
    lengths = np.stack(
        [np.linalg.norm(points[a] - points[b], axis=1) for a, b, _ in diagonals], axis=1
    )
    choice = np.argmin(lengths, axis=1)
    a = np.choose(choice, [d[0] for d in diagonals])
    b = np.choose(choice, [d[1] for d in diagonals])
    ring = [np.choose(choice, [d[2][k] for d in diagonals]) for k in range(4)]
    inner = [(a, b, ring[j], ring[(j + 1) % 4]) for j in range(4)]
    children = np.stack([np.stack(t, axis=1) for t in corners + inner], axis=1).reshape(-1, 4)
    flip = tet_volumes(points, children) < 0
    children[flip] = children[flip][:, [0, 2, 1, 3]]

    cell_sets = {
        k: (8 * np.asarray(ids, np.int64)[:, None] + np.arange(8)).ravel()
        for k, ids in mesh.cell_sets.items()
    }
    cell_data = {k: np.repeat(np.asarray(a), 8, axis=0) for k, a in mesh.cell_data.items()}
    facet_sets = {}
    for k, tri in mesh.facet_sets.items():
        tri = np.asarray(tri, np.int64).reshape(-1, 3)
        a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
        ab, bc, ca = lookup(a, b), lookup(b, c), lookup(c, a)
        sub = [(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)]  # same orientation
        facet_sets[k] = np.stack([np.stack(s, axis=1) for s in sub], axis=1).reshape(-1, 3)
    node_sets = {}
    for k, ids in mesh.node_sets.items():
        inside = np.zeros(pts.shape[0], bool)
        inside[np.asarray(ids, np.int64)] = True
        both = inside[ends[:, 0]] & inside[ends[:, 1]]
        node_sets[k] = np.concatenate(
            [np.asarray(ids, np.int64), pts.shape[0] + np.flatnonzero(both)]
        )
    return TetMesh(
        points=points,
        tets=children,
        node_sets=node_sets,
        cell_sets=cell_sets,
        facet_sets=facet_sets,
        cell_data=cell_data,
        notes=list(mesh.notes),
        source=f"{mesh.source} refined uniformly (each tet into 8)".strip(),
    )
