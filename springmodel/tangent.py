"""Small-strain tangent of a spring element, and its mismatch against the material.

At rest every spring measure changes linearly with the displacement gradient ``H = F - I``,
so the small-strain element stiffness is ``K_e[ia, jb] = V0 dN_i/dX_c A[a, c, b, d] dN_j/dX_d``
with a fourth-order tangent ``A = sum_b k_b B_b`` linear in the spring constants ``k_b``. The
basis tensors ``B_b`` of the parts that are switched on (:func:`tangent_basis`):

* axial ``l`` (``k`` in N/m): ``a_l (x) a_l / V``, ``a_l = zh_l (x) zeta_l^0`` (sym),
* torsion ``energy`` (``k`` in J): ``S_lm (x) S_lm / V``, ``S_lm = dc_lm / d eps``;
  ``cosine``/``angle``/``cubic`` (the same small-angle force law, not a gradient):
  ``T_lm (x) S_lm / V`` with ``T_lm = 2 (l_l zh_m (x) zh_l + l_m zh_l (x) zh_m) / (l_l + l_m)``,
  whose symmetric part is ``S_lm`` (for ``c0 = 0``) and whose skew part is the net torque,
* barycentric volume (``k`` in N/m): ``R (x) R / V``, ``R = sum_j xi_j xi_j^T / |xi_j|``
  (the ``spec`` force form is linearised as its gradient form),
* axis volume (``kappa`` in Pa): ``I (x) I`` (``J - 1 = tr eps`` to first order),
* Poisson coupling (``c`` in J): ``(w_l (x) w_m + w_m (x) w_l) / V``, ``w_l = a_l / l_l``.

**The mismatch norm.** :func:`tangent_mismatch` is ``||A - C|| / ||C||`` in the Frobenius
norm of the fourth-order tensor (all 81 components). For minor-symmetric tangents (every
energy form) it equals the Frobenius norm of the Mandel 6x6 matrices (the "Mandel Frobenius
norm"); the cosine law's skew part counts in the same norm.

Examples
--------
>>> import numpy as np
>>> from springfem.materials import material_matrix
>>> from springmodel.rest_geometry import RestGeometry
>>> X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> zeta0 = np.eye(3)[None] * 0.5
>>> g = RestGeometry(zeta0, (X - X.mean(0))[None], np.array([1 / 6]))
>>> B = tangent_basis(g, torsion="energy", volume="axes", coupling=False)
>>> B.shape
(1, 7, 3, 3, 3, 3)
"""

from __future__ import annotations

from typing import Any

import numpy as np

from springfem.materials import voigt_to_tensor

from .options import ENERGY_TORSION, GREEN_TORSION
from .rest_geometry import TORSION_PAIRS, radial_tensor, spring_strain_tensors

#: Elements per block when tangents are formed (bounds memory to ~100 MB).
CHUNK = 8192
MISMATCH_NORM = "relative Frobenius norm of the 4th-order tangent (= Mandel Frobenius)"


def _sym(a: np.ndarray) -> np.ndarray:
    return 0.5 * (a + np.swapaxes(a, -1, -2))


def _dyad(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., :, :, None, None] * b[..., None, None, :, :]


def basis_names(torsion: str, volume: Any, coupling: bool) -> list[str]:
    """Names of the constants :func:`tangent_basis` returns, in order.

    Parameters
    ----------
    torsion, volume, coupling
        The options' torsion law, ``volume`` (``True``, ``False`` or ``"axes"``) and coupling.

    Returns
    -------
    list of str
        E.g. ``["axial0", "axial1", "axial2", "torsion01", ..., "volume"]``.
    """
    names = ["axial0", "axial1", "axial2"]
    if torsion != "off":
        names += ["torsion01", "torsion02", "torsion12"]
    if volume is True:
        names.append("volume")
    elif volume == "axes":
        names.append("axis_volume")
    if coupling:
        names += ["coupling01", "coupling02", "coupling12"]
    return names


def tangent_basis(geometry: Any, torsion: str, volume: Any, coupling: bool) -> np.ndarray:
    """Basis tensors ``B_b`` of the switched-on spring constants, ``(m, nb, 3, 3, 3, 3)``.

    Parameters
    ----------
    geometry
        Rest geometry with ``zeta0 (m,3,3)``, ``xi0 (m,4,3)``, ``V0 (m,)``.
    torsion, volume, coupling
        The options' torsion law, ``volume`` (``True``, ``False`` or ``"axes"``) and coupling.

    Returns
    -------
    numpy.ndarray
        In the order of :func:`basis_names`; ``A = sum_b k_b B_b``.
    """
    zeta0, V = geometry.zeta0, geometry.V0
    m = zeta0.shape[0]
    a = _sym(spring_strain_tensors(zeta0, geometry.xi0[:, :, :]))  # (m, 7, 3, 3)
    iv = (1.0 / V)[:, None, None, None, None]
    out = [_dyad(a[:, l], a[:, l]) * iv for l in range(3)]
    if torsion != "off":
        l0 = np.linalg.norm(zeta0, axis=-1)
        u = zeta0 / l0[..., None]
        for p, (l, n) in enumerate(TORSION_PAIRS):
            S = a[:, 3 + p]
            if torsion in (*ENERGY_TORSION, GREEN_TORSION):  # the same small-strain tangent
                out.append(_dyad(S, S) * iv)
                continue
            ul, un = u[:, l], u[:, n]
            T = l0[:, l, None, None] * (un[:, :, None] * ul[:, None, :])
            T = T + l0[:, n, None, None] * (ul[:, :, None] * un[:, None, :])
            T = 2.0 * T / (l0[:, l] + l0[:, n])[:, None, None]
            out.append(_dyad(T, S) * iv)
    if volume is True:
        R = radial_tensor(geometry.xi0)
        out.append(_dyad(R, R) * iv)
    elif volume == "axes":
        out.append(np.broadcast_to(_dyad(np.eye(3), np.eye(3)), (m, 3, 3, 3, 3)))
    if coupling:
        w = a[:, :3] / np.linalg.norm(zeta0, axis=-1)[..., None, None]
        for l, n in TORSION_PAIRS:
            out.append((_dyad(w[:, l], w[:, n]) + _dyad(w[:, n], w[:, l])) * iv)
    return np.stack(out, axis=1)


def spring_tangent(geometry: Any, constants: np.ndarray, options: Any) -> np.ndarray:
    """Small-strain tangent ``A = sum_b k_b B_b`` of each element, ``(m, 3, 3, 3, 3)``.

    Parameters
    ----------
    geometry
        Rest geometry (see :func:`tangent_basis`).
    constants
        ``(m, nb)`` constants in the order of :func:`basis_names`.
    options
        :class:`~springmodel.options.SpringOptions` (``torsion``, ``volume``, ``coupling``).

    Returns
    -------
    numpy.ndarray
        ``A`` ``(m, 3, 3, 3, 3)`` (Pa).
    """
    B = tangent_basis(geometry, options.torsion, options.volume, options.coupling)
    return np.einsum("kb,kbijmn->kijmn", constants, B)


def tangent_mismatch(A: np.ndarray, C_voigt: np.ndarray) -> np.ndarray:
    """``||A - C|| / ||C||`` over the 81 tensor components (module docstring), ``(m,)``.

    Parameters
    ----------
    A
        ``(m, 3, 3, 3, 3)`` spring tangents.
    C_voigt
        ``(6, 6)`` or ``(m, 6, 6)`` material matrices (engineering-shear Voigt).

    Returns
    -------
    numpy.ndarray
        Relative mismatch ``(m,)``.
    """
    Ct = np.broadcast_to(voigt_to_tensor(np.asarray(C_voigt, float)), A.shape)
    m = A.shape[0]
    diff = (A - Ct).reshape(m, -1)
    return np.linalg.norm(diff, axis=1) / np.linalg.norm(Ct.reshape(m, -1), axis=1)


def element_mismatch(geometry: Any, constants: np.ndarray, C_voigt: np.ndarray, options: Any):
    """Mismatch of every element (chunked so that large meshes fit in memory), ``(m,)``.

    Parameters
    ----------
    geometry, constants, options
        As for :func:`spring_tangent`.
    C_voigt
        ``(6, 6)`` or ``(m, 6, 6)`` material matrices.

    Returns
    -------
    ndarray
        :func:`tangent_mismatch` of each element, ``(m,)``.
    """
    m = geometry.V0.shape[0]
    C = np.asarray(C_voigt, float)
    out = np.empty(m)
    for lo in range(0, m, CHUNK):
        hi = min(lo + CHUNK, m)
        g = type(geometry)(*(np.asarray(f)[lo:hi] for f in geometry))
        Ck = C[lo:hi] if C.ndim == 3 else C
        out[lo:hi] = tangent_mismatch(spring_tangent(g, constants[lo:hi], options), Ck)
    return out
