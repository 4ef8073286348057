"""The Holzapfel–Ogden (2009) orthotropic myocardium law, eight parameters.

``W = a/(2b) (e^{b (I1bar - 3)} - 1) + sum_{i=f,s} a_i/(2 b_i) (e^{b_i (I4i - 1)^2} - 1)
+ a_fs/(2 b_fs) (e^{b_fs I8fs^2} - 1)``, the fibre and sheet terms only where
``I4i > 1`` (tension). ``I4f = f.Cf``, ``I4s = s.Cs``, ``I8fs = f.Cs`` are invariants of
the full ``C`` (Nolan et al. 2014); only the isotropic term uses ``I1bar = J^(-2/3) I1``,
so the law is stress free at ``F = I`` with or without the volumetric penalty.

In the element frame ``I4f = C_00 = 1 + 2 E_00``, ``I4s = C_11``, ``I8fs = C_01``; a term
``psi(I)`` gives ``S = psi' dI/dE`` and ``dS/dE = psi'' dI/dE (x) dI/dE``.

Examples
--------
>>> import numpy as np
>>> law = HolzapfelOgden(a=1.0, b=5.0, a_f=2.0, b_f=5.0, a_s=1.0, b_s=5.0, a_fs=0.5,
...                      b_fs=5.0, kappa=100.0)
>>> float(abs(law.stress(np.eye(3))).max()), law.name
(0.0, 'holzapfel-ogden/log')
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .base import TissueLaw
from .kinematics import isochoric_i1, piola_from_pk2

#: ``I4 - 1`` above which a fibre or sheet counts as in tension: round-off of a rotated
#: frame at ``F = I`` does not switch the terms on (their stress there is ~1e-12 a_f).
TENSION = 1e-12
_E = np.eye(3)
#: d I4f / dE, d I4s / dE and d I8fs / dE (symmetric).
_DI4F = 2.0 * np.outer(_E[0], _E[0])
_DI4S = 2.0 * np.outer(_E[1], _E[1])
_DI8 = np.outer(_E[0], _E[1]) + np.outer(_E[1], _E[0])


def _exp_term(a: float, b: float, x: np.ndarray, active: np.ndarray | None = None):
    """``psi = a/(2b)(e^{b x^2} - 1)``, ``psi'(x)``, ``psi''(x)`` (zero where inactive)."""
    e = np.exp(b * x**2)
    psi, d1, d2 = a / (2 * b) * (e - 1.0), a * x * e, a * (1.0 + 2.0 * b * x**2) * e
    if active is None:
        return psi, d1, d2
    return np.where(active, psi, 0.0), np.where(active, d1, 0.0), np.where(active, d2, 0.0)


@dataclass(frozen=True)
class HolzapfelOgden(TissueLaw):
    """Holzapfel–Ogden law with an optional volumetric penalty.

    Parameters
    ----------
    a, b
        Isotropic (matrix) stiffness and exponent.
    a_f, b_f, a_s, b_s
        Fibre and sheet stiffnesses and exponents (tension only).
    a_fs, b_fs
        Fibre–sheet shear coupling.
    kappa, volumetric
        See :class:`~springfem.materials.laws.base.TissueLaw`.
    tension_only
        The fibre and sheet terms act in tension only (the law); False: always (their
        small-strain tangent in tension, :meth:`small_strain`).
    """

    a: float = 1.0
    b: float = 1.0
    a_f: float = 0.0
    b_f: float = 1.0
    a_s: float = 0.0
    b_s: float = 1.0
    a_fs: float = 0.0
    b_fs: float = 1.0
    tension_only: bool = field(default=True, metadata={"parameter": False})
    label = "holzapfel-ogden"
    nonnegative = ("a", "a_f", "a_s", "a_fs")
    example = {"a": 1.0, "b": 1.0, "a_f": 1.0, "b_f": 1.0, "a_s": 1.0, "b_s": 1.0,
               "a_fs": 1.0, "b_fs": 1.0}  # fmt: skip

    @classmethod
    def check(cls, parameters):
        if parameters["a"] == 0:
            return "a", "must be positive (the isotropic term carries shear)"
        return None

    @classmethod
    def stiffening_modulus(cls, parameters):
        """``a_f / b_f`` (when both are positive): the stiffening is then the fibre term
        ``a_f/(2 b_f) (exp(b_f (I4f - 1)^2) - 1)`` under a stretch along the fibre
        (``2 W_q / (C V) = b_f (I4f - 1)^2`` to leading order, ``W_q / V = 2 a_f E_ff^2``);
        one exponent per element cannot also be the sheet's ``b_s`` or the isotropic ``b``."""
        a_f, b_f = parameters.get("a_f", 0), parameters.get("b_f", 0)
        return float(a_f) / float(b_f) if a_f > 0 and b_f > 0 else None

    def small_strain(self, tension: bool) -> HolzapfelOgden:
        return replace(self, tension_only=not tension)

    def local(self, F: np.ndarray, tangent: bool):
        I1b, D1, D2 = isochoric_i1(F)
        e = np.exp(self.b * (I1b - 3.0))
        W = self.a / (2 * self.b) * (e - 1.0)
        P_iso = (0.5 * self.a * e)[..., None, None] * D1
        C = np.einsum("...kI,...kJ->...IJ", F, F)
        S = np.zeros_like(C)
        CC = np.zeros(C.shape[:-2] + (3, 3, 3, 3)) if tangent else None
        terms = (
            (self.a_f, self.b_f, C[..., 0, 0] - 1.0, _DI4F, True),
            (self.a_s, self.b_s, C[..., 1, 1] - 1.0, _DI4S, True),
            (self.a_fs, self.b_fs, C[..., 0, 1], _DI8, False),
        )
        for a, b, x, dI, switch in terms:
            if a == 0.0:
                continue
            on = (x > TENSION) if switch and self.tension_only else None
            psi, d1, d2 = _exp_term(a, b, x, on)
            W = W + psi
            S = S + d1[..., None, None] * dI
            if tangent:
                CC = CC + d2[..., None, None, None, None] * np.einsum("ab,cd->abcd", dI, dI)
        P, A = piola_from_pk2(F, S, CC)
        P = P + P_iso
        if tangent:
            A = A + (0.5 * self.a * e)[..., None, None, None, None] * D2
            A = A + (0.5 * self.a * self.b * e)[..., None, None, None, None] * np.einsum(
                "...ij,...kl->...ijkl", D1, D1
            )
        return W, P, A
