"""The models from Python: list them, get one by name, solve a scene with it.

Every model — each spring element and variant, each FEM order and formulation, each
plug-in — is a model of the one registry of :mod:`springfem.model_api`, and its solve
returns one type, :class:`~springfem.model_api.ModelSolution`. :func:`solve` adds the
warnings the command line prints about the solved state
(:func:`springfem.plausibility.check_solution`, and the model's own, such as the spring
model's calibration warnings). The manual walks through it (docs/usage.rst#python-api).

Examples
--------
>>> names = models()  # also springfem.models(), springfem.get_model(), springfem.solve()
>>> {"spring-exact", "P1", "fem-P2-mixed", "corotational"} <= set(names)
True
>>> get_model("p1-nh").name, get_model("fem-MINI").locking_free
('P1-NH', True)
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({"mesh": {"generator": "box", "size": [0.1, 0.01, 0.01],
...     "divisions": [4, 1, 1]}, "material": {"law": "linear", "E": 1e4, "nu": 0.3},
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
...     "load": [{"type": "traction", "region": "x_max", "value": [0, 0, -0.1]}]})
>>> sol = solve(scene, "spring-exact")
>>> sol.result.model, sol.u.shape, sol.warnings
('spring', (20, 3), [])
"""

from __future__ import annotations

from .errors import InputError
from .model_api import ModelPlugin, ModelSolution, plugin_models
from .plausibility import check_solution
from .scene import Scene
from .scene.reader import suggestion


def models() -> dict[str, ModelPlugin]:
    """The registered models by name: the installed packages' entry points (the spring
    models, the FEM models, the plug-ins) and those of
    :func:`~springfem.model_api.register_model`.

    Returns
    -------
    dict
    """
    return plugin_models()


def get_model(name: str | ModelPlugin) -> ModelPlugin:
    """The registered model ``name`` (case-insensitive; a model is returned as is).

    Parameters
    ----------
    name
        A model name (``spring-exact``, ``P2``, ``fem-P2-mixed``, ``xpbd`` ...).

    Returns
    -------
    ModelPlugin

    Raises
    ------
    InputError
        Unknown name: the message suggests the closest and lists the valid ones.
    """
    if not isinstance(name, str):
        return name
    known = models()
    for key, model in known.items():
        if key.lower() == name.lower():
            return model
    near = suggestion(name, known)
    hint = f" (did you mean {near}?)" if near else ""
    raise InputError(f"unknown model {name!r}{hint}; valid models: {', '.join(known)}")


def warnings(scene: Scene, solution: ModelSolution) -> list[str]:
    """The warnings about a solved state: the model's own (``result.info["warnings"]``)
    and the implausible quantities (:func:`springfem.plausibility.check_solution`).

    Parameters
    ----------
    scene
        The scene solved.
    solution
        Its solution.

    Returns
    -------
    list of str
    """
    own = [str(w) for w in solution.result.info.get("warnings", None) or ()]
    return own + [f.line for f in check_solution(scene, solution.u, solution.result.law)]


def solve(
    scene: Scene, model: str | ModelPlugin = "spring", verbose: bool = False
) -> ModelSolution:
    """The static solution of ``scene`` by ``model``, with its warnings.

    Parameters
    ----------
    scene
        The scene (:func:`springfem.scene.load_scene`, :func:`~springfem.scene.scene_from_dict`).
    model
        A model name or a model (:func:`models`).
    verbose
        Solver progress on stderr.

    Returns
    -------
    ModelSolution
        Its ``warnings`` are those the command line prints (:func:`warnings`).

    Raises
    ------
    InputError
        Unknown model, or one that does not apply to the scene.
    SolverError
        The solve failed (``state``: the last good displacement).
    """
    m = get_model(model)
    why = m.applies(scene)
    if why is not None:
        raise InputError(why)
    sol = m.solve(scene, verbose)
    sol.warnings = warnings(scene, sol)
    return sol
