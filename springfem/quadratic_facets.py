"""Curved (6-node, quadratic) triangles: the divergence-theorem volume integral over them.

A P2 field maps each boundary facet to the quadratic triangle
``x(xi, eta) = sum_k N_k(xi, eta) x_k`` through its three vertices and three edge nodes.
``1/3 int (x - c) . n dA`` over such a facet, with ``n dA = x_xi x x_eta dxi deta``, has an
integrand of degree 2 + 1 + 1 = 4 in ``(xi, eta)``; :func:`triangle_rule` is exact to degree 5,
so :func:`quadratic_facet_integral` is exact (to round-off) for the field's own surface.

Examples
--------
>>> x = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]])
>>> nodes = straight_facet_nodes(x, np.array([[0, 1, 2]]))
>>> round(quadratic_facet_integral(nodes, np.zeros(3)), 12)  # the corner tet's volume
0.166666666667
"""

from __future__ import annotations

import numpy as np

#: The facet's edges in the 6-node order: nodes 3, 4, 5 sit on edges (0,1), (1,2), (2,0).
FACET_EDGES = ((0, 1), (1, 2), (2, 0))


def triangle_rule() -> tuple[np.ndarray, np.ndarray]:
    """scikit-fem's degree-5 rule on the reference triangle ``{xi, eta >= 0, xi + eta <= 1}``.

    Returns
    -------
    points, weights
        ``(7, 2)`` reference coordinates and ``(7,)`` weights summing to the area 1/2;
        exact for polynomials of degree 5.

    Examples
    --------
    >>> p, w = triangle_rule()
    >>> round(float(w.sum()), 15), round(float(w @ (p[:, 0] ** 2 * p[:, 1] ** 3)), 12)
    (0.5, 0.002380952381)
    """
    from skfem.quadrature import get_quadrature
    from skfem.refdom import RefTri

    X, W = get_quadrature(RefTri, 5)
    return X.T, W


def _p2_shapes(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """scikit-fem's 6-node triangle (``ElementTriP2``: vertices, then the edge nodes of
    :data:`FACET_EDGES`) shape functions ``(q, 6)`` and their derivatives ``(q, 6, 2)``."""
    from skfem import ElementTriP2

    e = ElementTriP2()
    basis = [e.lbasis(p.T, i) for i in range(6)]
    return np.stack([b[0] for b in basis], axis=1), np.stack([b[1].T for b in basis], axis=1)


def straight_facet_nodes(x: np.ndarray, tris: np.ndarray) -> np.ndarray:
    """The 6 nodes of straight-sided facets: the vertices and the edge midpoints.

    Parameters
    ----------
    x
        ``(n, 3)`` vertex positions.
    tris
        ``(k, 3)`` vertex indices.

    Returns
    -------
    numpy.ndarray
        ``(k, 6, 3)`` in the order of :data:`FACET_EDGES`.
    """
    v = np.asarray(x, dtype=float)[tris]
    mid = [0.5 * (v[:, i] + v[:, j]) for i, j in FACET_EDGES]
    return np.concatenate([v, np.stack(mid, axis=1)], axis=1)


def quadratic_facet_integral(nodes: np.ndarray, c: np.ndarray) -> float:
    """``1/3 sum int (x - c) . n dA`` over 6-node triangles (the enclosed signed volume).

    Parameters
    ----------
    nodes
        ``(k, 6, 3)`` node positions per facet (vertices, then :data:`FACET_EDGES` nodes);
        the normal is ``x_xi x x_eta``.
    c
        The cone apex of the closure (see the module docstring).

    Returns
    -------
    float
    """
    p, w = triangle_rule()
    N, dN = _p2_shapes(p)
    y = np.asarray(nodes, dtype=float) - np.asarray(c, dtype=float)
    pos = np.einsum("qa,kai->kqi", N, y)
    t = np.einsum("qad,kai->kqdi", dN, y)  # (k, q, 2, 3): x_xi and x_eta
    integrand = np.einsum("kqi,kqi->kq", pos, np.cross(t[:, :, 0], t[:, :, 1]))
    return float((integrand @ w).sum() / 3.0)
