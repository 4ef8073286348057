"""Face-sharing topology of a tet mesh: overlapping tets, disconnected parts, hinge nodes.

Examples
--------
>>> import numpy as np
>>> two = np.array([[0, 1, 2, 3], [4, 5, 6, 7]])  # two tets sharing nothing
>>> topology_notes(two, "m")[0].startswith("m: 2 disconnected parts")
True
"""

from __future__ import annotations

import numpy as np

from ..errors import MeshError, format_ids
from .tetmesh import _FACES


def _row_keys(rows: np.ndarray) -> np.ndarray:
    """One sortable key per row of small non-negative ints (fast ``np.unique``)."""
    n = int(rows.max(initial=0)) + 1
    if n ** rows.shape[1] < 2**63:
        key = np.zeros(len(rows), dtype=np.int64)
        for c in range(rows.shape[1]):
            key = key * n + rows[:, c]
        return key
    return np.unique(rows, axis=0, return_inverse=True)[1].ravel()


def topology_notes(tets: np.ndarray, name: str) -> list[str]:
    """Face-sharing topology: raise for non-manifold facets, note parts and bad nodes.

    * A triangle shared by three or more tets, or by two tets on the same side of it,
      means overlapping tets: :class:`MeshError` naming the triangle and the tets.
    * Parts: tets connected through shared triangles. More than one is legal (several
      bodies), so it is a note naming the parts' sizes and a tet of each.
    * Non-manifold nodes: at a node, the tets around it fall into more than one group
      connected through triangles at that node (parts touching at a node or an edge, a
      "bow tie"). Legal, but such a hinge is rarely meant: a note naming the nodes.

    Parameters
    ----------
    tets
        Node indices ``(m, 4)``, positively oriented.
    name
        The mesh's name in messages.

    Returns
    -------
    list of str
        The notes (empty for one connected, manifold body).

    Raises
    ------
    MeshError
        For non-manifold facets and folds (overlapping tets).
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    m = len(tets)
    local = _FACES  # (4, 3) local node indices of the faces
    faces = tets[:, local].reshape(-1, 3)  # face f of tet t at row 4 t + f
    order = np.argsort(faces, axis=1, kind="stable")
    key = np.take_along_axis(faces, order, axis=1)
    _, inverse, counts = np.unique(_row_keys(key), return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    shared = counts[inverse]
    if (shared > 2).any():
        rows = np.flatnonzero(shared > 2)
        first = key[rows[0]]
        n_bad = int((counts > 2).sum())
        around = rows[inverse[rows] == inverse[rows[0]]] // 4
        raise MeshError(
            f"{name}: non-manifold facets: triangle {first.tolist()} is shared by "
            f"{int(shared[rows[0]])} tets ({format_ids(around)})"
            f"; {n_bad} non-manifold triangle{'s' if n_bad > 1 else ''} in all (overlapping tets)"
        )
    rows = np.flatnonzero(shared == 2)
    rows = rows[np.argsort(inverse[rows], kind="stable")]
    a, b = rows[0::2], rows[1::2]  # the two sides of each interior triangle
    # outward faces of two neighbours run in opposite directions: the permutations that
    # sort them have opposite parity; equal parity means both tets lie on the same side
    even = (order[:, 1] - order[:, 0]) % 3 == 1
    folded = np.flatnonzero(even[a] == even[b])
    if folded.size:
        f = folded[0]
        raise MeshError(
            f"{name}: folded mesh: tets {a[f] // 4} and {b[f] // 4} lie on the same side of "
            f"their shared triangle {key[a[f]].tolist()}; {folded.size} such "
            f"triangle{'s' if folded.size > 1 else ''} in all (overlapping tets)"
        )
    notes = []
    graph = coo_matrix((np.ones(a.size), (a // 4, b // 4)), shape=(m, m))
    n_parts, part = connected_components(graph, directed=False)
    if n_parts > 1:
        sizes = np.bincount(part)
        firsts = [int(np.flatnonzero(part == k)[0]) for k in range(min(n_parts, 8))]
        notes.append(
            f"{name}: {n_parts} disconnected parts (no shared triangle between them) of "
            f"{format_ids(sizes)} tets, containing tets {format_ids(firsts)}; each part "
            "needs its own boundary conditions"
        )
    # corners of a tet: item 4 t + j is node tets[t, j]; an interior triangle joins, at each
    # of its three nodes, the corner items of its two tets
    ia = (a // 4)[:, None] * 4 + local[a % 4][np.arange(a.size)[:, None], order[a]]
    ib = (b // 4)[:, None] * 4 + local[b % 4][np.arange(b.size)[:, None], order[b]]
    corners = coo_matrix((np.ones(ia.size), (ia.ravel(), ib.ravel())), shape=(4 * m, 4 * m))
    _, group = connected_components(corners, directed=False)
    node = tets.ravel()
    pairs = np.unique(node * np.int64(4 * m) + group)  # distinct (node, group) pairs
    n_groups = np.bincount(pairs // (4 * m))
    bad = np.flatnonzero(n_groups > 1)
    if bad.size:
        notes.append(
            f"{name}: {bad.size} non-manifold node{'s' if bad.size > 1 else ''} (parts touch "
            f"only at a node or an edge there): {format_ids(bad)}"
        )
    return notes
