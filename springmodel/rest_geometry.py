"""The rest geometry of a spring element and its small-strain measures
(docs/theory.rst#the-effective-small-strain-matrix-d-k).

Calibration needs, per element, the rest axis vectors ``zeta_l^0``, the radial vectors
``xi_j^0`` (barycenter to vertex) and the volume. At small strain ``eps`` every spring's
measure changes by ``a_a : eps`` with a symmetric tensor ``a_a`` of that geometry
(:func:`spring_strain_tensors`):

* axial ``a_l = zeta_l zeta_l^T / l_l`` (``d|zeta_l| = zeta_hat . eps . zeta``),
* torsion ``a_lm = 2 sym(zh_l zh_m^T) - c0 (zh_l zh_l^T + zh_m zh_m^T)`` (``dc_lm = a_lm : eps``),
* volume ``R = sum_j xi_j xi_j^T / |xi_j|`` (``dL = R : eps``, :func:`radial_tensor`).

Examples
--------
>>> import numpy as np
>>> rest_cosines(np.eye(3)[None]).tolist()  # orthonormal axes: every c_lm^0 = 0
[[0.0, 0.0, 0.0]]
>>> X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> G = np.zeros((1, 4, 3)); G[0, 1:] = np.eye(3)  # zeta_l = x_{l+1}
>>> g = rest_geometry(X, np.array([[0, 1, 2, 3]]), G)
>>> g.zeta0[0].tolist(), round(float(g.V0[0]), 12)
([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], 0.166666666667)
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

# Voigt order xx, yy, zz, yz, xz, xy (engineering shear strains).
#: Torsion spring pairs ``(l, m)`` of axes.
TORSION_PAIRS = ((0, 1), (0, 2), (1, 2))
#: The Voigt index of the shear each torsion pair carries.
TORSION_VOIGT = (5, 4, 3)


class RestGeometry(NamedTuple):
    """What calibration needs from an element's rest state.

    Attributes
    ----------
    zeta0
        Rest axis vectors, ``(m, 3, 3)``, ``zeta0[k, l]`` for axis ``l``.
    xi0
        Rest radial vectors barycenter -> vertex, ``(m, 4, 3)``.
    V0
        Rest volumes, ``(m,)``.
    """

    zeta0: np.ndarray
    xi0: np.ndarray
    V0: np.ndarray


def rest_geometry(points: np.ndarray, tets: np.ndarray, G: np.ndarray) -> RestGeometry:
    """Rest axis vectors, radial vectors and volumes of the elements.

    Parameters
    ----------
    points
        Rest node positions ``(n, 3)`` (m).
    tets
        Node indices ``(m, 4)``.
    G
        Axis gradients ``(m, 4, 3)``: ``zeta_l = sum_i G[k, i, l] x_i``
        (:func:`springmodel.elements.axis_gradients_from`).

    Returns
    -------
    RestGeometry
        ``zeta0`` ``(m, 3, 3)``, ``xi0 = x_j - x_b`` ``(m, 4, 3)`` and the signed volumes
        ``V0`` ``(m,)`` (m^3).
    """
    X = np.asarray(points, float)[tets]
    zeta0 = G.transpose(0, 2, 1) @ X
    xi0 = X - X.mean(axis=1, keepdims=True)
    e = X[:, 1:] - X[:, :1]
    V0 = np.linalg.det(e) / 6.0
    return RestGeometry(zeta0, xi0, V0)


def rest_cosines(zeta0: np.ndarray) -> np.ndarray:
    """Cosines ``c_lm = zeta_hat_l . zeta_hat_m`` of the pairs (0,1), (0,2), (1,2) (eq. 2.32).

    Parameters
    ----------
    zeta0
        Axis vectors ``(m, 3, 3)`` (rest or current), row ``l`` for axis ``l``.

    Returns
    -------
    ndarray
        ``(m, 3)``, in the order of :data:`TORSION_PAIRS`.
    """
    u = zeta0 / np.linalg.norm(zeta0, axis=-1, keepdims=True)
    return np.stack([(u[:, a] * u[:, b]).sum(-1) for a, b in TORSION_PAIRS], axis=1)


def radial_tensor(xi0: np.ndarray) -> np.ndarray:
    """Radial tensor ``R = sum_j xi_j xi_j^T / |xi_j|``: ``dL = R : eps`` at small strain.

    Parameters
    ----------
    xi0
        Radial vectors barycenter -> vertex ``(m, 4, 3)`` (m).

    Returns
    -------
    ndarray
        ``(m, 3, 3)`` symmetric (m); ``tr R = sum_j |xi_j|``.
    """
    r = np.linalg.norm(xi0, axis=-1)
    return (xi0 / r[..., None]).transpose(0, 2, 1) @ xi0


def spring_strain_tensors(zeta0: np.ndarray, xi0: np.ndarray) -> np.ndarray:
    """Tensors ``a_a`` with ``d(measure_a) = a_a : eps`` at rest.

    Order: axial 0, 1, 2 (measure ``|zeta_l|``), torsion (0,1), (0,2), (1,2) (measure
    ``c_lm``), volume (measure ``L = sum_j |xi_j|``).

    Parameters
    ----------
    zeta0
        Rest axis vectors ``(m, 3, 3)`` (m).
    xi0
        Rest radial vectors ``(m, 4, 3)`` (m).

    Returns
    -------
    ndarray
        ``(m, 7, 3, 3)``, symmetric in the last two axes; axial and volume tensors in m,
        torsion tensors dimensionless.
    """
    m = zeta0.shape[0]
    l0 = np.linalg.norm(zeta0, axis=-1)
    u = zeta0 / l0[..., None]
    c0 = rest_cosines(zeta0)
    a = np.empty((m, 7, 3, 3))
    a[:, :3] = u[..., :, None] * zeta0[..., None, :]
    for p, (l, n) in enumerate(TORSION_PAIRS):
        ul, un = u[:, l, :, None], u[:, n, :, None]
        outer = ul * un.transpose(0, 2, 1)
        a[:, 3 + p] = (outer + outer.transpose(0, 2, 1)) - c0[:, p, None, None] * (
            ul * ul.transpose(0, 2, 1) + un * un.transpose(0, 2, 1)
        )
    a[:, 6] = radial_tensor(xi0)
    return a
