"""Compressible neo-Hookean laws: energy, first Piola stress and its tangent.

Two energies (docs/fem.rst#neo-hookean-energies), both with ``F`` of shape ``(..., 3, 3)``:

- ``coupled``: ``psi = mu/2 (I1 - 3) - mu ln J + lam/2 ln^2 J`` (scikit-fem example 43),
- ``uncoupled``: ``psi = mu/2 (I1bar - 3) + U(J)`` with ``I1bar = J^(-2/3) I1`` and
  ``U = kappa/2 ln^2 J`` (``log``), ``kappa/2 (J - 1)^2`` (``quadratic``) or
  ``kappa/4 (J^2 - 1 - 2 ln J)`` (``simo-taylor``).

At ``F = I`` every variant's tangent is the isotropic linear elasticity tensor with the same
``mu`` and ``lam = kappa - 2 mu / 3``.

Examples
--------
>>> import numpy as np
>>> law = NeoHookean(mu=1.0, lam=2.0)
>>> P, A = law.stress_tangent(np.eye(3))
>>> float(abs(P).max()), float(A[0, 0, 0, 0]), float(A[0, 1, 0, 1]), float(A[0, 0, 1, 1])
(0.0, 4.0, 1.0, 2.0)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal, cast

import numpy as np

from ...errors import InputError
from ...volumetric import volumetric_energy as _volumetric
from .kinematics import det as _det

Formulation = Literal["coupled", "uncoupled"]
Volumetric = Literal["log", "quadratic", "simo-taylor"]
#: The energies (``[material] formulation``) and the uncoupled one's ``U(J)``.
FORMULATIONS = ("coupled", "uncoupled")
VOLUMETRIC = ("log", "quadratic", "simo-taylor")

_I = np.eye(3)


@dataclass(frozen=True)
class NeoHookean:
    """A compressible neo-Hookean law.

    Parameters
    ----------
    mu, lam
        Shear modulus and Lamé's first parameter; ``kappa = lam + 2 mu / 3``.
    formulation
        ``coupled`` or ``uncoupled``.
    volumetric
        ``U(J)`` of the uncoupled formulation.
    """

    mu: float
    lam: float
    formulation: Formulation = "coupled"
    volumetric: Volumetric = "log"

    @classmethod
    def from_material(
        cls, material: Any, formulation: str | None = None, volumetric: str | None = None
    ) -> NeoHookean:
        """The law of a scene's :class:`~springfem.scene.Material` (``mu``, ``lam``), with
        its ``formulation`` and ``volumetric`` unless overridden."""
        form = formulation or material.formulation
        vol = volumetric or material.volumetric
        if form not in FORMULATIONS:
            raise InputError(f"formulation {form!r} is not one of {', '.join(FORMULATIONS)}")
        if vol not in VOLUMETRIC:
            raise InputError(f"volumetric {vol!r} is not one of {', '.join(VOLUMETRIC)}")
        return cls(material.mu, material.lam, cast(Formulation, form), cast(Volumetric, vol))

    @property
    def kappa(self) -> float:
        return self.lam + 2.0 * self.mu / 3.0

    @property
    def name(self) -> str:
        if self.formulation == "coupled":
            return "neo-hookean/coupled"
        return f"neo-hookean/uncoupled/{self.volumetric}"

    def energy(self, F: np.ndarray, frames: np.ndarray | None = None) -> np.ndarray:
        """Strain energy density ``psi(F)`` (NaN where ``J <= 0``; isotropic: ``frames``,
        the anisotropic laws' element frames, are ignored)."""
        J = _det(F)
        I1 = np.einsum("...ij,...ij->...", F, F)
        with np.errstate(invalid="ignore", divide="ignore"):
            if self.formulation == "coupled":
                lnJ = np.log(J)
                return 0.5 * self.mu * (I1 - 3.0) - self.mu * lnJ + 0.5 * self.lam * lnJ**2
            U, _, _ = _volumetric(J, self.kappa, self.volumetric)
            return 0.5 * self.mu * (J ** (-2.0 / 3.0) * I1 - 3.0) + U

    def stress(self, F: np.ndarray, frames: np.ndarray | None = None) -> np.ndarray:
        """First Piola stress ``P = dpsi/dF`` (NaN where ``J <= 0``)."""
        F = np.asarray(F, dtype=float)
        J = _det(F)
        bad = ~(J > 0)
        with np.errstate(invalid="ignore", divide="ignore"):
            FiT = np.swapaxes(np.linalg.inv(np.where(bad[..., None, None], _I, F)), -1, -2)
            J = np.where(bad, np.nan, J)
            if self.formulation == "coupled":
                lnJ = np.log(J)[..., None, None]
                P = self.mu * (F - FiT) + self.lam * lnJ * FiT
            else:
                I1 = np.einsum("...ij,...ij->...", F, F)[..., None, None]
                c = self.mu * J[..., None, None] ** (-2.0 / 3.0)
                _, dU, _ = _volumetric(J, self.kappa, self.volumetric)
                P = c * (F - I1 / 3.0 * FiT) + (J * dU)[..., None, None] * FiT
        return np.where(bad[..., None, None], np.nan, P)

    def stress_tangent(
        self, F: np.ndarray, frames: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """First Piola stress ``P = dpsi/dF`` and tangent ``A_iJkL = dP_iJ/dF_kL``.

        Returns NaN where ``J <= 0`` (an inverted element), which the Newton solver
        treats as a failed step.
        """
        F = np.asarray(F, dtype=float)
        J = _det(F)
        with np.errstate(invalid="ignore", divide="ignore"):
            Fi = np.linalg.inv(np.where((J > 0)[..., None, None], F, _I))
            FiT = np.swapaxes(Fi, -1, -2)
            bad = ~(J > 0)
            J = np.where(bad, np.nan, J)
            # d(F^-T)_iJ / dF_kL = -F^-T_iL F^-T_kJ
            FiT_FiT = np.einsum("...ij,...kl->...ijkl", FiT, FiT)
            FiT_x = np.einsum("...il,...kj->...ijkl", FiT, FiT)
            II = np.einsum("ik,jl->ijkl", _I, _I)
            mu = self.mu
            if self.formulation == "coupled":
                lnJ = np.log(J)
                P = mu * (F - FiT) + self.lam * lnJ[..., None, None] * FiT
                A = (
                    mu * II
                    + ((mu - self.lam * lnJ)[..., None, None, None, None]) * FiT_x
                    + self.lam * FiT_FiT
                )
            else:
                I1 = np.einsum("...ij,...ij->...", F, F)
                c = mu * J ** (-2.0 / 3.0)
                _, dU, ddU = _volumetric(J, self.kappa, self.volumetric)
                c_ = c[..., None, None]
                P = c_ * (F - (I1 / 3.0)[..., None, None] * FiT) + (J * dU)[..., None, None] * FiT
                c4 = c[..., None, None, None, None]
                I1_4 = I1[..., None, None, None, None]
                F_FiT = np.einsum("...ij,...kl->...ijkl", F, FiT)
                FiT_F = np.einsum("...ij,...kl->...ijkl", FiT, F)
                A = c4 * (
                    II
                    - 2.0 / 3.0 * (F_FiT + FiT_F)
                    + 2.0 / 9.0 * I1_4 * FiT_FiT
                    + I1_4 / 3.0 * FiT_x
                )
                A = A + (J * (dU + J * ddU))[..., None, None, None, None] * FiT_FiT
                A = A - (J * dU)[..., None, None, None, None] * FiT_x
        P = np.where(bad[..., None, None], np.nan, P)
        return P, A

    def cauchy(self, F: np.ndarray, frames: np.ndarray | None = None) -> np.ndarray:
        """Cauchy stress ``sigma = P F^T / J``."""
        P, _ = self.stress_tangent(F)
        return np.einsum("...ij,...kj->...ik", P, F) / _det(F)[..., None, None]
