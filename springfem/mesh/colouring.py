"""Element colouring: the race-free parallel scatter of both fused kernels.

Examples
--------
>>> import numpy as np
>>> element_colouring(np.array([[0, 1, 2, 3], [1, 2, 3, 4]]), 5).tolist()
[0, 1]
"""

from __future__ import annotations

import numpy as np


def _greedy_element_colouring(tets, node_ptr, node_elems):  # pragma: no cover - compiled
    """Smallest colour not used by an already coloured element sharing a node."""
    m = tets.shape[0]
    colour = np.full(m, -1, dtype=np.int64)
    mark = np.full(m + 1, -1, dtype=np.int64)  # mark[c] == k: colour c is taken near k
    for k in range(m):
        for a in range(4):
            node = tets[k, a]
            for p in range(node_ptr[node], node_ptr[node + 1]):
                c = colour[node_elems[p]]
                if c >= 0:
                    mark[c] = k
        c = 0
        while mark[c] == k:
            c += 1
        colour[k] = c
    return colour


_compiled_colouring = None


def element_colouring(tets: np.ndarray, n_points: int) -> np.ndarray:
    """Greedy element colouring: elements of one colour share no node.

    The race-free parallel scatter of both fused kernels (spring model and explicit FEM)
    runs the elements of one colour concurrently. Compiled with numba on first use.

    Parameters
    ----------
    tets
        Node indices ``(m, 4)``.
    n_points
        Number of nodes.

    Returns
    -------
    numpy.ndarray
        ``(m,)`` int64 colours ``0, 1, …``; each element takes the smallest colour not
        used by an earlier element sharing a node.

    Examples
    --------
    >>> element_colouring(np.array([[0, 1, 2, 3], [1, 2, 3, 4], [5, 6, 7, 8]]), 9).tolist()
    [0, 1, 0]
    """
    global _compiled_colouring
    if _compiled_colouring is None:
        from numba import njit

        _compiled_colouring = njit(cache=True)(_greedy_element_colouring)
    tets = np.ascontiguousarray(tets, dtype=np.int64)
    if tets.size == 0:
        return np.zeros(0, dtype=np.int64)
    flat = tets.ravel()
    node_elems = (np.argsort(flat, kind="stable") // 4).astype(np.int64)
    node_ptr = np.zeros(n_points + 1, dtype=np.int64)
    np.cumsum(np.bincount(flat, minlength=n_points), out=node_ptr[1:])
    return _compiled_colouring(tets, node_ptr, node_elems)
