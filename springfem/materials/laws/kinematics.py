"""Tensor pieces shared by the laws: frames, second to first Piola, det, U(J), I1bar.

Conventions: ``F`` is ``(..., 3, 3)``; a frame ``R`` has the element's axes as rows (fiber,
sheet, normal), so ``F' = F R^T`` is the deformation gradient in the element frame
(``C' = F'^T F' = R C R^T``). A law written in its frame gives ``P'``, ``A'``; then
``P = P' R`` and ``A_iJkL = A'_iMkN R_MJ R_NL``. Tangents are ``A_iJkL = dP_iJ / dF_kL``.

Examples
--------
>>> import numpy as np
>>> F = np.diag([1.1, 1.0, 1.0])
>>> U, P, A = volumetric_terms(F, kappa=2.0, kind="quadratic")
>>> round(float(U), 12), round(float(P[0, 0]), 12)  # U = kappa/2 (J - 1)^2, P = kappa (J-1) J F^-T
(0.01, 0.2)
"""

from __future__ import annotations

import numpy as np

from ...volumetric import volumetric_energy

_I = np.eye(3)
#: ``II[i, j, k, l] = delta_ik delta_jl`` (d F / d F).
II = np.einsum("ik,jl->ijkl", _I, _I)


def to_frame(F: np.ndarray, frames: np.ndarray | None) -> np.ndarray:
    """``F' = F R^T`` (``frames`` broadcast against ``F``; ``None``: the global frame).

    Parameters
    ----------
    F
        Deformation gradients ``(..., 3, 3)``.
    frames
        Element frames ``R`` ``(..., 3, 3)`` (rows: fiber, sheet, normal) or None.

    Returns
    -------
    ndarray
        ``F`` in the element frame, ``(..., 3, 3)``.
    """
    if frames is None:
        return F
    return np.einsum("...iJ,...KJ->...iK", F, frames)


def stress_from_frame(P: np.ndarray, frames: np.ndarray | None) -> np.ndarray:
    """``P = P' R``.

    Parameters
    ----------
    P
        First Piola stress in the element frame ``(..., 3, 3)``.
    frames
        Element frames ``R`` ``(..., 3, 3)`` or None.

    Returns
    -------
    ndarray
        ``P`` in the global frame, ``(..., 3, 3)``.
    """
    if frames is None:
        return P
    return np.einsum("...iM,...MJ->...iJ", P, frames)


def tangent_from_frame(A: np.ndarray, frames: np.ndarray | None) -> np.ndarray:
    """``A_iJkL = A'_iMkN R_MJ R_NL``.

    Parameters
    ----------
    A
        Tangent ``dP/dF`` in the element frame ``(..., 3, 3, 3, 3)``.
    frames
        Element frames ``R`` ``(..., 3, 3)`` or None.

    Returns
    -------
    ndarray
        The tangent in the global frame, ``(..., 3, 3, 3, 3)``.
    """
    if frames is None:
        return A
    return np.einsum("...iMkN,...MJ,...NL->...iJkL", A, frames, frames, optimize=True)


def piola_from_pk2(F: np.ndarray, S: np.ndarray, CC: np.ndarray | None):
    """``P = F S`` and ``A_iJkL = delta_ik S_JL + F_iM CC_MJNL F_kN``.

    ``CC = dS/dE`` must have the minor symmetries (``CC_MJNL = CC_MJLN``).

    Parameters
    ----------
    F, S
        Deformation gradient and second Piola stress, ``(..., 3, 3)``.
    CC
        ``dS/dE`` ``(..., 3, 3, 3, 3)``, or None for the stress only.

    Returns
    -------
    P, A
        First Piola stress ``(..., 3, 3)`` and tangent ``(..., 3, 3, 3, 3)`` (None without
        ``CC``).
    """
    P = np.einsum("...iM,...MJ->...iJ", F, S)
    if CC is None:
        return P, None
    A = np.einsum("ik,...JL->...iJkL", _I, S) + np.einsum(
        "...iM,...MJNL,...kN->...iJkL", F, CC, F, optimize=True
    )
    return P, A


def det(F: np.ndarray) -> np.ndarray:
    """Determinant of ``(..., 3, 3)`` arrays (explicit formula, fast for many small ones).

    Parameters
    ----------
    F
        ``(..., 3, 3)`` matrices.

    Returns
    -------
    ndarray
        ``(...)``.
    """
    return (
        F[..., 0, 0] * (F[..., 1, 1] * F[..., 2, 2] - F[..., 1, 2] * F[..., 2, 1])
        - F[..., 0, 1] * (F[..., 1, 0] * F[..., 2, 2] - F[..., 1, 2] * F[..., 2, 0])
        + F[..., 0, 2] * (F[..., 1, 0] * F[..., 2, 1] - F[..., 1, 1] * F[..., 2, 0])
    )


def volumetric_terms(F: np.ndarray, kappa: float, kind: str, tangent: bool = True):
    """``U(J)`` (:func:`springfem.volumetric.volumetric_energy`), its first Piola stress and
    tangent.

    ``P = J U' F^-T``, ``A = J (U' + J U'') F^-T (x) F^-T - J U' F^-T_iL F^-T_kJ``.

    Parameters
    ----------
    F
        Deformation gradients ``(..., 3, 3)``.
    kappa
        Bulk modulus (Pa).
    kind
        ``log``, ``quadratic`` or ``simo-taylor``.
    tangent
        False: ``A`` is None.

    Returns
    -------
    U, P, A
        Energy density ``(...)``, stress ``(..., 3, 3)``, tangent ``(..., 3, 3, 3, 3)``; NaN
        where ``J <= 0``.
    """
    J = det(F)
    bad = ~(J > 0)
    with np.errstate(invalid="ignore", divide="ignore"):
        FiT = np.swapaxes(np.linalg.inv(np.where(bad[..., None, None], _I, F)), -1, -2)
        J = np.where(bad, np.nan, J)
        U, dU, ddU = volumetric_energy(J, kappa, kind)
    P = (J * dU)[..., None, None] * FiT
    if not tangent:
        return U, P, None
    A = (J * (dU + J * ddU))[..., None, None, None, None] * np.einsum(
        "...ij,...kl->...ijkl", FiT, FiT
    ) - (J * dU)[..., None, None, None, None] * np.einsum("...il,...kj->...ijkl", FiT, FiT)
    return U, P, A


def isochoric_i1(F: np.ndarray):
    """``I1bar = J^(-2/3) tr C``, ``d I1bar / dF`` and ``d^2 I1bar / dF^2``.

    ``dI1bar/dF = 2 J^(-2/3) (F - I1/3 F^-T)``; NaN where ``J <= 0``.

    Parameters
    ----------
    F
        Deformation gradients ``(..., 3, 3)``.

    Returns
    -------
    I1bar, D1, D2
        ``(...)``, ``(..., 3, 3)`` and ``(..., 3, 3, 3, 3)``.
    """
    J = det(F)
    bad = ~(J > 0)
    with np.errstate(invalid="ignore", divide="ignore"):
        FiT = np.swapaxes(np.linalg.inv(np.where(bad[..., None, None], _I, F)), -1, -2)
        J = np.where(bad, np.nan, J)
        c = J ** (-2.0 / 3.0)
    I1 = np.einsum("...ij,...ij->...", F, F)
    c2 = c[..., None, None]
    D1 = 2.0 * c2 * (F - (I1 / 3.0)[..., None, None] * FiT)
    I1_4 = I1[..., None, None, None, None]
    F_FiT = np.einsum("...ij,...kl->...ijkl", F, FiT)
    FiT_F = np.einsum("...ij,...kl->...ijkl", FiT, F)
    FiT_FiT = np.einsum("...ij,...kl->...ijkl", FiT, FiT)
    FiT_x = np.einsum("...il,...kj->...ijkl", FiT, FiT)
    D2 = (2.0 * c)[..., None, None, None, None] * (
        II - 2.0 / 3.0 * (F_FiT + FiT_F) + 2.0 / 9.0 * I1_4 * FiT_FiT + I1_4 / 3.0 * FiT_x
    )
    return c * I1, D1, D2


def green_lagrange(F: np.ndarray) -> np.ndarray:
    """``E = (F^T F - I) / 2``.

    Parameters
    ----------
    F
        Deformation gradients ``(..., 3, 3)``.

    Returns
    -------
    ndarray
        Green–Lagrange strain ``(..., 3, 3)``.
    """
    return 0.5 * (np.einsum("...kI,...kJ->...IJ", F, F) - _I)
