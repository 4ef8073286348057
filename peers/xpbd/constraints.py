"""The stable neo-Hookean tetrahedral constraints of Macklin & Müller 2021, in numpy.

Per element, with the rest shape gradients ``g_a = grad N_a`` (``a = 1..3``) and volume
``V``, ``F = sum_a (x_a - x_0) (x) g_a`` and two constraints with their compliances::

    C_D = sqrt(tr F^T F),   alpha_D = 1 / (mu' V)       (deviatoric)
    C_H = det F - gamma,    alpha_H = 1 / (lam' V)      (hydrostatic), gamma = 1 + mu'/lam'

whose XPBD energy ``C_D^2 / (2 alpha_D) + C_H^2 / (2 alpha_H)`` is ``V`` times the stable
neo-Hookean density ``psi = mu'/2 (I_C - 3) + lam'/2 (J - gamma)^2`` (Smith, de Goes & Kim
2018 without their log term), up to a constant. ``gamma`` makes ``F = I`` a rest state.
Linearised at ``F = I`` the density is isotropic linear elasticity with shear modulus
``mu'`` and Lamé ``lam' - mu'`` (the ``(J - gamma)`` factor of ``d^2 J`` is ``-mu'/lam'``),
so the scene's ``(mu, lam)`` enter as ``mu' = mu``, ``lam' = lam + mu``
(:func:`stable_neo_hookean`): at small strain XPBD then solves the scene's linear elasticity,
as every neo-Hookean law of the reference does (docs/peers.rst#xpbd).

The gradient of a constraint with respect to node ``a`` is ``dC/dF g_a`` (``a = 1..3``)
and minus their sum for node 0; ``dC_D/dF = F / C_D``, ``dC_H/dF = cof F`` (columns
``f_2 x f_3, f_3 x f_1, f_1 x f_2`` of ``F``'s columns ``f_j``).

Examples
--------
>>> import numpy as np
>>> X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> G, V = rest_shape(X, np.array([[0, 1, 2, 3]]))
>>> F = deformation_gradients(X, np.array([[0, 1, 2, 3]]), G)
>>> round(float(deviatoric(F)[0][0] ** 2), 12), float(hydrostatic(F, 1.5)[0][0])  # I_C, J - gamma
(3.0, -0.5)
"""

from __future__ import annotations

import numpy as np

from springfem.errors import InputError


def stable_neo_hookean(mu: float, lam: float) -> tuple[float, float, float]:
    """The constraint moduli ``(mu', lam', gamma)`` whose linearisation is ``(mu, lam)``.

    Parameters
    ----------
    mu, lam
        The scene's shear modulus and Lamé's first parameter.

    Returns
    -------
    mu', lam', gamma
        ``mu' = mu``, ``lam' = lam + mu``, ``gamma = 1 + mu'/lam'``.

    Raises
    ------
    InputError
        If ``mu <= 0`` or ``lam + mu <= 0``.
    """
    if not mu > 0 or not lam + mu > 0:
        raise InputError(f"xpbd needs mu > 0 and lam + mu > 0 (got mu = {mu:g}, lam = {lam:g})")
    lam_c = lam + mu
    return float(mu), float(lam_c), 1.0 + mu / lam_c


def rest_shape(points: np.ndarray, tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rest shape gradients ``G (m, 3, 3)`` (row ``a - 1`` is ``grad N_a``) and volumes.

    Parameters
    ----------
    points, tets
        The mesh at rest.

    Returns
    -------
    G, V
        ``(m, 3, 3)`` and ``(m,)`` (signed: positive for a positively oriented tet).
    """
    x = np.asarray(points, dtype=float)[np.asarray(tets)]
    E = x[:, 1:] - x[:, :1]  # rows x_a - x_0, so F = E^T G = I at rest: G = E^-T
    V = np.linalg.det(E) / 6.0
    if np.any(V <= 0):
        k = int(np.flatnonzero(V <= 0)[0])
        raise InputError(f"element {k} has non-positive volume {V[k]:.3g} at rest")
    return np.ascontiguousarray(np.linalg.inv(E).transpose(0, 2, 1)), V


def deformation_gradients(x: np.ndarray, tets: np.ndarray, G: np.ndarray) -> np.ndarray:
    """``F (m, 3, 3)`` of positions ``x (n, 3)``.

    Parameters
    ----------
    x, tets
        Positions and elements.
    G
        :func:`rest_shape`'s gradients.

    Returns
    -------
    ndarray
    """
    X = np.asarray(x, dtype=float).reshape(-1, 3)[tets]
    return np.einsum("kac,kad->kcd", X[:, 1:] - X[:, :1], G)


def cofactor(F: np.ndarray) -> np.ndarray:
    """``cof F = det(F) F^-T`` (defined for singular ``F`` too), ``(..., 3, 3)``."""
    c = np.empty_like(F)
    for j in range(3):
        c[..., :, j] = np.cross(F[..., :, (j + 1) % 3], F[..., :, (j + 2) % 3])
    return c


def deviatoric(F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``C_D = sqrt(tr F^T F)`` and ``dC_D/dF = F / C_D``.

    Parameters
    ----------
    F
        ``(m, 3, 3)``.

    Returns
    -------
    C, dC
        ``(m,)`` and ``(m, 3, 3)``.
    """
    C = np.sqrt(np.einsum("kij,kij->k", F, F))
    return C, F / C[:, None, None]


def hydrostatic(F: np.ndarray, gamma: float) -> tuple[np.ndarray, np.ndarray]:
    """``C_H = det F - gamma`` and ``dC_H/dF = cof F``.

    Parameters
    ----------
    F
        ``(m, 3, 3)``.
    gamma
        The rest offset ``1 + mu'/lam'``.

    Returns
    -------
    C, dC
        ``(m,)`` and ``(m, 3, 3)``.
    """
    return np.linalg.det(F) - gamma, cofactor(F)


def node_gradients(dCdF: np.ndarray, G: np.ndarray) -> np.ndarray:
    """Gradients ``(m, 4, 3)`` of a constraint with respect to the element's four nodes.

    Parameters
    ----------
    dCdF
        ``(m, 3, 3)``.
    G
        :func:`rest_shape`'s gradients.

    Returns
    -------
    ndarray
        Row ``a``: ``dC/dx_a``; they sum to zero (a translation does not change ``F``).
    """
    g = np.einsum("kcd,kad->kac", dCdF, G)
    return np.concatenate([-g.sum(axis=1, keepdims=True), g], axis=1)


def energy_density(F: np.ndarray, mu: float, lam: float, gamma: float) -> np.ndarray:
    """``psi = mu'/2 (I_C - 3) + lam'/2 ((J - gamma)^2 - (1 - gamma)^2)``: zero at rest.

    Parameters
    ----------
    F
        ``(..., 3, 3)``.
    mu, lam, gamma
        The constraint moduli (:func:`stable_neo_hookean`).

    Returns
    -------
    ndarray
    """
    I_C = np.einsum("...ij,...ij->...", F, F)
    J = np.linalg.det(F)
    return 0.5 * mu * (I_C - 3.0) + 0.5 * lam * ((J - gamma) ** 2 - (1.0 - gamma) ** 2)


def first_piola(F: np.ndarray, mu: float, lam: float, gamma: float) -> np.ndarray:
    """``P = dpsi/dF = mu' F + lam' (J - gamma) cof F``."""
    J = np.linalg.det(F)
    return mu * F + (lam * (J - gamma))[..., None, None] * cofactor(F)


__all__ = [
    "cofactor",
    "deformation_gradients",
    "deviatoric",
    "energy_density",
    "first_piola",
    "hydrostatic",
    "node_gradients",
    "rest_shape",
    "stable_neo_hookean",
]
