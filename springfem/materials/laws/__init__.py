"""The finite-strain tissue laws, one module each, and the one table that lists them.

A law is a :class:`~.base.TissueLaw` subclass (its energy, first Piola stress and tangent
in the element's (fiber, sheet, normal) frame) registered here with :func:`register`.
Everything else is read off this table: the scene's law names and keys, the small-strain
tangent the spring calibration matches (:func:`small_strain_tangent`, the law's own
tangent at ``F = I``), the FEM reference's laws, the explicit kernels' choice and the
verdict's list. Adding a law: docs/laws.rst.

- :class:`Guccione` (``law = "guccione"``), :class:`HolzapfelOgden`
  (``law = "holzapfel-ogden"``);
- :func:`tissue_law` builds one from a scene material.

The isotropic :class:`NeoHookean` (``law = "neo-hookean"``, coupled or uncoupled) lives here
too; the small-strain laws are their matrices (:mod:`springfem.materials.elastic`).

Examples
--------
>>> import numpy as np
>>> law = Guccione(C=2.0, b_f=8.0, b_t=2.0, b_fs=4.0, kappa=50.0)
>>> P, A = law.stress_tangent(np.eye(3))
>>> float(A[0, 0, 0, 0]), float(A[1, 1, 1, 1]), float(A[0, 0, 1, 1])  # C b_f + kappa, ..
(66.0, 54.0, 50.0)
>>> TISSUE_LAWS["guccione"]
('C', 'b_f', 'b_t', 'b_fs')
>>> np.diag(small_strain_tangent("guccione", Guccione.example)).tolist()
[16.0, 4.0, 4.0, 2.0, 4.0, 4.0]
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ...errors import InputError
from ..voigt import VOIGT_PAIRS
from .base import TissueLaw
from .guccione import Guccione
from .holzapfel_ogden import HolzapfelOgden
from .neo_hookean import NeoHookean

#: The registered laws by name (:func:`register`).
LAWS: dict[str, type[TissueLaw]] = {}
#: Each registered law's constants, the ``[material]`` keys besides ``kappa`` (a live view).
TISSUE_LAWS: dict[str, tuple[str, ...]] = {}


def register(cls: type[TissueLaw]) -> type[TissueLaw]:
    """Add a law to the table under its ``label`` (usable as a class decorator).

    Parameters
    ----------
    cls
        A :class:`~.base.TissueLaw` subclass, a frozen dataclass whose fields beyond the
        common ones are its constants.

    Returns
    -------
    type
        ``cls``.
    """
    LAWS[cls.label] = cls
    TISSUE_LAWS[cls.label] = cls.keys()
    return cls


class LawNames(Sequence[str]):
    """A live tuple of law names: the fixed ones, then every registered law.

    Parameters
    ----------
    fixed
        Names that do not come from the table (the small-strain laws, neo-Hookean).

    Examples
    --------
    >>> names = LawNames(("linear",))
    >>> "guccione" in names, names[0], len(names) >= 3
    (True, 'linear', True)
    """

    def __init__(self, fixed: tuple[str, ...]):
        self.fixed = fixed

    def __getitem__(self, i: Any) -> Any:
        return (*self.fixed, *LAWS)[i]

    def __len__(self) -> int:
        return len(self.fixed) + len(LAWS)

    def __repr__(self) -> str:
        return repr(tuple(self))


def law_class(name: str) -> type[TissueLaw]:
    """The registered law ``name``.

    Raises
    ------
    InputError
        For a name not in the table (the message lists them).
    """
    if name not in LAWS:
        raise InputError(f"law {name!r} is not one of {', '.join(LAWS)}")
    return LAWS[name]


def tissue_law(material, kappa: float | None = None) -> TissueLaw:
    """The law object of a scene material with a registered ``law``.

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
    cls = law_class(material.law)
    params = dict(material.parameters)
    values = {k: float(params[k]) for k in cls.keys()}
    k = float(params.get("kappa", 0.0)) if kappa is None else float(kappa)
    active = float(params.get("active_tension", 0.0))
    return cls(kappa=k, volumetric=material.volumetric, active_tension=active, **values)


def small_strain_tangent(
    law: str, parameters: Mapping[str, float], kappa: float = 0.0, tension: bool = True
) -> np.ndarray:
    """The law's tangent at ``F = I`` as a ``(6, 6)`` Voigt matrix in its element frame.

    ``D_ab = A_ijkl`` at ``F = I`` (Voigt order ``ff, ss, nn, sn, fn, fs``, engineering
    shears): the passive law is stress free there, so ``dP/dF`` is the elasticity tensor.

    Parameters
    ----------
    law
        A registered law.
    parameters
        Its constants (:data:`TISSUE_LAWS`); other keys are ignored.
    kappa
        Bulk modulus of the volumetric penalty (0: none); it adds ``kappa`` to every entry
        of the normal block.
    tension
        For a law with terms on in tension only: the tangent with them on (a stretch along
        them) or off (compression, and the FEM's at exactly ``F = I``).

    Returns
    -------
    numpy.ndarray
        ``D`` with ``sigma = D eps``; rotate it to the global frame with
        :func:`springfem.materials.rotate_to_global`.

    Raises
    ------
    ValueError
        An unknown law, or a constant missing.
    """
    if law not in LAWS:
        raise ValueError(f"law {law!r} is not one of {', '.join(LAWS)}")
    cls = LAWS[law]
    missing = [k for k in cls.keys() if k not in parameters]
    if missing:
        raise ValueError(f"{law} needs {', '.join(missing)}")
    values = {k: float(parameters[k]) for k in cls.keys()}
    tissue = cls(kappa=float(kappa), volumetric="log", **values).small_strain(tension)
    _, A = tissue.stress_tangent(np.eye(3))
    idx = np.array(VOIGT_PAIRS)
    return A[idx[:, 0, None], idx[:, 1, None], idx[None, :, 0], idx[None, :, 1]]


def register_plugins() -> None:
    """Register the laws installed packages declare: entry points ``springfem.laws``,
    ``name = "module:Class"`` (:mod:`springfem.plugins`; docs/laws.rst#add-a-law-plug-in)."""
    from ...plugins import entry_points, load

    for value in entry_points("springfem.laws").values():
        register(load(value))


register(Guccione)
register(HolzapfelOgden)
register_plugins()

__all__ = [
    "LAWS",
    "TISSUE_LAWS",
    "Guccione",
    "HolzapfelOgden",
    "LawNames",
    "NeoHookean",
    "TissueLaw",
    "law_class",
    "register",
    "register_plugins",
    "small_strain_tangent",
    "tissue_law",
]
