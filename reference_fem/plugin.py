"""The FEM models of the model registry (:mod:`springfem.model_api`): each order, law and
formulation of the reference, one name each: ``fem`` (the scene's ``[fem]``), ``P1``, ``P2``
(the scene's small-strain law, or its tissue law), ``P1-NH``, ``P2-NH`` and the locking-free
``fem-P1-nodal-strain``, ``fem-P1-nodal-volume``, ``fem-MINI``, ``fem-P2-mixed``
(docs/studies.rst#the-model-registry). A model whose order the scene's formulation does not
fit solves the nearest one (:func:`~reference_fem.fitting.fitting_formulation`).

Examples
--------
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({"mesh": {"generator": "box", "size": [1, 1, 1],
...     "divisions": [1, 1, 1]}, "material": {"law": "neo-hookean", "E": 1.0, "nu": 0.3}})
>>> [m.name for m in MODELS if m.locking_free]
['fem-P1-nodal-volume', 'fem-P1-nodal-strain', 'fem-MINI', 'fem-P2-mixed']
>>> P1_NH.fem_options(scene).order, P1_NH.locks(scene)
(1, None)
>>> MODELS[-3].system(scene)  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
springfem.errors.InputError: model fem-P1-nodal-strain: the explicit FEM is displacement P1, ...
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

from springfem.errors import InputError
from springfem.materials.laws import TISSUE_LAWS
from springfem.model_api import ModelSolution
from springfem.plausibility import nearly_incompressible
from springfem.scene import Scene

from .fitting import fitted_scene, formulation_problem, linear_law, tissue_scene
from .options import FemOptions

#: The small-strain laws (a model solving one against a hyperelastic reference is not like
#: for like).
SMALL_STRAIN_LAWS = ("linear", "transverse-linear")


class FemModel:
    """An FEM model: an order, a law and the ``[fem]`` options it replaces.

    Parameters
    ----------
    name, label
        See :class:`springfem.model_api.ModelPlugin`.
    order
        1 or 2 (``None``: the scene's ``[fem] order``).
    law
        ``small-strain``, ``neo-hookean`` or ``scene`` (the scene's own law and
        formulation).
    fem
        ``[fem]`` options (fields of :class:`~reference_fem.options.FemOptions`, such as
        ``formulation``) that replace the scene's before the solve.

    Attributes
    ----------
    default
        ``False``: the studies name the FEM models they weigh.
    reference
        ``True``: an FEM of the scene's law may be a comparison's reference.
    locking_free
        A formulation that does not lock near incompressibility (weighed too on a nearly
        incompressible scene).
    claims
        What :func:`springfem.testing.check_model` holds it to: ``P1`` is linear P1
        (``small_strain = "exact"``), ``P1-NH`` its limit under a tiny load (``limit``).
    """

    default = False
    reference = True
    result_model = "fem"

    def __init__(
        self,
        name: str,
        label: str,
        order: int | None = None,
        law: str = "small-strain",
        fem: Mapping[str, Any] | None = None,
    ):
        self.name, self.label, self.order, self.fem_law = name, label, order, law
        self.fem = dict(fem or {})
        self.settings: Mapping[str, Any] = {"order": order, "law": law, **self.fem}
        form = self.fem.get("formulation", "displacement")
        self.locking_free = form != "displacement"
        p1 = order == 1 and form == "displacement"
        limit = {"small-strain": "exact", "neo-hookean": "limit"}.get(law) if p1 else None
        self.claims: Mapping[str, str] = {"small_strain": limit} if limit else {}

    def __repr__(self) -> str:
        return f"FemModel({self.name!r})"

    def applies(self, scene: Scene) -> str | None:
        """Why this model cannot solve ``scene`` (``None``: it can)."""
        law = scene.material.law
        if self.fem_law == "neo-hookean" and law == "transverse-linear":
            return (
                f"model {self.name}: reference_fem has no anisotropic hyperelastic law "
                "for the transverse-linear material"
            )
        if self.fem_law == "neo-hookean" and law in TISSUE_LAWS:
            return (
                f"model {self.name}: neo-Hookean is not the scene's {law} law; P1 and P2 "
                "solve that law"
            )
        if self.fem.get("formulation"):
            why = formulation_problem(scene, str(self.fem["formulation"]), self.fem_law)
            return None if why is None else f"model {self.name}: {why}"
        return None

    def fem_settings(self, scene: Scene) -> tuple[Scene, int | None, str | None]:
        """``(scene, order, law)`` of :func:`reference_fem.solve` for this model.

        Parameters
        ----------
        scene
            The scene.

        Returns
        -------
        tuple
        """
        if self.fem:
            scene = scene.with_options(fem=replace(FemOptions.of(scene), **self.fem))
        if self.fem_law == "scene":
            return scene, self.order, None
        # the scene's formulation, or the nearest one of this order (fitting.fitted_scene)
        if self.fem_law == "neo-hookean":
            return fitted_scene(scene, self.order, "neo-hookean"), self.order, "neo-hookean"
        if scene.material.law in TISSUE_LAWS:
            return tissue_scene(scene, self.order), self.order, scene.material.law
        law = linear_law(scene)
        return fitted_scene(scene, self.order, law), self.order, law

    def fem_options(self, scene: Scene) -> FemOptions:
        """The ``[fem]`` options (order and formulation included) it solves ``scene`` with."""
        fem_scene, order, _ = self.fem_settings(scene)
        fem = FemOptions.of(fem_scene)
        return replace(fem, order=fem.order if order is None else order)

    def solves_law(self, scene: Scene) -> str:
        """The law it solves on ``scene`` (``linear``, ``neo-hookean``, a tissue law ...)."""
        fem_scene, _, law = self.fem_settings(scene)
        return (law or fem_scene.material.law).split("/")[0]

    def solve_key(self, scene: Scene) -> Any:
        """What identifies its solve of ``scene`` (models with one key are one solve)."""
        fem_scene, _, law = self.fem_settings(scene)
        fem = self.fem_options(scene)
        return ("fem", repr(fem), law or fem_scene.material.law, repr(fem_scene.material))

    def law_versus(self, scene: Scene, reference_law: str) -> str:
        """What it solves against the reference's law (:func:`studies.models.law_versus`)."""
        law = self.solves_law(scene)
        if law == reference_law:
            return "same law"
        return "small-strain law" if law in SMALL_STRAIN_LAWS else "other law"

    def locks(self, scene: Scene) -> str | None:
        """Why it locks on ``scene``: a displacement P1 or P2 on a nearly incompressible
        scene (``None``: it does not)."""
        if not nearly_incompressible(scene):
            return None
        try:
            fem = self.fem_options(scene)
        except Exception:  # noqa: BLE001 - a model that does not build here is not ruled out
            return None
        if fem.formulation != "displacement":
            return None
        mat = scene.material
        nu = getattr(mat, "nu", None)
        why = "an incompressible material" if mat.incompressible else f"nu = {nu:.4g}"
        return f"displacement P{fem.order} locks at {why}"

    def solve(self, scene: Scene, verbose: bool = False) -> ModelSolution:
        """The static solve of ``scene`` (:func:`reference_fem.solve`)."""
        from .solver import solve

        why = self.applies(scene)
        if why is not None:
            raise InputError(why)
        fem_scene, order, law = self.fem_settings(scene)
        sol = solve(fem_scene, order=order, law=law, verbose=verbose)
        return ModelSolution(sol.result, sol.u_vertices, dict(sol.cell_data))

    def system(self, scene: Scene):
        """The explicit P1 FEM of the law it solves (:class:`~reference_fem.explicit.ExplicitFem`).

        Raises
        ------
        InputError
            It does not apply, or has no explicit form: a P2 model, or a formulation other
            than displacement P1 (nodal strain, nodal volume, MINI, mixed).
        """
        from .explicit import ExplicitFem

        why = self.applies(scene)
        if why is not None:
            raise InputError(why)
        fem = self.fem_options(scene)
        if fem.order == 2:
            raise InputError(f"model {self.name}: there is no explicit P2 FEM")
        if fem.formulation != "displacement":
            raise InputError(
                f"model {self.name}: the explicit FEM is displacement P1, not {fem.formulation}"
            )
        _, _, law = self.fem_settings(scene)
        return ExplicitFem(scene, law=law or scene.material.law)


FEM = FemModel("fem", "FEM (the scene's [fem] options)", law="scene")
P1 = FemModel("P1", "FEM P1", order=1)
P2 = FemModel("P2", "FEM P2", order=2)
P1_NH = FemModel("P1-NH", "FEM P1 neo-Hookean", order=1, law="neo-hookean")
P2_NH = FemModel("P2-NH", "FEM P2 neo-Hookean", order=2, law="neo-hookean")

#: The FEM models, in the order the studies list them: the locking-free methods
#: (docs/volumetric.rst) last.
MODELS: tuple[FemModel, ...] = (
    FEM,
    P1,
    P2,
    P1_NH,
    P2_NH,
    *(
        FemModel(
            name, label, order=order, law="scene", fem={"order": order, "formulation": form}
        )  # fmt: skip
        for name, label, order, form in (
            ("fem-P1-nodal-volume", "FEM P1, nodal-averaged volume", 1, "nodal-volume"),
            ("fem-P1-nodal-strain", "FEM P1, nodal-averaged strain", 1, "nodal-strain"),
            ("fem-MINI", "FEM MINI (P1-bubble / P1)", 1, "mini"),
            ("fem-P2-mixed", "FEM P2/P1 Taylor–Hood", 2, "mixed"),
        )
    ),
)


def models() -> tuple[FemModel, ...]:
    """The FEM models (the ``springfem.models`` entry point of this package)."""
    return MODELS
