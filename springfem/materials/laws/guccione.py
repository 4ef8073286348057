"""Guccione's transversely isotropic exponential law (Guccione et al. 1991).

``W = C/2 (e^Q - 1)``, ``Q = b_f E_ff^2 + b_t (E_ss^2 + E_nn^2 + 2 E_sn^2)
+ 2 b_fs (E_fs^2 + E_fn^2)`` with ``E`` the Green–Lagrange strain in the element's
(fiber, sheet, normal) frame. Written over all nine entries, ``Q = sum_ab B_ab E_ab^2``
with ``B = [[b_f, b_fs, b_fs], [b_fs, b_t, b_t], [b_fs, b_t, b_t]]``, so
``S = dW/dE = C e^Q (B o E)`` and ``dS/dE = C e^Q (B_ab sym(delta_ac delta_bd)
+ 2 (B o E)_ab (B o E)_cd)``.

Examples
--------
>>> import numpy as np
>>> law = Guccione(C=2.0, b_f=8.0, b_t=2.0, b_fs=4.0, kappa=0.0)
>>> float(law.energy(np.eye(3))), law.name
(0.0, 'guccione')
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .base import TissueLaw
from .kinematics import green_lagrange, piola_from_pk2

_I = np.eye(3)
_SYM = 0.5 * (np.einsum("ac,bd->abcd", _I, _I) + np.einsum("ad,bc->abcd", _I, _I))


@dataclass(frozen=True)
class Guccione(TissueLaw):
    """Guccione law with an optional volumetric penalty.

    Parameters
    ----------
    C
        Stress scale.
    b_f, b_t, b_fs
        Fibre, transverse and fibre–sheet/normal shear exponents.
    kappa, volumetric
        See :class:`~springfem.materials.laws.base.TissueLaw`.
    """

    C: float = 1.0
    b_f: float = 1.0
    b_t: float = 1.0
    b_fs: float = 1.0
    label = "guccione"
    example = {"C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0}

    @classmethod
    def stiffening_modulus(cls, parameters):
        """``C``: with the exact calibration ``2 W_q / (C V)`` is Guccione's ``Q``."""
        return float(parameters["C"])

    @property
    def B(self) -> np.ndarray:
        f, t, s = self.b_f, self.b_t, self.b_fs
        return np.array([[f, s, s], [s, t, t], [s, t, t]], dtype=float)

    def local(self, F: np.ndarray, tangent: bool):
        E = green_lagrange(F)
        BE = self.B * E
        Q = np.einsum("...ab,...ab->...", BE, E)
        eQ = np.exp(Q)
        W = 0.5 * self.C * (eQ - 1.0)
        S = (self.C * eQ)[..., None, None] * BE
        CC = None
        if tangent:
            CC = (self.C * eQ)[..., None, None, None, None] * (
                self.B[:, :, None, None] * _SYM + 2.0 * np.einsum("...ab,...cd->...abcd", BE, BE)
            )
        P, A = piola_from_pk2(F, S, CC)
        return W, P, A
