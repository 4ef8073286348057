"""The law and ``[fem]`` formulation each FEM model (:mod:`reference_fem.plugin`) solves
on a scene.

A tissue scene's P2 model keeps the scene's ``[fem]`` options (its formulation); P1, which
cannot be Taylor–Hood, is the displacement formulation with the penalty
:func:`p1_penalty`, so that same-mesh P1 stays the spring model's like-for-like reference
(docs/studies.rst#the-model-registry).

Examples
--------
>>> from springfem.scene import load_scene
>>> scene = load_scene("land-beam")
>>> is_tissue(scene), tissue_scene(scene, 1).material.incompressible
(True, False)
"""

from __future__ import annotations

from dataclasses import replace

from springfem.materials.laws import TISSUE_LAWS, LawNames
from springfem.scene import Scene

from .options import FemOptions


def is_tissue(scene: Scene) -> bool:
    """True when the scene's law is a finite-strain tissue law (Guccione, Holzapfel–Ogden).

    Parameters
    ----------
    scene
        The scene.

    Returns
    -------
    bool
    """
    return scene.material.law in TISSUE_LAWS


def linear_law(scene: Scene) -> str:
    """The small-strain law of the scene's material (``linear`` or ``transverse-linear``).

    Parameters
    ----------
    scene
        The scene.

    Returns
    -------
    str
    """
    return "transverse-linear" if scene.material.law == "transverse-linear" else "linear"


def p1_penalty(scene: Scene) -> float:
    """Bulk modulus of the volumetric penalty of a tissue scene's P1 model.

    The scene's ``kappa`` if it has one; for an incompressible material the bulk modulus
    of its isotropic equivalent (``Material.kappa``: 1000 × the mean shear modulus of the
    law's small-strain tangent), which is the penalty the spring model's calibration uses.
    Same-mesh P1 and the spring model then stand in for the incompressible law with the
    same volumetric stiffness, so P1 stays the spring model's like-for-like reference.

    Parameters
    ----------
    scene
        A tissue scene.

    Returns
    -------
    float
    """
    kappa = float(scene.material.parameters.get("kappa", 0.0) or 0.0)
    return kappa if kappa > 0.0 else float(scene.material.kappa)


#: The laws the u–p formulations (``mixed``, ``mini``) take: the hyperelastic ones.
HYPERELASTIC = LawNames(("neo-hookean",))  # and every tissue law of the table
#: Formulations of linear tets only, and of P2 only.
LINEAR_TET_FORMULATIONS = ("nodal-volume", "nodal-strain", "mini")


def fitting_formulation(formulation: str, order: int | None, law: str) -> str:
    """The scene's ``[fem] formulation``, or the nearest one that an FEM model of ``order``
    and ``law`` can solve.

    A P1 model of a ``mixed`` (P2/P1) scene gets the P1 u–p pair (``mini``) for a
    hyperelastic law, else the nodal-strain tet (the locking-free linear tet that takes a
    small-strain law); a P2 model of a linear-tet scene (``nodal-volume``, ``nodal-strain``,
    ``mini``) gets ``mixed`` for a hyperelastic law, else the displacement formulation.

    Parameters
    ----------
    formulation
        The scene's ``[fem] formulation``.
    order
        The model's order (``None``: the scene's, which fits by construction).
    law
        The law the model solves (``linear``, ``neo-hookean``, a tissue law, ...).

    Returns
    -------
    str

    Examples
    --------
    >>> fitting_formulation("mixed", 1, "neo-hookean"), fitting_formulation("mixed", 1, "linear")
    ('mini', 'nodal-strain')
    >>> fitting_formulation("nodal-strain", 2, "guccione")
    'mixed'
    >>> fitting_formulation("mixed", 2, "linear")
    'displacement'
    """
    hyper = law.split("/")[0] in HYPERELASTIC
    if order == 1 and formulation == "mixed":
        return "mini" if hyper else "nodal-strain"
    if order == 2 and formulation in LINEAR_TET_FORMULATIONS:
        return "mixed" if hyper else "displacement"
    if not hyper and formulation in ("mixed", "mini"):
        return "nodal-strain" if order != 2 else "displacement"
    return formulation


def fitted_scene(scene: Scene, order: int | None, law: str) -> Scene:
    """``scene`` with the ``[fem] formulation`` an FEM model of ``order`` and ``law`` solves
    (:func:`fitting_formulation`; the scene itself when its own fits).

    Parameters
    ----------
    scene
        The scene.
    order, law
        The model's.

    Returns
    -------
    Scene
    """
    fem = FemOptions.of(scene)
    form = fitting_formulation(fem.formulation, order, law)
    if form == fem.formulation:
        return scene
    return scene.with_options(fem=replace(fem, formulation=form))  # type: ignore[arg-type]


def formulation_problem(scene: Scene, formulation: str, model_law: str) -> str | None:
    """Why an FEM model with ``[fem] formulation`` cannot solve ``scene``'s law (``None``:
    it can).

    Parameters
    ----------
    scene
        The scene.
    formulation
        The model's formulation.
    model_law
        The model's law setting (``scene``, ``neo-hookean`` or ``small-strain``).

    Returns
    -------
    str or None

    Examples
    --------
    >>> from springfem.scene import load_scene
    >>> formulation_problem(load_scene("cantilever"), "mini", "scene")
    'formulation mini needs a hyperelastic law (neo-hookean, guccione, holzapfel-ogden), not linear'
    """
    law: str = scene.material.law
    if model_law == "neo-hookean":
        law = "neo-hookean"
    elif model_law == "small-strain" and law not in TISSUE_LAWS:
        law = linear_law(scene)
    if formulation in ("mixed", "mini") and law not in HYPERELASTIC:
        return (
            f"formulation {formulation} needs a hyperelastic law ({', '.join(HYPERELASTIC)}), "
            f"not {law}"
        )
    if formulation in ("nodal-volume", "nodal-strain") and law == "transverse-linear":
        return f"formulation {formulation} needs an isotropic or hyperelastic law, not {law}"
    return None


def tissue_scene(scene: Scene, order: int | None) -> Scene:
    """The scene a tissue FEM model of ``order`` solves.

    P2 keeps the scene's ``[fem]`` options (its formulation); P1, which cannot be
    Taylor–Hood, is the displacement formulation with the penalty :func:`p1_penalty`.

    Parameters
    ----------
    scene
        A tissue scene.
    order
        1 or 2.

    Returns
    -------
    Scene
        A shallow copy with the model's material and ``[fem]`` options.
    """
    fem = FemOptions.of(scene)
    if order == 2:
        form = fitting_formulation(fem.formulation, 2, scene.material.law)
        return scene.with_options(fem=replace(fem, order=2, formulation=form))  # type: ignore[arg-type]
    mat = scene.material
    params = {**mat.parameters, "kappa": p1_penalty(scene)}
    p1 = replace(scene, material=replace(mat, parameters=params, incompressible=False))
    return p1.with_options(fem=replace(fem, order=1, formulation="displacement"))


def tissue_note(scene: Scene) -> str:
    """The note of a tissue comparison: which law and formulation each FEM model solves.

    Parameters
    ----------
    scene
        A tissue scene.

    Returns
    -------
    str
    """
    law = scene.material.law
    p2 = FemOptions.of(tissue_scene(scene, 2)).formulation
    p2_form = "mixed Taylor–Hood u–p" if p2 == "mixed" else "displacement formulation"
    if scene.material.incompressible:
        why = "1000 μ, the spring model's incompressible penalty"
    else:
        why = "the scene's kappa"
    return (
        f"finite-strain tissue law {law}: P1 and P2 solve it (P2 {p2_form}; P1 displacement "
        f"formulation, penalty kappa = {p1_penalty(scene):.4g} = {why}, so same-mesh P1 is "
        "the spring model's like-for-like model-error reference); P2 is the reference"
    )
