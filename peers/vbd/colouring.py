"""Vertex colouring and vertex–element incidence, stored in colour order, for Vertex Block
Descent's Gauss–Seidel sweep: vertices of one colour share no element, so their block
updates are independent (they could run in parallel and give the serial sweep's answer).

Examples
--------
>>> import numpy as np
>>> c = vertex_colouring(np.array([[0, 1, 2, 3], [1, 2, 3, 4]]), 5)
>>> c.order.tolist(), c.colour_ptr.tolist()  # 0 and 4 share no element
([0, 4, 1, 2, 3], [0, 2, 3, 4, 5])
>>> c.inc_elem[c.inc_ptr[0]:c.inc_ptr[1]].tolist()  # vertex 0's elements
[0]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit


@njit(cache=True)
def _greedy(tets, node_ptr, node_elems, n):  # pragma: no cover - compiled
    """Smallest colour not used by an already coloured vertex sharing an element."""
    colour = np.full(n, -1, dtype=np.int64)
    mark = np.full(n + 1, -1, dtype=np.int64)
    for i in range(n):
        for p in range(node_ptr[i], node_ptr[i + 1]):
            k = node_elems[p]
            for a in range(4):
                c = colour[tets[k, a]]
                if c >= 0:
                    mark[c] = i
        c = 0
        while mark[c] == i:
            c += 1
        colour[i] = c
    return colour


@dataclass(frozen=True)
class VertexColouring:
    """Vertices in colour order with their incident elements.

    Attributes
    ----------
    order
        Vertex indices ``(n,)`` sorted by colour (stable within a colour).
    colour_ptr
        ``order[colour_ptr[c]:colour_ptr[c + 1]]`` are the vertices of colour ``c``.
    inc_ptr, inc_elem, inc_local
        Incidence in the same order: the ``q``-th vertex of ``order`` is corner
        ``inc_local[p]`` of element ``inc_elem[p]`` for ``p`` in ``inc_ptr[q]:inc_ptr[q + 1]``.
    """

    order: np.ndarray
    colour_ptr: np.ndarray
    inc_ptr: np.ndarray
    inc_elem: np.ndarray
    inc_local: np.ndarray

    @property
    def n_colours(self) -> int:
        """Number of colours."""
        return int(self.colour_ptr.size - 1)


def vertex_colouring(tets: np.ndarray, n_points: int) -> VertexColouring:
    """Greedy colouring of the vertex adjacency (two vertices are adjacent when they share an
    element) with the incidence arrays in colour order.

    Parameters
    ----------
    tets
        ``(m, 4)`` node indices.
    n_points
        Number of vertices.

    Returns
    -------
    VertexColouring
    """
    tets = np.ascontiguousarray(tets, dtype=np.int64)
    flat = tets.ravel()
    by_node = np.argsort(flat, kind="stable")
    node_ptr = np.zeros(n_points + 1, dtype=np.int64)
    np.cumsum(np.bincount(flat, minlength=n_points), out=node_ptr[1:])
    elems = (by_node // 4).astype(np.int64)
    local = (by_node % 4).astype(np.int64)
    colour = _greedy(tets, node_ptr, elems, n_points)
    order = np.argsort(colour, kind="stable").astype(np.int64)
    colour_ptr = np.zeros(int(colour.max(initial=-1)) + 2, dtype=np.int64)
    np.cumsum(np.bincount(colour, minlength=colour_ptr.size - 1), out=colour_ptr[1:])
    counts = np.diff(node_ptr)[order]
    inc_ptr = np.zeros(n_points + 1, dtype=np.int64)
    np.cumsum(counts, out=inc_ptr[1:])
    starts = np.repeat(node_ptr[:-1][order] - inc_ptr[:-1], counts)
    take = starts + np.arange(inc_ptr[-1], dtype=np.int64)
    return VertexColouring(order, colour_ptr, inc_ptr, elems[take], local[take])


__all__ = ["VertexColouring", "vertex_colouring"]
