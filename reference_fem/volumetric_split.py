"""Split a law into the part kept per element and its volumetric penalty ``U(J)``.

The locking-free formulations (:mod:`reference_fem.nodal_volume`, :mod:`reference_fem.mixed`)
treat the volumetric energy on their own and the rest of the law element by element
(docs/fem.rst#locking-free-linear-tetrahedra):

- uncoupled neo-Hookean ``mu/2 (I1bar - 3) + U(J)``: the isochoric part and ``U`` with
  ``kappa``;
- coupled neo-Hookean ``mu/2 (I1 - 3) - mu ln J + lam/2 ln^2 J``: the first two terms and
  ``U = lam/2 ln^2 J`` (the ``log`` energy with ``kappa = lam``);
- a tissue law (Guccione, Holzapfel–Ogden): the law without its penalty and its ``U(J)``
  (:mod:`springfem.materials.laws.base`); an incompressible material gets the penalty of its
  isotropic equivalent, ``Material.kappa``.

Every split adds up to the law: ``W(F) = W_base(F) + U(J)``.

Examples
--------
>>> import numpy as np
>>> from springfem.materials.laws.neo_hookean import NeoHookean
>>> law = NeoHookean(mu=1.0, lam=2.0, formulation="uncoupled", volumetric="quadratic")
>>> part = volumetric_split(law)
>>> round(part.kappa, 12), part.kind
(2.666666666667, 'quadratic')
>>> F = np.diag([1.1, 0.95, 1.02])
>>> U, _, _ = part.volumetric(np.linalg.det(F))
>>> bool(np.isclose(part.base.energy(F) + U, law.energy(F)))
True
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from springfem.errors import InputError
from springfem.materials.laws import TissueLaw
from springfem.materials.laws.neo_hookean import NeoHookean
from springfem.volumetric import volumetric_energy as _volumetric


@dataclass(frozen=True)
class VolumetricSplit:
    """A law as ``W_base(F) + U(J)``.

    Attributes
    ----------
    base
        The law without its volumetric energy (same interface as the law).
    kappa
        Bulk modulus of ``U`` (Pa); 0 means none.
    kind
        ``U``: ``log``, ``quadratic`` or ``simo-taylor``
        (docs/volumetric.rst#volumetric-energies).
    """

    base: Any
    kappa: float
    kind: str

    def volumetric(self, J: np.ndarray):
        """``U(J)``, ``U'(J)`` and ``U''(J)`` (NaN where ``J <= 0``)."""
        J = np.asarray(J, dtype=float)
        with np.errstate(invalid="ignore", divide="ignore"):
            return _volumetric(np.where(J > 0, J, np.nan), self.kappa, self.kind)


def volumetric_split(law, material=None) -> VolumetricSplit:
    """The element part and the volumetric energy of a hyperelastic law.

    Parameters
    ----------
    law
        A :class:`~springfem.materials.laws.neo_hookean.NeoHookean` or
        :class:`~springfem.materials.laws.TissueLaw`.
    material
        The scene material; its ``kappa`` is the penalty of a tissue law without one
        (an incompressible material). Without it such a law keeps ``kappa = 0``
        (incompressible, for the mixed formulation).

    Returns
    -------
    VolumetricSplit

    Raises
    ------
    InputError
        A law without a volumetric split (a linear law).
    """
    if isinstance(law, NeoHookean):
        if law.formulation == "coupled":
            return VolumetricSplit(NeoHookean(law.mu, 0.0, "coupled"), law.lam, "log")
        base = NeoHookean(law.mu, -2.0 * law.mu / 3.0, "uncoupled", law.volumetric)
        return VolumetricSplit(base, law.kappa, law.volumetric)
    if isinstance(law, TissueLaw):
        kappa = law.kappa
        if kappa <= 0 and material is not None:
            kappa = float(material.kappa)
        return VolumetricSplit(dataclasses.replace(law, kappa=0.0), kappa, law.volumetric)
    raise InputError(f"law {getattr(law, 'name', law)!r} has no volumetric split")
