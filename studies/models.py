"""The models the studies weigh: one name, one label and one solve per model, in the one
registry of :mod:`springfem.model_api`.

Every comparison, sweep and study names its models here, so a model has one spelling in
the command line (``compare --models``), in tables, figures, sweep files and headline keys.
The models come from their packages: the spring models of :mod:`springmodel.plugin`, the
FEM orders and formulations of :mod:`reference_fem.plugin`, and the plug-ins (entry points
of group ``springfem.models``, :func:`springfem.model_api.register_model`), such as
``corotational``; :func:`plugins` lists those a study weighs without naming them. A model
declares what it applies to (``applies``, ``locking_free``, ``reference``, ``order`` ...:
:class:`springfem.model_api.ModelPlugin`), and the studies ask it
(:func:`springfem.model_api.declared`). Names are looked up case-insensitively (``p1`` is
``P1``); a misspelt name gets a "did you mean". Failures are caught in one place,
:func:`run`.

Examples
--------
>>> get("p1-nh").name, get("P1-NH").label
('P1-NH', 'FEM P1 neo-Hookean')
>>> get("spring-exact").changes
{'volume': 'axes', 'torsion': 'energy', 'calibration': 'exact'}
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({"mesh": {"generator": "box", "size": [0.1, 0.01, 0.01],
...     "divisions": [4, 1, 1]}, "material": {"law": "linear", "E": 1e4, "nu": 0.3},
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
...     "load": [{"type": "traction", "region": "x_max", "value": [0, 0, -0.1]}]})
>>> [run(scene, m).status for m in ("spring-exact", "P1")]
['ok', 'ok']
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

import reference_fem.plugin as fem_models
import springmodel.plugin as spring_models
from springfem.api import get_model
from springfem.errors import SolverError
from springfem.mechanics.limits import SolveStopped
from springfem.model_api import ModelPlugin, declared, plugin_models, register_model
from springfem.plausibility import check_solution
from springfem.scene import Scene

from .partial import partial_solution

#: A model of the registry (any :class:`~springfem.model_api.ModelPlugin`).
Model = ModelPlugin
# the in-house models, whether or not the installed metadata names their entry points yet
register_model(spring_models.MODELS)
register_model(fem_models.MODELS)
SPRING = spring_models.SPRING
EXACT, STIFFENED, TISSUE = spring_models.EXACT, spring_models.STIFFENED, spring_models.TISSUE
FEM, P1, P2, P1_NH, P2_NH = (fem_models.FEM, fem_models.P1, fem_models.P2, fem_models.P1_NH,
                             fem_models.P2_NH)  # fmt: skip


def spring_variant(
    name: str, label: str, coupling: bool = False, element: bool = False, **changes: Any
) -> Model:
    """Register a spring model: the scene's ``[spring]`` options with ``changes``
    (:class:`springmodel.plugin.SpringVariant`).

    Parameters
    ----------
    name
        ``spring-<variant>``.
    label
        Its label.
    coupling
        Add the Poisson-coupling springs for an anisotropic law.
    element
        The model defines the whole element.
    **changes
        Spring options.

    Returns
    -------
    Model
    """
    known = plugin_models().get(name)
    if known is not None:
        return known
    m = spring_models.SpringVariant(name, label, changes, coupling=coupling, element=element)
    return register_model(m)[0]


def fem_variant(name: str, label: str, order: int, formulation: str, **fem: Any) -> Model:
    """Register an FEM model of the scene's own law with ``[fem] formulation``
    (:class:`reference_fem.plugin.FemModel`; a registered name is returned as is).

    Returns
    -------
    Model
    """
    known = plugin_models().get(name)
    if known is not None:
        return known
    options = {"order": order, "formulation": formulation, **fem}
    m = fem_models.FemModel(name, label, order=order, law="scene", fem=options)
    return register_model(m)[0]


def get(name: str | Model) -> Model:
    """The registered model ``name`` (case-insensitive; :func:`springfem.api.get_model`).

    Parameters
    ----------
    name
        A model name, or a model (returned as is).

    Returns
    -------
    Model

    Raises
    ------
    InputError
        Unknown name: the message suggests the closest and lists the valid ones.
    """
    return get_model(name)


def solve_model(model: Model, scene: Scene, verbose: bool = False) -> Any:
    """The solve :func:`run` makes by default: ``model.solve(scene, verbose)``."""
    return model.solve(scene, verbose)


def system(model: Model, scene: Scene):
    """The model's explicit form on ``scene``.

    Raises
    ------
    InputError
        It has none on this scene (the model says why).
    """
    from springfem.errors import InputError

    why = model.applies(scene)
    got = model.system(scene) if why is None else None
    if got is None:
        raise InputError(why or f"model {model.name}: no explicit form")
    return got


@dataclass
class Outcome:
    """What :func:`run` got from one model on one scene.

    Attributes
    ----------
    model
        The model.
    status
        ``ok``, ``implausible`` (solved, but :func:`springfem.plausibility.check_solution`
        found the state implausible: ``message`` says why), ``partial`` (a load-stepped
        solve stopped part way: ``solution`` is the state at ``load_factor``) or
        ``failed``.
    solution
        The solution (``ok``: a :class:`~springfem.model_api.ModelSolution`, or what a study's own
        solve returned) or the partial state (``partial``); ``None`` when failed.
    message
        Why it failed or stopped (empty when ok).
    seconds
        Wall time of the attempt.
    """

    model: Model
    status: Literal["ok", "implausible", "partial", "failed"]
    solution: Any = None
    message: str = ""
    seconds: float = float("nan")

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    @property
    def solved(self) -> bool:
        """Solved to full load (``ok`` or ``implausible``)."""
        return self.status in ("ok", "implausible")

    @property
    def load_factor(self) -> float:
        """The load reached: 1 when ok, the partial state's, NaN when failed."""
        if self.solved:
            return 1.0
        if self.solution is not None:
            return float(self.solution.result.info.get("load_factor", np.nan))
        return float("nan")

    @property
    def u(self) -> np.ndarray | None:
        return None if self.solution is None else self.solution.u


def run(
    scene: Scene,
    model: str | Model,
    solve: Callable[[Model, Scene], Any] | None = None,
    verbose: bool = False,
    check: bool = False,
) -> Outcome:
    """Solve ``scene`` with ``model``; a solver failure is an outcome, not an exception.

    Parameters
    ----------
    scene
        The scene.
    model
        A model or its name.
    solve
        How to solve (default :func:`solve_model`): a study's own solver settings; what it
        returns is the outcome's ``solution``.
    verbose
        Solver progress on stderr (the default solve).
    check
        Check a solved state's plausibility (:func:`springfem.plausibility.check_solution`:
        ``J``, volume change, small strain, displacement): ``implausible`` when it fails.

    Returns
    -------
    Outcome
        ``ok``; ``implausible`` (with ``check``); ``partial`` with the last converged
        state when a load-stepped solve stopped part way (a solver failure, or a cap of
        :func:`springfem.mechanics.limits.solve_limits`); ``failed`` with the message.

    Raises
    ------
    InputError
        Unknown model, or one that does not apply to the scene: bad input, not a failure.
    """
    m = get(model)
    t0 = time.perf_counter()
    try:
        sol = solve(m, scene) if solve is not None else solve_model(m, scene, verbose)
    except (SolverError, SolveStopped) as exc:  # a stop by a cap is kept like a failure
        seconds = time.perf_counter() - t0
        state = partial_solution(scene, declared(m, "result_model", default="plugin"), exc, seconds)
        status: Literal["partial", "failed"] = "partial" if state is not None else "failed"
        return Outcome(m, status, state, str(exc), seconds)
    seconds = time.perf_counter() - t0
    if check and getattr(sol, "u", None) is not None:
        findings = check_solution(scene, sol.u, sol.result.law)
        if findings:
            return Outcome(m, "implausible", sol, "; ".join(f.line for f in findings), seconds)
    return Outcome(m, "ok", sol, "", seconds)


#: The models a verdict weighs on a user's scene: the scene's own spring model, the three
#: spring elements and the FEM of the scene's law (the torsion variants and the studies'
#: own variants are the studies' business).
PRIMARY = (
    "spring",
    "spring-spec",
    "spring-exact",
    "spring-stiffened",
    "P1",
    "P2",
    "P1-NH",
    "P2-NH",
)


def sync_plugins() -> list[Model]:
    """The plug-in models: those of packages other than the spring model's and the FEM's,
    in registration order.

    Returns
    -------
    list of Model
    """
    from springfem.model_api import plugin_module

    own = ("springmodel", "reference_fem")
    return [m for m in plugin_models().values() if plugin_module(m) not in own]


def plugins(scene: Scene | None = None, explicit: bool = False) -> list[str]:
    """The models a study weighs without naming them (``default``) on ``scene``.

    Parameters
    ----------
    scene
        Only those that apply to it (``None``: all).
    explicit
        Only those with an explicit form on ``scene`` (a mechanical system).

    Returns
    -------
    list of str
    """
    out = []
    for m in plugin_models().values():
        if not m.default:
            continue
        if scene is not None and m.applies(scene) is not None:
            continue
        if explicit and scene is not None:
            try:
                system(m, scene)
            except Exception:  # noqa: BLE001 - no explicit form on this scene
                continue
        out.append(m.name)
    return out
