"""The interface every tissue law shares: energy, stress and tangent in element frames.

A law implements :meth:`TissueLaw.local` (energy, first Piola stress and tangent of the
deformation gradient expressed in the element frame, without the volumetric term); this
class adds the penalty ``U(J)`` (``kappa > 0``), rotates to the global frame and marks
inverted elements (``J <= 0``) with NaN, like :class:`~.neo_hookean.NeoHookean`.
The law's constants are its other dataclass fields (:meth:`TissueLaw.keys`, the
``[material]`` keys), in the order :func:`springfem.materials.laws.register` lists them.
``frames`` is ``(..., 3, 3)`` broadcast against ``F`` (rows: fiber, sheet, normal);
``None`` means the global axes.

The fibre invariants are those of the full ``C``, never split isochorically (Nolan et al.
2014); incompressibility comes from ``U(J)`` or from the mixed formulation
(``kappa = 0``, :mod:`reference_fem.mixed`). Adding a law: docs/laws.rst.

An active fibre tension ``T_a`` (``active_tension``, docs/fem.rst#active-tension) adds
``T_a f0 (x) f0`` to the second Piola stress: in the element frame (``f0 = e_0``) the
energy-like term ``T_a/2 (I4f - 1)`` with ``I4f = C'_00``, so ``P' += T_a F' e_0 (x) e_0``
and ``A'_iJkL += T_a delta_ik delta_J0 delta_L0``; :meth:`TissueLaw.activated` scales it
with the load factor.

Examples
--------
A law with no energy of its own (``W = 0``) is the volumetric penalty alone:

>>> import numpy as np
>>> class Penalty(TissueLaw):
...     label = "penalty"
...     def local(self, F, tangent):
...         zero = np.zeros(F.shape[:-2])
...         A = np.zeros(F.shape + (3, 3)) if tangent else None
...         return zero, np.zeros_like(F), A
>>> law = Penalty(kappa=1.0, volumetric="quadratic")
>>> law.name, float(law.energy(np.eye(3)))
('penalty/quadratic', 0.0)
>>> bool(np.isnan(law.energy(-np.eye(3))))  # inverted (J <= 0): NaN
True

An active tension ``T_a`` is a fibre stress ``S_ff = T_a`` at rest; half of it at load 0.5:

>>> active = Penalty(kappa=1.0, active_tension=60.0)
>>> float(active.stress(np.eye(3))[0, 0]), float(active.activated(0.5).stress(np.eye(3))[0, 0])
(60.0, 30.0)
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from typing import ClassVar

import numpy as np

from .kinematics import det, stress_from_frame, tangent_from_frame, to_frame, volumetric_terms

#: The fields every law has that are not its own constants.
_COMMON = ("kappa", "volumetric", "active_tension")


@dataclass(frozen=True)
class TissueLaw:
    """Base of the anisotropic tissue laws.

    Parameters
    ----------
    kappa
        Bulk modulus of the volumetric penalty ``U(J)``; 0 for none (mixed formulation).
    volumetric
        ``log``, ``quadratic`` or ``simo-taylor`` (as for neo-Hookean).
    active_tension
        Active fibre tension ``T_a`` (a stress; 0: passive), added as ``T_a f0 (x) f0``
        to the second Piola stress.
    """

    kappa: float = 0.0
    volumetric: str = "log"
    active_tension: float = 0.0

    #: Assembly passes each element's frame to laws with this flag.
    anisotropic = True
    label = "tissue"
    #: Constants that may be zero (the others must be positive in a scene).
    nonnegative: ClassVar[tuple[str, ...]] = ()
    #: Constants of a small example material (the scene reference, docs/laws.rst).
    example: ClassVar[dict[str, float]] = {}

    @classmethod
    def keys(cls) -> tuple[str, ...]:
        """The law's constants: its dataclass fields but ``kappa``, ``volumetric``,
        ``active_tension`` and those marked ``metadata={"parameter": False}``."""
        return tuple(
            f.name
            for f in fields(cls)
            if f.name not in _COMMON and f.metadata.get("parameter", True)
        )

    @classmethod
    def check(cls, parameters: Mapping[str, float]) -> tuple[str, str] | None:
        """``(key, reason)`` when the constants are not a valid material, else None.

        Parameters
        ----------
        parameters
            The constants (:meth:`keys`), each already finite and of the right sign.
        """
        return None

    @classmethod
    def stiffening_modulus(cls, parameters: Mapping[str, float]) -> float | None:
        """The modulus ``C`` of the spring element's exponential stiffening
        ``V C/2 (exp(2 W_q / (C V)) - 1)`` (:mod:`springmodel.stiffening`), or None: the
        scene must give ``[spring] stiffening_modulus``."""
        return None

    def small_strain(self, tension: bool) -> TissueLaw:
        """The law whose tangent at ``F = I`` is this one's small-strain tangent.

        A law with terms that switch on in tension only returns itself with them always on
        (``tension``) or always off; others return ``self``.
        """
        return self

    @property
    def name(self) -> str:
        return self.label if self.kappa == 0 else f"{self.label}/{self.volumetric}"

    def local(self, F: np.ndarray, tangent: bool):  # pragma: no cover - interface
        """``(W, P, A)`` of ``F`` in the element frame (``A`` None without ``tangent``)."""
        raise NotImplementedError

    def activated(self, level: float) -> TissueLaw:
        """The law with its active tension scaled by ``level`` (the load factor).

        Parameters
        ----------
        level
            Activation level, 1 for the full ``active_tension``.

        Returns
        -------
        TissueLaw
            ``self`` when there is no active tension or ``level == 1``.
        """
        if self.active_tension == 0.0 or level == 1.0:
            return self
        return replace(self, active_tension=level * self.active_tension)

    def _evaluate(self, F: np.ndarray, frames, tangent: bool):
        F = np.asarray(F, dtype=float)
        bad = ~(det(F) > 0)
        Fl = to_frame(F, frames)
        with np.errstate(invalid="ignore", over="ignore"):
            W, P, A = self.local(Fl, tangent)
            if self.active_tension != 0.0:
                W, P, A = _add_active(Fl, self.active_tension, W, P, A)
            if self.kappa > 0:
                U, Pv, Av = volumetric_terms(Fl, self.kappa, self.volumetric, tangent)
                W, P = W + U, P + Pv
                A = A + Av if tangent else None
        W = np.where(bad, np.nan, W)
        P = np.where(bad[..., None, None], np.nan, stress_from_frame(P, frames))
        if tangent:
            A = tangent_from_frame(A, frames)
        return W, P, A

    def energy(self, F: np.ndarray, frames: np.ndarray | None = None) -> np.ndarray:
        """Strain energy density ``W(F)`` (NaN where ``J <= 0``)."""
        return self._evaluate(F, frames, False)[0]

    def stress(self, F: np.ndarray, frames: np.ndarray | None = None) -> np.ndarray:
        """First Piola stress ``P = dW/dF``."""
        return self._evaluate(F, frames, False)[1]

    def stress_tangent(self, F: np.ndarray, frames: np.ndarray | None = None):
        """``P`` and the tangent ``A_iJkL = dP_iJ / dF_kL``."""
        _, P, A = self._evaluate(F, frames, True)
        return P, A

    def cauchy(self, F: np.ndarray, frames: np.ndarray | None = None) -> np.ndarray:
        """Cauchy stress ``sigma = P F^T / J`` (without the mixed pressure)."""
        P = self.stress(F, frames)
        return np.einsum("...ij,...kj->...ik", P, F) / det(F)[..., None, None]


def _add_active(Fl: np.ndarray, T: float, W, P, A):
    """``W + T/2 (I4f - 1)``, ``P + T F' e0 (x) e0``, ``A + T delta_ik e0_J e0_L`` (frame)."""
    f = Fl[..., :, 0]  # F' e_0: the deformed fibre
    W = W + 0.5 * T * (np.einsum("...i,...i->...", f, f) - 1.0)
    P = P.copy()
    P[..., :, 0] += T * f
    if A is not None:
        A = A.copy()
        A[..., :, 0, :, 0] += T * np.eye(3)
    return W, P, A
