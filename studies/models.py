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
:func:`run`. Which models a verdict, a comparison and a sweep weigh on a scene, and what
each solves:

- :func:`locking_free_models`: on a nearly incompressible scene
  (:func:`springfem.plausibility.nearly_incompressible`: ν ≥ 0.45, κ > 10 μ or an
  incompressible flag) the locking-free methods of :data:`LOCKING_FREE` that
  apply to its law: nodal-strain and nodal-volume P1, MINI, the stabilised spring elements
  and P2/P1 mixed, which is then the reference of a neo-Hookean or tissue law
  (:func:`mixed_reference`, with the one-line :func:`locking_note`).
- :func:`same_solves`: models whose options resolve to the same solve on the scene (the
  scene's own spring element and a named one, ``P2-NH`` of a mixed scene and
  ``fem-P2-mixed``), to be solved once.
- :func:`formulation_notes`: the FEM rows whose order the scene's ``[fem] formulation`` does
  not fit, and the formulation they solve instead
  (:func:`reference_fem.fitting.fitting_formulation`).
- :func:`law_versus`: whether a model solves the reference's law, or a small-strain law or
  calibration of it (a speed is compared like for like only in the first case).
- :func:`reference_model`: the reference the verdict, the comparisons and the studies take.

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
>>> from springfem.scene import load_scene
>>> beam = load_scene("land-beam")  # incompressible Guccione, [fem] formulation = "mixed"
>>> locking_free_models(beam)[:3], mixed_reference(beam)
(['fem-P1-nodal-strain', 'fem-P1-nodal-volume', 'fem-MINI'], 'fem-P2-mixed')
>>> same_solves(beam, ["P2", "fem-P2-mixed"])  # the scene's P2 is P2/P1 mixed already
{'fem-P2-mixed': 'P2'}
>>> locking_free_models(load_scene("cantilever"))  # nu = 0.3
[]
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

import reference_fem.plugin as fem_models
import springmodel.plugin as spring_models
from reference_fem.fitting import HYPERELASTIC, is_tissue
from reference_fem.options import FemOptions
from reference_fem.plugin import SMALL_STRAIN_LAWS
from springfem.api import get_model
from springfem.errors import SolverError
from springfem.mechanics.limits import SolveStopped
from springfem.model_api import ModelPlugin, declared, plugin_models, register_model
from springfem.plausibility import check_solution, nearly_incompressible
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
    stopped
        Ended by a cap of :func:`springfem.mechanics.limits.solve_limits`, not the solver.
    """

    model: Model
    status: Literal["ok", "implausible", "partial", "failed"]
    solution: Any = None
    message: str = ""
    seconds: float = float("nan")
    stopped: bool = False  # ended by a cap (time, steps), not by the solver

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
        return Outcome(m, status, state, str(exc), seconds, isinstance(exc, SolveStopped))
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


# -- the models a scene calls for ----------------------------------------------------------

#: The P2/P1 mixed reference of a nearly incompressible hyperelastic scene.
MIXED = "fem-P2-mixed"
#: The largest principal Green–Lagrange strain of the small-strain P1 solution above which
#: a neo-Hookean or tissue reference is needed.
LARGE_STRAIN = 0.05


def locking_free_models(scene: Scene) -> list[str]:
    """The models of :data:`LOCKING_FREE` that apply to ``scene`` when it is
    nearly incompressible (else none).

    Parameters
    ----------
    scene
        The scene.

    Returns
    -------
    list of str
    """
    if not nearly_incompressible(scene):
        return []
    found = [m for m in plugin_models().values() if declared(m, "locking_free")]
    rank = {n: i for i, n in enumerate(LOCKING_FREE)}
    found.sort(key=lambda m: rank.get(m.name, len(rank)))
    return [m.name for m in found if m.applies(scene) is None
            and (m.name in rank or m.default)]  # fmt: skip


def mixed_reference(scene: Scene) -> str | None:
    """``fem-P2-mixed`` when it is the scene's reference: a nearly incompressible scene of
    a hyperelastic law (neo-Hookean, Guccione, Holzapfel–Ogden), on which P1 and the
    displacement P2 lock; else ``None``.

    Parameters
    ----------
    scene
        The scene.

    Returns
    -------
    str or None
    """
    if scene.material.law in HYPERELASTIC and MIXED in locking_free_models(scene):
        return MIXED
    return None


def reference_model(scene: Scene, p1_strain: float, large: float = LARGE_STRAIN) -> str:
    """The scene's reference, which the verdict, the comparisons and every study take:
    P2/P1 mixed on a nearly incompressible hyperelastic scene (:func:`mixed_reference`),
    else P2 of its law (neo-Hookean when it is, or at large strain).

    Parameters
    ----------
    scene
        The scene.
    p1_strain
        The largest principal Green–Lagrange strain of its small-strain P1 solution
        (:func:`studies.metrics.max_principal_strain`; ignored on a mixed scene).
    large
        The strain above which the reference is finite-strain (:data:`LARGE_STRAIN`).

    Returns
    -------
    str

    Examples
    --------
    >>> from springfem.scene import load_scene
    >>> beam, cantilever = load_scene("land-beam"), load_scene("cantilever")
    >>> [reference_model(s, e) for s, e in ((beam, 0.0), (cantilever, 0.01), (cantilever, 0.1))]
    ['fem-P2-mixed', 'P2', 'P2-NH']
    """
    mixed = mixed_reference(scene)
    if mixed is not None:
        return mixed
    if is_tissue(scene) or scene.material.law == "transverse-linear":
        return "P2"
    if scene.material.law == "neo-hookean" or p1_strain > large:
        return "P2-NH"
    return "P2"


def locking_note(
    scene: Scene, weighed: Sequence[str], reference: str | None, mixed: bool | None = None
) -> str:
    """One line: why the locking-free methods are weighed and which is the reference.

    Parameters
    ----------
    scene
        The scene.
    weighed
        The locking-free models weighed.
    reference
        The reference model.
    mixed
        Whether the reference is P2/P1 mixed (default: it is ``fem-P2-mixed``); a row
        that is the same solve, such as ``P2-NH`` of a mixed scene, may stand for it.

    Returns
    -------
    str
    """
    mat = scene.material
    nu = getattr(mat, "nu", None)
    if mat.incompressible:
        why = "incompressible material"
    elif nu is not None and nu >= 0.45:
        why = f"nu = {nu:.4g} >= 0.45"
    else:
        why = f"kappa = {mat.kappa / mat.mu:.3g} mu"
    ref = (
        f"P2/P1 mixed ({reference}) is the reference, as P1 and displacement P2 lock"
        if (reference == MIXED if mixed is None else mixed)
        else f"the reference is {reference} (P2/P1 mixed takes no {mat.law} law)"
    )
    others = ", ".join(n for n in weighed if n != MIXED)
    return f"nearly incompressible ({why}): " + (f"{others} weighed too; " if others else "") + ref


def same_solves(scene: Scene, names: Sequence[str]) -> dict[str, str]:
    """Models whose options resolve to the same solve on ``scene``: name -> the first one.

    Parameters
    ----------
    scene
        The scene.
    names
        Model names.

    Returns
    -------
    dict
    """
    seen: dict[Any, str] = {}
    alias = {}
    for n in names:
        try:
            m = get(n)
            key = declared(m, "solve_key", scene, default=("plugin", m.name))
        except Exception:  # noqa: BLE001 - a model that cannot be set up is solved (and fails) alone
            continue
        if key in seen:
            alias[n] = seen[key]
        else:
            seen[key] = n
    return alias


def formulation_notes(scene: Scene, names: Sequence[str]) -> list[str]:
    """Notes on the FEM rows that solve another formulation than the scene's ``[fem]
    formulation``, which does not fit their order or law
    (:func:`reference_fem.fitting.fitting_formulation`).

    Parameters
    ----------
    scene
        The scene.
    names
        Model names.

    Returns
    -------
    list of str

    Examples
    --------
    >>> from springfem.scene import scene_from_dict
    >>> s = scene_from_dict({"mesh": {"generator": "box", "size": [1, 1, 1],
    ...     "divisions": [1, 1, 1]}, "material": {"law": "neo-hookean", "E": 1.0, "nu": 0.49},
    ...     "fem": {"formulation": "mixed", "order": 2}})
    >>> print(formulation_notes(s, ["P1", "P2", "P1-NH", "P2-NH"])[0])
    ... # doctest: +NORMALIZE_WHITESPACE
    the scene's [fem] formulation "mixed" (P2/P1, hyperelastic laws) does not fit every row:
    P1 solves "nodal-strain", P2 "displacement", P1-NH "mini" (the nearest of their order and
    law)
    """
    own = FemOptions.of(scene).formulation
    changed = []
    for n in names:
        m = get(n)
        if getattr(m, "fem_law", "scene") == "scene" or m.applies(scene) is not None:
            continue  # not an FEM, or an FEM of the scene's own formulation
        if m.order == 1 and is_tissue(scene):
            continue  # a tissue law's P1 is displacement P1 with a penalty (fitting.tissue_note)
        form = m.fem_options(scene).formulation
        if form != own:
            changed.append((n, form, m.order))
    if not changed:
        return []
    rows = ", ".join(f'{n} "{f}"' for n, f, _ in changed)
    what = {"mixed": " (P2/P1, hyperelastic laws)", "mini": " (P1-bubble/P1, hyperelastic laws)"}
    return [
        f'the scene\'s [fem] formulation "{own}"{what.get(own, " (linear tets)")} does not fit '
        f"every row: {rows.replace(' ', ' solves ', 1)} (the nearest of their order and law)"
    ]


def law_versus(scene: Scene, name: str, reference_law: str) -> str:
    """What model ``name`` solves, against the reference's law: ``same law``, ``small-strain
    law`` (linear FEM against a hyperelastic reference), ``small-strain calibration`` or
    ``stiffened calibration`` (a spring element calibrated to the law's small-strain
    tangent, plain or exponentially stiffened, against a finite-strain law: only the tissue
    element equals a tissue law at finite strain), ``own law (...)`` (a plug-in model's own
    law, such as XPBD's stable neo-Hookean energy), or ``other law``.

    Parameters
    ----------
    scene
        The scene.
    name
        The model.
    reference_law
        The reference's ``Result.law`` (``neo-hookean/coupled/mixed-P2P1``, ``linear``, ...).

    Returns
    -------
    str

    Examples
    --------
    >>> from springfem.scene import load_scene
    >>> beam = load_scene("land-beam")
    >>> [law_versus(beam, n, "guccione/mixed-P2P1") for n in
    ...  ("P1", "spring-exact", "spring-tissue")]
    ['same law', 'small-strain calibration', 'same law']
    """
    ref = reference_law.split("/")[0]
    m = get(name)
    if ref in SMALL_STRAIN_LAWS or not ref:
        return "same law"
    versus = declared(m, "law_versus", scene, ref)
    if versus is not None:
        return versus
    own = declared(m, "law")  # a plug-in's own law, when it names one
    return "same law" if own == ref else f"own law ({own})" if own else "own law"


#: What a verdict, a comparison and a sweep weigh as well on a nearly incompressible scene
#: (:func:`springfem.plausibility.nearly_incompressible`): the locking-free P1 tets, the
#: stabilised spring elements and the P2/P1 mixed reference (docs/studies.rst#the-verdict).
LOCKING_FREE = (
    "fem-P1-nodal-strain",
    "fem-P1-nodal-volume",
    "fem-MINI",
    "spring-stabilised",
    "spring-tissue-stabilised",
    "fem-P2-mixed",
)


def candidates() -> tuple[str, ...]:
    """The models a verdict weighs: :data:`studies.PRIMARY` and the default plug-ins."""
    return PRIMARY + tuple(plugins())
