"""The six intersection points of each spring element and the map back to the vertices.

An element's intersection points are affine in its four vertices, ``q_j = sum_i C_ij x_i``
(eq. 2.25), and a force on them goes to the vertices with the same coefficients,
``f_i = sum_j C_ij f_j`` (eqs. 2.28–2.29). Axis ``l`` joins ``q_{2l+1}`` to ``q_{2l}``:
``zeta_l = q_{2l} - q_{2l+1}`` (eq. 2.31).

Examples
--------
>>> import numpy as np
>>> q = np.array([[[1.0, 0, 0], [-1, 0, 0], [0, 2, 0], [0, -2, 0], [0, 0, 3], [0, 0, -3]]])
>>> zeta, L, u = axis_vectors(q)
>>> L.tolist()  # axis lengths |q_{2l} - q_{2l+1}|
[[2.0, 4.0, 6.0]]
>>> fv = np.ones((1, 4, 3))
>>> scatter(fv, np.array([[0, 1, 2, 0]]), 3)[:, 0].tolist()  # node 0 gets two corners
[2.0, 1.0, 1.0]
"""

from __future__ import annotations

import numpy as np

from ..elements import SpringElements


def intersection_points(x: np.ndarray, elements: SpringElements) -> np.ndarray:
    """Current intersection points ``q_j = sum_i C_ij x_i`` (eq. 2.25).

    Parameters
    ----------
    x
        Node positions ``(n, 3)`` (m), or any nodal field mapped the same way (velocities).
    elements
        Rest data; ``elements.C`` is ``(n_tets, 4, 6)`` and ``elements.tets`` ``(n_tets, 4)``.

    Returns
    -------
    ndarray
        ``(n_tets, 6, 3)``; point ``2l`` is the hit along ``+axis l``, ``2l+1`` along ``-l``.
    """
    return elements.C.transpose(0, 2, 1) @ x[elements.tets]


def distribute(fq: np.ndarray, elements: SpringElements) -> np.ndarray:
    """Forces on the six points to forces on the element's vertices, ``f_i = sum_j C_ij f_j``.

    Parameters
    ----------
    fq
        Forces on the intersection points ``(n_tets, 6, 3)`` (N).
    elements
        Rest data with the coefficients ``C`` ``(n_tets, 4, 6)``.

    Returns
    -------
    ndarray
        Per-element vertex forces ``(n_tets, 4, 3)`` (N), same net force as ``fq``.
    """
    return elements.C @ fq


def scatter(fv: np.ndarray, tets: np.ndarray, n: int) -> np.ndarray:
    """Sum per-element vertex forces into nodal forces.

    Parameters
    ----------
    fv
        Per-element vertex forces ``(n_tets, 4, 3)``.
    tets
        Node indices ``(n_tets, 4)``.
    n
        Number of nodes.

    Returns
    -------
    ndarray
        Nodal forces ``(n, 3)``; nodes in no element get zero.
    """
    idx = tets.ravel()
    flat = fv.reshape(-1, 3)
    return np.stack([np.bincount(idx, weights=flat[:, c], minlength=n) for c in range(3)], axis=1)


def axis_vectors(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Axis vectors, their lengths and unit vectors from the six points (eq. 2.31).

    Parameters
    ----------
    q
        Intersection points ``(n_tets, 6, 3)``.

    Returns
    -------
    zeta, L, zeta_hat
        ``zeta_l = q_{2l} - q_{2l+1}`` ``(n_tets, 3, 3)`` (row ``l``), ``|zeta_l|``
        ``(n_tets, 3)`` and ``zeta_l / |zeta_l|`` ``(n_tets, 3, 3)``.
    """
    zeta = q[:, 0::2] - q[:, 1::2]
    L = np.linalg.norm(zeta, axis=-1)
    return zeta, L, zeta / L[..., None]


def add_pair_forces(fq: np.ndarray, s_l: np.ndarray, l: int, dir_l: np.ndarray) -> None:
    """Add ``s_l dir_l`` on ``q_{2l}`` and its opposite on ``q_{2l+1}``, in place.

    Parameters
    ----------
    fq
        Point forces ``(n_tets, 6, 3)``, updated.
    s_l
        Signed magnitudes ``(n_tets,)``.
    l
        Axis index 0, 1 or 2.
    dir_l
        Directions ``(n_tets, 3)``.

    Returns
    -------
    None
    """
    f = s_l[:, None] * dir_l
    fq[:, 2 * l] += f
    fq[:, 2 * l + 1] -= f
