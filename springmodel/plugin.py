"""The spring models of the model registry (:mod:`springfem.model_api`): the scene's spring
model (``spring``), each named element (``spring-spec``, ``spring-exact``,
``spring-stiffened``, ``spring-tissue``), the torsion variants and the stabilised
(locking-free) elements, one name each (docs/studies.rst#the-model-registry).

Examples
--------
>>> [m.name for m in MODELS][:3]
['spring', 'spring-spec', 'spring-exact']
>>> MODELS[2].changes == EXACT, MODELS[2].order, MODELS[2].claims
(True, 1, {'small_strain': 'exact'})
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

from springfem.errors import InputError
from springfem.materials.laws import LAWS, TISSUE_LAWS
from springfem.model_api import ModelSolution
from springfem.scene import Scene

from .options import (
    ANISOTROPIC_LAWS,
    ELEMENT_KEYS,
    ELEMENTS,
    GREEN_AXIAL_COEFFICIENTS,
    LMSOptions,
    SpringOptions,
)

#: The exact spring element: small-strain P1 on any tet (with coupling when anisotropic).
EXACT = dict(ELEMENTS["exact"])
#: The spring element for tissue at finite strain: the exact element with Green axial
#: springs, the shear torsion law, the exponential stiffening of the element energy and the
#: tissue laws' log penalty ``U(J)``.
STIFFENED = dict(ELEMENTS["stiffened"])
#: The tissue element: the stiffened element's Green measures with the Green torsion (all six
#: frame components of E) and each spring group stiffened as the law's own terms, so that
#: it equals its law under any homogeneous deformation (docs/tissue.rst).
TISSUE = dict(ELEMENTS["tissue"])
_NODAL = {"volume_average": "nodal", "strain_average": "nodal"}
#: The claim of the elements whose tangent at rest is linear P1's.
P1_TANGENT = {"small_strain": "exact"}


class SpringVariant:
    """A spring model: the scene's ``[spring]`` options with changes, or a whole element.

    Parameters
    ----------
    name, label
        See :class:`springfem.model_api.ModelPlugin`.
    changes
        Changes to the scene's ``[spring]`` options (values of
        :class:`~springmodel.options.SpringOptions`; ``lms`` may be a rule name and
        ``axial`` ``"green"``, as in a scene file). If the scene's element is not the
        seed's, the changes are made to the seed's element.
    coupling
        Add the Poisson-coupling springs when the law is anisotropic.
    element
        The model defines the whole element (:data:`~springmodel.options.ELEMENT_KEYS`
        start from their defaults, whatever the scene's ``[spring]`` says).

    Attributes
    ----------
    default, reference
        ``False``: the studies name the spring models they weigh; none is a reference.
    order
        1: the spring element is a linear tet (docs/design: a P1 element with its own
        material).
    locking_free
        Nodal strain and nodal volume (the stabilised elements).
    claims
        What :func:`springfem.testing.check_model` holds it to: ``small_strain = "exact"``
        for the exact, stiffened and tissue elements (their tangent at rest is linear
        P1's).
    """

    default = False
    reference = False
    order = 1
    result_model = "spring"

    def __init__(
        self,
        name: str,
        label: str,
        changes: Mapping[str, Any] | None = None,
        coupling: bool = False,
        element: bool = False,
        claims: Mapping[str, str] | None = None,
    ):
        self.name, self.label = name, label
        self.changes = dict(changes or {})
        self.coupling, self.element = coupling, element
        self.settings: Mapping[str, Any] = dict(self.changes)
        nodal = ("strain_average", "volume_average")
        self.locking_free = any(self.changes.get(k) == "nodal" for k in nodal)
        self.claims: Mapping[str, str] = dict(claims or {})

    def __repr__(self) -> str:
        return f"SpringVariant({self.name!r})"

    def spring_options(self, scene: Scene) -> SpringOptions:
        """The spring options this model solves ``scene`` with.

        Parameters
        ----------
        scene
            The scene.

        Returns
        -------
        SpringOptions
        """
        changes = dict(self.changes)
        if isinstance(changes.get("lms"), str):
            changes["lms"] = LMSOptions(rule=changes["lms"])
        if changes.get("axial") == "green":  # the scene files' spelling of the cubic law
            changes["axial"], changes["axial_coefficients"] = "cubic", GREEN_AXIAL_COEFFICIENTS
        if self.coupling and scene.material.law in ANISOTROPIC_LAWS:
            changes["coupling"] = True
        options = SpringOptions.of(scene)
        if self.element or (changes and options.element != "seed"):
            # a whole element, or a variant of one option: a variant is of the spec's
            # element, whichever element the scene names (docs/studies.rst)
            default = SpringOptions()
            reset = {k: getattr(default, k) for k in ELEMENT_KEYS}
            options = replace(options, **reset, element="seed")
        return replace(options, **changes)

    def applies(self, scene: Scene) -> str | None:
        """Why this model cannot solve ``scene`` (``None``: it can): the law's stiffening
        needs a tissue law, and an exponential stiffening a modulus the law gives."""
        law = scene.material.law
        if self.changes.get("stiffening") == "law" and law not in LAWS:
            return f'model {self.name}: stiffening = "law" needs a tissue law'
        try:
            opts = self.spring_options(scene)
        except (ValueError, TypeError) as exc:
            return f"model {self.name}: {exc}"
        if opts.stiffening == "law" and law not in LAWS:
            return f'model {self.name}: stiffening = "law" needs a tissue law'
        if opts.stiffening == "exponential" and opts.stiffening_modulus is None:
            own = LAWS[law].stiffening_modulus(scene.material.parameters) if law in LAWS else None
            if own is None:
                return f"model {self.name}: its stiffening needs a modulus the {law} law lacks"
        return None

    def solve_key(self, scene: Scene) -> Any:
        """What identifies its solve of ``scene`` (models with one key are one solve)."""
        return ("spring", repr(self.spring_options(scene)))

    def law_versus(self, scene: Scene, reference_law: str) -> str:
        """What it solves against the reference's law: ``same law`` (the tissue element
        against its tissue law), ``small-strain calibration`` or ``stiffened calibration``."""
        opts = self.spring_options(scene)
        if opts.stiffening == "law" and reference_law in TISSUE_LAWS:
            return "same law"
        return "small-strain calibration" if opts.stiffening == "off" else "stiffened calibration"

    def solve(self, scene: Scene, verbose: bool = False) -> ModelSolution:
        """The solve its options ask for (:func:`springmodel.model.solve_spring`)."""
        from .model import solve_spring

        why = self.applies(scene)
        if why is not None:
            raise InputError(why)
        return solve_spring(scene, self.spring_options(scene), verbose)

    def system(self, scene: Scene):
        """The spring model as a :class:`~springfem.mechanics.MechanicalSystem`."""
        from .model import SpringModel

        why = self.applies(scene)
        if why is not None:
            raise InputError(why)
        return SpringModel(scene, self.spring_options(scene))


#: The spring models, in the order the studies list them.
MODELS: tuple[SpringVariant, ...] = (
    SpringVariant("spring", "spring model (the scene's [spring] options)"),
    SpringVariant("spring-spec", "the specification's spring element", element=True),
    *(
        SpringVariant(name, label, changes, coupling=True, element=True, claims=claims)
        for name, label, changes, claims in (
            ("spring-exact", "exact spring element", EXACT, P1_TANGENT),
            ("spring-stiffened", "stiffened exact spring element", STIFFENED, P1_TANGENT),
            ("spring-tissue", "tissue spring element (Green torsion, the law's stiffening)",
             TISSUE, P1_TANGENT),
        )
    ),
    SpringVariant("spring-energy", "spring model, energy torsion", {"torsion": "energy"}),
    SpringVariant("spring-cosine", "spring model, cosine torsion", {"torsion": "cosine"}),
    *(
        SpringVariant(name, label, {**changes, **_NODAL}, coupling=True, element=True)
        for name, label, changes in (
            ("spring-stabilised", "exact spring element, stabilised nodal strain + nodal "
             "volume", EXACT),
            ("spring-tissue-stabilised", "tissue spring element, stabilised nodal strain + "
             "nodal volume", TISSUE),
        )
    ),
)  # fmt: skip
#: The scene's own spring model.
SPRING = MODELS[0]


def models() -> tuple[SpringVariant, ...]:
    """The spring models (the ``springfem.models`` entry point of this package)."""
    return MODELS
