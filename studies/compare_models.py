"""The models of ``springfem compare``: names, what each one solves, and the solve.

Models (names used in tables and figures)
-----------------------------------------
``spring``  the spring model with the scene's ``[spring]`` options;
``P1``, ``P2``  FEM on the scene's mesh. For a linear, transverse-linear or neo-Hookean
scene: linear (small-strain) FEM with the scene's linear law (``linear`` or
``transverse-linear``; ``linear`` with ``E, nu`` for a neo-Hookean scene). For a
finite-strain tissue law (:data:`TISSUE_LAWS`: Guccione, Holzapfel–Ogden) the scene's own
law (the table's ``law`` column names it): ``P2`` with the scene's ``[fem]`` formulation
(Taylor–Hood u–p when ``formulation = "mixed"``), ``P1`` in the displacement formulation
with the scene's ``kappa``, or for an incompressible material the penalty the spring model
uses (:func:`p1_penalty`);
``P1-NH``, ``P2-NH``  neo-Hookean FEM (the scene's formulation); not for tissue laws.

Examples
--------
>>> from springfem.mesh import box_mesh
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({"mesh": box_mesh((1.0, 1.0, 1.0), (1, 1, 1)),
...     "material": {"law": "guccione", "C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0,
...                  "incompressible": True},
...     "fem": {"order": 2, "formulation": "mixed"}})
>>> model_settings(scene, "P1"), model_settings(scene, "P2")
(('fem', 1, 'guccione'), ('fem', 2, 'guccione'))
>>> p1 = model_scene(scene, "P1")
>>> p1.material.incompressible, p1.material.parameters["kappa"] == p1_penalty(scene)
(False, True)
>>> FemOptions.of(p1).formulation, FemOptions.of(model_scene(scene, "P2")).formulation
('displacement', 'mixed')
"""

from __future__ import annotations

from dataclasses import replace

from reference_fem.options import FemOptions
from springfem.errors import InputError
from springfem.materials.tissue import TISSUE_LAWS
from springfem.scene import Scene

from .solve import Solution

MODELS = ("spring", "P1", "P2", "P1-NH", "P2-NH")
SPRING_PARALLEL_MIN_TETS = 200_000  # below this the serial spring kernel is faster


def is_tissue(scene: Scene) -> bool:
    """True when the scene's law is a finite-strain tissue law (:data:`TISSUE_LAWS`).

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
    """The small-strain law of the scene's material."""
    return "transverse-linear" if scene.material.law == "transverse-linear" else "linear"


def p1_penalty(scene: Scene) -> float:
    """Bulk modulus of the volumetric penalty of a tissue scene's P1 model (Pa).

    The scene's ``kappa`` if it has one; for an incompressible material the bulk modulus
    of its isotropic equivalent (``Material.kappa``: 1000 × the mean shear modulus of the
    law's small-strain tangent, :func:`springfem.scene.tissue.parse_tissue`), which is the
    penalty the spring model's calibration uses
    (:func:`springfem.materials.tissue_matrix`). Same-mesh P1 and the spring model then
    stand in for the incompressible law with the same volumetric stiffness, so P1 stays the
    spring model's like-for-like model-error reference.

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


def model_scene(scene: Scene, name: str) -> Scene:
    """The scene a model solves: ``scene`` itself except for the tissue FEM models.

    A tissue scene's ``P2`` is solved with its ``[fem]`` options at order 2 (its
    formulation kept), its ``P1`` in the displacement formulation at order 1 with the
    penalty :func:`p1_penalty` (P1 cannot be Taylor–Hood).

    Parameters
    ----------
    scene
        The scene.
    name
        A model name of :data:`MODELS`.

    Returns
    -------
    Scene
        A shallow copy with the model's material and ``[fem]`` options, or ``scene``.
    """
    if not is_tissue(scene) or name not in ("P1", "P2"):
        return scene
    fem = FemOptions.of(scene)
    if name == "P2":
        return scene.with_options(fem=replace(fem, order=2))
    mat = scene.material
    params = {**mat.parameters, "kappa": p1_penalty(scene)}
    fem = replace(fem, order=1, formulation="displacement")
    p1 = replace(scene, material=replace(mat, parameters=params, incompressible=False))
    return p1.with_options(fem=fem)


def model_settings(scene: Scene, name: str) -> tuple[str, int | None, str | None]:
    """``(model, order, law)`` of a model name for :func:`solve_model`.

    Parameters
    ----------
    scene
        The scene.
    name
        A model name of :data:`MODELS`.

    Returns
    -------
    tuple
        ``("spring", None, None)`` or ``("fem", order, law name)``.

    Raises
    ------
    InputError
        An unknown name, or a neo-Hookean model for a law it cannot stand for.
    """
    if name == "spring":
        return "spring", None, None
    if name in ("P1", "P2"):
        law = scene.material.law if is_tissue(scene) else linear_law(scene)
        return "fem", int(name[1]), law
    if name in ("P1-NH", "P2-NH"):
        if scene.material.law == "transverse-linear":
            raise InputError(
                f"model {name}: reference_fem has no anisotropic hyperelastic law for the "
                "transverse-linear material"
            )
        if is_tissue(scene):
            raise InputError(
                f"model {name}: neo-Hookean is not the scene's {scene.material.law} law; "
                "P1 and P2 solve that law"
            )
        return "fem", int(name[1]), "neo-hookean"
    raise InputError(f"unknown model {name!r}; valid models: {', '.join(MODELS)}")


def solve_model(scene: Scene, name: str) -> Solution:
    """Solve ``scene`` with one of :data:`MODELS`.

    Parameters
    ----------
    scene
        The scene.
    name
        A model name.

    Returns
    -------
    Solution
        Result, vertex displacements and cell data.

    Raises
    ------
    InputError, SolverError
        From the model.
    """
    model, order, law = model_settings(scene, name)
    if model == "spring":
        from springmodel.model import solve_spring

        parallel = scene.mesh.n_tets >= SPRING_PARALLEL_MIN_TETS
        sol = solve_spring(scene, parallel=parallel)
        return Solution(sol.result, sol.u, dict(sol.cell_data))
    import reference_fem

    sol = reference_fem.solve(model_scene(scene, name), order=order, law=law)
    return Solution(sol.result, sol.u_vertices, dict(sol.cell_data))


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
    p2 = FemOptions.of(model_scene(scene, "P2")).formulation
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
