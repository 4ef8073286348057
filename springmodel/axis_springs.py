"""Axis-volume and Poisson-coupling springs, the numpy oracle
(docs/theory.rst#the-axis-volume-ratio-is-j).

Both act on the axis vectors ``zeta_l = q_{2l} - q_{2l+1}`` only, as a force ``g_l`` on the
point ``q_{2l}`` and ``-g_l`` on ``q_{2l+1}`` (so net force and torque vanish), distributed to
the vertices with ``C^k`` like the axial and torsion springs.

axis volume (``volume = "axes"``)
    ``J = det[zeta_1 zeta_2 zeta_3] / det[zeta_1^0 zeta_2^0 zeta_3^0]`` is the exact volume
    ratio of the tet (``zeta_l = F zeta_l^0``); energy ``V0 U(J)`` with ``U`` one of
    :mod:`springfem.volumetric`'s energies (stiffness ``kappa = k_axis_volume``).
    ``dJ/d zeta_0 = zeta_1 x zeta_2 / det0`` (cyclic), so ``g_l = -V0 U'(J) dJ/d zeta_l``.
    Damping on the volume rate: ``g_l -= eta V0 (dJ/dt) dJ/d zeta_l`` with
    ``dJ/dt = sum_l dJ/d zeta_l . dzeta_l/dt`` (``eta = volume_damping``, Pa s).
Poisson coupling (``coupling = true``)
    Energy ``c_lm s_l s_m`` for the pairs (0,1), (0,2), (1,2), ``s_l = |zeta_l| / l_l^0 - 1``:
    ``g_l -= c_lm s_m zh_l / l_l^0`` and ``g_m -= c_lm s_l zh_m / l_m^0``.

Examples
--------
>>> import numpy as np
>>> z0 = np.eye(3)[None]
>>> float(volume_ratio(2.0 * z0, np.array([1.0]))[0])
8.0
"""

from __future__ import annotations

import numpy as np

from springfem.volumetric import volumetric_energy

from .rest_geometry import TORSION_PAIRS


def volume_ratio(zeta: np.ndarray, det0: np.ndarray) -> np.ndarray:
    """``J = det[zeta_1 zeta_2 zeta_3] / det0`` of current axes ``(m, 3, 3)``, ``(m,)``.

    Parameters
    ----------
    zeta
        Current axis vectors ``(m, 3, 3)``, ``zeta[k, l]`` for axis ``l``.
    det0
        Rest determinants ``det[zeta_1^0 zeta_2^0 zeta_3^0]`` ``(m,)``.

    Returns
    -------
    ndarray
        Volume ratio ``J`` ``(m,)``.
    """
    return np.einsum("kc,kc->k", zeta[:, 0], np.cross(zeta[:, 1], zeta[:, 2])) / det0


def volume_ratio_gradient(zeta: np.ndarray, det0: np.ndarray) -> np.ndarray:
    """``dJ / d zeta_l``, ``(m, 3, 3)`` (row ``l``).

    Parameters
    ----------
    zeta, det0
        Current axis vectors ``(m, 3, 3)`` and rest determinants ``(m,)``.

    Returns
    -------
    ndarray
        ``dJ / d zeta_l`` ``(m, 3, 3)``.
    """
    z0, z1, z2 = zeta[:, 0], zeta[:, 1], zeta[:, 2]
    g = np.stack([np.cross(z1, z2), np.cross(z2, z0), np.cross(z0, z1)], axis=1)
    return g / det0[:, None, None]


def axis_volume_axis_forces(
    zeta: np.ndarray, zeta_dot: np.ndarray | None, elements, kind: str, eta: float = 0.0
) -> np.ndarray:
    """Forces ``g_l`` ``(m, 3, 3)`` of the axis-volume spring on the ``+`` ends of the axes.

    Parameters
    ----------
    zeta, zeta_dot
        Current axis vectors and their rates ``(m, 3, 3)`` (``zeta_dot`` only for damping).
    elements
        :class:`~springmodel.elements.SpringElements` (``det0``, ``V0``, ``k_axis_volume``).
    kind
        Volumetric energy (``quadratic``, ``log``, ``simo-taylor``).
    eta
        Volume viscosity (Pa s); used when positive and ``zeta_dot`` is given.

    Returns
    -------
    ndarray
        ``g_l`` ``(m, 3, 3)`` (N); ``-g_l`` acts on the ``-`` ends.
    """
    J = volume_ratio(zeta, elements.det0)
    gJ = volume_ratio_gradient(zeta, elements.det0)
    _, dU, _ = volumetric_energy(J, elements.k_axis_volume, kind)
    s = -elements.V0 * dU
    if eta > 0 and zeta_dot is not None:
        s = s - eta * elements.V0 * np.einsum("klc,klc->k", gJ, zeta_dot)
    return s[:, None, None] * gJ


def coupling_axis_forces(zeta: np.ndarray, elements) -> np.ndarray:
    """Forces ``g_l`` ``(m, 3, 3)`` of the Poisson-coupling springs on the ``+`` ends.

    Parameters
    ----------
    zeta
        Current axis vectors ``(m, 3, 3)``.
    elements
        :class:`~springmodel.elements.SpringElements` (``l0``, ``k_coupling``).

    Returns
    -------
    ndarray
        ``g_l`` ``(m, 3, 3)`` (N).
    """
    L = np.linalg.norm(zeta, axis=-1)
    u = zeta / L[..., None]
    s = L / elements.l0 - 1.0
    g = np.zeros_like(zeta)
    for p, (l, m) in enumerate(TORSION_PAIRS):
        c = elements.k_coupling[:, p]
        g[:, l] -= (c * s[:, m] / elements.l0[:, l])[:, None] * u[:, l]
        g[:, m] -= (c * s[:, l] / elements.l0[:, m])[:, None] * u[:, m]
    return g


def axis_spring_energy(zeta: np.ndarray, elements, options) -> np.ndarray:
    """Energy per element ``(m,)`` of the axis-volume and coupling springs that are on.

    Parameters
    ----------
    zeta
        Current axis vectors ``(m, 3, 3)``.
    elements
        :class:`~springmodel.elements.SpringElements`.
    options
        :class:`~springmodel.options.SpringOptions` (``axis_volume``, ``coupling``).

    Returns
    -------
    ndarray
        Energy ``(m,)`` (J).
    """
    W = np.zeros(zeta.shape[0])
    if options.axis_volume:
        J = volume_ratio(zeta, elements.det0)
        W += elements.V0 * volumetric_energy(J, elements.k_axis_volume, options.volumetric)[0]
    if options.coupling:
        s = np.linalg.norm(zeta, axis=-1) / elements.l0 - 1.0
        for p, (l, m) in enumerate(TORSION_PAIRS):
            W += elements.k_coupling[:, p] * s[:, l] * s[:, m]
    return W
