"""The spring element's energy as a function of ``F``, and its small-strain matrix ``D_k``.

Under the affine deformation of a linear tet (gradient ``F``) every axis vector and every
radial vector maps exactly, ``zeta_l = F zeta_l^0`` and ``xi_j = F xi_j^0``, so the energy of
a spring element is a function of ``F`` alone (:func:`element_energy_from_F`)::

    W_k(F) = sum_l k_l/2 (|F zeta_l^0| - l_l^0)^2                 axial springs (2.35)
           + sum_lm k_lm/2 (c_lm(F) - c_lm^0)^2                     torsion (energy form)
           + k_s/2 (sum_j |F xi_j^0| - L^0)^2                       volume springs (2.76)

Linearising at ``F = I`` every term is ``k_a/2 (a_a : eps)^2`` with the tensors ``a_a`` of
:func:`springmodel.rest_geometry.spring_strain_tensors`, so the element is a P1 element with
the effective Voigt matrix ``D_k = (1/V) sum_a k_a v_a v_a^T`` (:func:`effective_matrix`),
``v_a`` the Voigt vector of ``a_a``.

Examples
--------
>>> import numpy as np
>>> from springmodel.rest_geometry import RestGeometry
>>> X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> g = RestGeometry(np.eye(3)[None], (X - X.mean(0))[None], np.array([1 / 6]))
>>> F = np.diag([1.1, 1.0, 1.0])[None]  # 10% stretch along axis 0
>>> element_energy_from_F(F, g, [[2.0, 0, 0]], 0.0, 0.0).round(12).tolist()  # k d^2 / 2
[0.01]
>>> D = effective_matrix(g, [[2.0, 0, 0]], 0.0, 0.0)  # only the xx entry: k l^2 / V
>>> float(D[0, 0, 0]), float(abs(D[0]).sum() - D[0, 0, 0])
(12.0, 0.0)
"""

from __future__ import annotations

from typing import Any

import numpy as np

from springfem.materials import voigt_vector

from .rest_geometry import rest_cosines, spring_strain_tensors


def stack_constants(k_axial, k_torsion, k_volume, m: int) -> np.ndarray:
    """The seven constants of each element in the order of the strain tensors.

    Parameters
    ----------
    k_axial, k_torsion, k_volume
        ``(m, 3)``, ``(m, 3)``, ``(m,)`` or broadcastable to them.
    m
        Number of elements.

    Returns
    -------
    ndarray
        ``(m, 7)``: axial 0, 1, 2, torsion (0,1), (0,2), (1,2), volume.
    """
    k = np.empty((m, 7))
    k[:, :3] = np.broadcast_to(np.asarray(k_axial, float), (m, 3))
    k[:, 3:6] = np.broadcast_to(np.asarray(k_torsion, float), (m, 3))
    k[:, 6] = np.broadcast_to(np.asarray(k_volume, float), (m,))
    return k


def effective_matrix(geometry: Any, k_axial, k_torsion, k_volume) -> np.ndarray:
    """Small-strain effective Voigt matrix ``D_k`` of the spring elements, ``(m, 6, 6)``.

    ``D_k = (1/V) sum_a k_a v_a v_a^T`` with ``v_a`` the Voigt vectors of
    :func:`~springmodel.rest_geometry.spring_strain_tensors`: the element energy is
    ``V/2 g^T D_k g`` to second order in the engineering strain ``g``. Valid for the energy
    forms (axial linear/polynomial, torsion ``energy``, volume ``gradient``); the torsion
    force laws ``angle``/``cosine``/``cubic`` linearise to non-symmetric stiffnesses that
    share its symmetric shear part only on the pure-shear modes.

    Parameters
    ----------
    geometry
        Anything with ``zeta0 (m,3,3)``, ``xi0 (m,4,3)``, ``V0 (m,)`` (e.g.
        :class:`~springmodel.rest_geometry.RestGeometry` or
        :class:`~springmodel.elements.SpringElements`).
    k_axial, k_torsion, k_volume
        ``(m, 3)``, ``(m, 3)``, ``(m,)`` or broadcastable; torsion in energy units.

    Returns
    -------
    ndarray
        ``D_k`` ``(m, 6, 6)`` (Pa), engineering-shear Voigt.
    """
    v = voigt_vector(spring_strain_tensors(geometry.zeta0, geometry.xi0))  # (m, 7, 6)
    k = stack_constants(k_axial, k_torsion, k_volume, v.shape[0])
    return (v * (k / geometry.V0[:, None])[..., None]).transpose(0, 2, 1) @ v


def element_energy_from_F(
    F: np.ndarray,
    geometry: Any,
    k_axial,
    k_torsion,
    k_volume,
    axial_coefficients: tuple[float, float] = (0.0, 0.0),
) -> np.ndarray:
    """Energy ``W_k(F)`` of each spring element from its deformation gradient alone.

    Energy forms only: axial polynomial ``k (d^2/2 + b2 d^3/(3 l0) + b3 d^4/(4 l0^2))``
    (``b2 = b3 = 0`` is linear), torsion ``k/2 (c - c0)^2``, volume ``k_s/2 dL^2``. Nothing
    here uses intersection points: ``zeta_l = F zeta_l^0`` and ``xi_j = F xi_j^0``.

    Parameters
    ----------
    F
        Deformation gradients ``(m, 3, 3)``.
    geometry
        Rest geometry (``zeta0`` ``(m, 3, 3)``, ``xi0`` ``(m, 4, 3)``, ``V0`` ``(m,)``).
    k_axial, k_torsion, k_volume
        ``(m, 3)`` (N/m), ``(m, 3)`` (J), ``(m,)`` (N/m) or broadcastable.
    axial_coefficients
        ``(b2, b3)`` of the polynomial axial law (eq. 2.36).

    Returns
    -------
    ndarray
        ``W_k`` ``(m,)`` (J).
    """
    m = geometry.V0.shape[0]
    k = stack_constants(k_axial, k_torsion, k_volume, m)
    b2, b3 = axial_coefficients
    zeta = geometry.zeta0 @ F.transpose(0, 2, 1)
    l0 = np.linalg.norm(geometry.zeta0, axis=-1)
    L = np.linalg.norm(zeta, axis=-1)
    d = L - l0
    W = np.sum(k[:, :3] * (d**2 / 2 + b2 * d**3 / (3 * l0) + b3 * d**4 / (4 * l0**2)), axis=1)
    c = rest_cosines(zeta)
    W += np.sum(0.5 * k[:, 3:6] * (c - rest_cosines(geometry.zeta0)) ** 2, axis=1)
    xi = geometry.xi0 @ F.transpose(0, 2, 1)
    dL = np.linalg.norm(xi, axis=-1).sum(1) - np.linalg.norm(geometry.xi0, axis=-1).sum(1)
    W += 0.5 * k[:, 6] * dL**2
    return W
