"""Finite-strain anisotropic tissue laws for the FEM reference.

- :class:`Guccione` (``law = "guccione"``), :class:`HolzapfelOgden`
  (``law = "holzapfel-ogden"``): energy, first Piola stress and consistent tangent,
  vectorised over quadrature points, in each element's (fiber, sheet, normal) frame;
- :func:`tissue_law` builds one from a scene material.

Their small-strain tangents are :func:`springfem.materials.tissue.tissue_tangent`.

Examples
--------
>>> import numpy as np
>>> law = Guccione(C=2.0, b_f=8.0, b_t=2.0, b_fs=4.0, kappa=50.0)
>>> P, A = law.stress_tangent(np.eye(3))
>>> float(A[0, 0, 0, 0]), float(A[1, 1, 1, 1]), float(A[0, 0, 1, 1])  # C b_f + kappa, ..
(66.0, 54.0, 50.0)
"""

from __future__ import annotations

from springfem.errors import InputError
from springfem.materials.tissue import TISSUE_LAWS

from .base import TissueLaw
from .guccione import Guccione
from .holzapfel_ogden import HolzapfelOgden

_CLASSES = {"guccione": Guccione, "holzapfel-ogden": HolzapfelOgden}


def tissue_law(material, kappa: float | None = None) -> TissueLaw:
    """The law object of a scene material with ``law`` in :data:`TISSUE_LAWS`.

    Parameters
    ----------
    material
        A :class:`~springfem.scene.Material` (its ``parameters`` hold the law's keys,
        ``kappa`` (``incompressible`` materials get ``kappa = 0``) and, if active,
        ``active_tension``).
    kappa
        Override of the penalty bulk modulus (0: none, for the mixed formulation).

    Returns
    -------
    TissueLaw
    """
    if material.law not in _CLASSES:
        raise InputError(f"law {material.law!r} is not one of {', '.join(TISSUE_LAWS)}")
    params = dict(material.parameters)
    values = {k: float(params[k]) for k in TISSUE_LAWS[material.law]}
    k = float(params.get("kappa", 0.0)) if kappa is None else float(kappa)
    active = float(params.get("active_tension", 0.0))
    return _CLASSES[material.law](
        kappa=k, volumetric=material.volumetric, active_tension=active, **values
    )


__all__ = ["TISSUE_LAWS", "Guccione", "HolzapfelOgden", "TissueLaw", "tissue_law"]
