"""Cases of the speed-accuracy study: settings, the methods, the points of a scene, one
timed solve.

A method is a model of :mod:`studies.models` and a solution method, ``"<model>
<solution>"``: ``static`` (FEM models' own solve; spring models by Newton to
:data:`STATIC_TOL`), ``implicit`` (backward-Euler pseudo-time stepping to rest, ``dt`` a
multiple of the critical step) or ``explicit`` (dynamic relaxation to rest,
:func:`springfem.mechanics.explicit_static`). The plug-in models that apply get ``static``
points and, with an explicit form, ``explicit`` ones; a plug-in with a ``sweep`` of its own
settings (XPBD's substeps x iterations) a ``static`` point per entry (:func:`method_name`).
A case is the scene's :meth:`~studies.scenes.StudyScene.case` with ``model``, ``solution``,
``factor`` (the level) and ``setting`` (a sweep point's model settings under ``"model"``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from springfem.errors import InputError, SolverError
from springfem.model_api import declared
from springfem.result import Result
from springfem.scene import Scene

from .. import models
from .. import study_convergence as convergence
from ..scenes import StudyScene
from ..solve import Solution
from ..study_convergence.levels import case_level, coarse_index

VERSION = 3
#: Static and implicit tolerances (relative residual).
STATIC_TOL = 1e-8
IMPLICIT_TOL = 1e-6
STEP_REPEATS = 7
STEP_COUNT = 20
#: The spring model (energy torsion: conservative, so static Newton has an analytic Hessian
#: and explicit dynamics conserve energy) and the exact element.
SPRING, EXACT = "spring-energy", "spring-exact"
#: The static FEM models (those that apply to the scene's law).
FEM_STATIC = ("P1", "P1-NH", "P2", "P2-NH")
#: The FEM model of the explicit runs (the explicit P1 FEM).
EXPLICIT_FEM = "P1-NH"
L2 = "L2 err (level-1 vertices)"
#: The column of the error against P1-NH static on the same level (a P1 model's error
#: against the Newton answer of its own mesh, e.g. XPBD's substep error).
SAME = "L2 vs P1-NH same mesh"


@dataclass(frozen=True)
class Settings:
    """Levels and solver settings of the speed-accuracy study: the refinement ``levels`` (a
    point per method each), the ``reference`` level (a scene that cannot take it: its
    finest), the ``explicit`` runs' ``(tol, dt_safety)``, the ``implicit`` runs' time-step
    factor -> the largest level it runs on, ``max_tets`` (larger levels are left out, the two
    coarsest always run), ``max_error`` (the tolerance of the cheapest points the findings
    name, ``--tolerance``), the first ``sweep`` entries of a plug-in's sweep (``None``: all)
    and ``sweep_levels``, the largest level its later entries run on (XPBD's static answer
    takes minutes at 80 substeps on level 4)."""

    levels: tuple[int, ...] = (1, 2, 4)
    reference: int = 6
    explicit: tuple[tuple[float, float], ...] = ((1e-3, 0.3), (1e-6, 0.3), (1e-6, 0.5))
    implicit: dict[float, int] = field(default_factory=lambda: {100.0: 2, 1e4: 4})
    max_tets: int = 40_000
    max_error: float = 0.05
    sweep: int | None = None
    sweep_levels: int | None = 2

    @classmethod
    def full(cls) -> Settings:
        """Levels 1, 2, 4 and the reference at 6."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """Levels 1, 2 and the reference at 4, one explicit setting."""
        return cls(levels=(1, 2), reference=4, explicit=((1e-6, 0.5),),
                   implicit={100.0: 1, 1e4: 2}, max_tets=5_000, sweep=2,
                   sweep_levels=None)  # fmt: skip


def bundled_scenes(settings: Settings) -> list[StudyScene]:
    """The convergence study's bar (:func:`studies.study_convergence.bundled_scenes`): its
    levels 1, 2, 4 and the reference 6 are 10x1x1, 20x2x2, 40x4x4 and 60x6x6 hexahedra.
    """
    return convergence.bundled_scenes(convergence.Settings())


def reference_model(law: str) -> str:
    """P2 with the scene's law (:func:`studies.study_convergence.fem_models`)."""
    return convergence.fem_models(law)[1]


def method_name(model: str, solution: str, setting: dict | None = None) -> str:
    """A method's one spelling: the registry's model name, a sweep point's model settings
    (their values joined by ``x``) and the solution method.

    Examples
    --------
    >>> method_name("xpbd", "static", {"model": {"substeps": 20, "iterations": 2}})
    'xpbd 20x2 static'
    >>> method_name("P1", "static", {"tol": 1e-8})
    'P1 static'
    """
    own = (setting or {}).get("model")
    tag = f" {'x'.join(map(str, own.values()))}" if own else ""
    return f"{model}{tag} {solution}"


def sweep(model: str, q: Settings) -> tuple[dict, ...]:
    """A plug-in's sweep (its optional ``sweep`` attribute; ``()``: none), the first
    ``q.sweep`` entries."""
    got = tuple(dict(s) for s in getattr(models.get(model), "sweep", None) or ())
    return got if q.sweep is None else got[: q.sweep]


def with_settings(m: models.Model, own: dict | None) -> models.Model:
    """The plug-in model ``m`` with its own settings changed (``own`` empty: ``m``)."""
    if not own:
        return m
    if not hasattr(m, "with_settings"):
        raise InputError(f"model {m.name} takes no settings of its own (no with_settings)")
    return m.with_settings(**own)


def explicit_fem_refusal(scene: Scene) -> str | None:
    """Why the explicit P1 FEM cannot run the scene (``None``: it can)."""
    m = models.get(EXPLICIT_FEM)
    why = m.applies(scene)
    if why is None:
        try:
            m.system(scene)
        except InputError as exc:
            why = str(exc)
    return why


def points(s: StudyScene, scene: Scene, levels: list[int], q: Settings) -> list[dict]:
    """Every (method, level, setting) point of a scene (``scene``: it built, level 1)."""
    fem = [m for m in FEM_STATIC if models.get(m).applies(scene) is None]
    explicit_fem = explicit_fem_refusal(scene) is None
    peers, peers_explicit = models.plugins(scene), models.plugins(scene, explicit=True)
    out = []
    for k in levels:

        def add(model: str, solution: str, **setting: float) -> None:
            out.append(point_case(s, model, solution, k, setting))  # noqa: B023

        for m in fem:
            add(m, "static")
        add(SPRING, "static", tol=STATIC_TOL)
        add(EXACT, "static", tol=STATIC_TOL)
        for factor, largest in q.implicit.items():
            if k <= largest:
                add(SPRING, "implicit", dt_factor=factor, tol=IMPLICIT_TOL)
        for tol, safety in q.explicit:
            add(SPRING, "explicit", tol=tol, dt_safety=safety)
            if explicit_fem:
                add(EXPLICIT_FEM, "explicit", tol=tol, dt_safety=safety)
        tol, safety = q.explicit[-1]  # the exact element: the last explicit setting only
        add(EXACT, "explicit", tol=tol, dt_safety=safety)
        for m in peers:  # the plug-in models: a point per sweep entry, or one
            for j, own in enumerate(sweep(m, q) or [None]):
                if j == 0 or q.sweep_levels is None or k <= q.sweep_levels:
                    out.append(point_case(s, m, "static", k, {"model": own} if own else {}))
        for m in peers_explicit:
            add(m, "explicit", tol=tol, dt_safety=safety)
    return out


def point_case(s: StudyScene, model: str, solution: str, factor: int, setting: dict) -> dict:
    """The cache case of one point."""
    return s.case("speed_accuracy", VERSION, kind="point", model=model, solution=solution,
                  factor=factor, setting=setting)  # fmt: skip


def _trajectory(scene: Scene, m: models.Model, u: np.ndarray, facts: dict) -> Solution:
    """A :class:`Solution` of a run to rest: its probes and solver facts."""
    kind = declared(m, "result_model", default="plugin")
    res = Result(scene=scene.name, model=kind, element=m.name, law=scene.material.law,
                 counts={"nodes": scene.mesh.n_points, "tets": scene.mesh.n_tets},
                 probes=scene.probe_displacements(u), volume={}, reactions={},
                 wall_time=float("nan"), converged=True,
                 iterations=int(facts.get("iterations", 0)), info=facts)  # fmt: skip
    return Solution(res, u)


def solver(solution: str, setting: dict):
    """``solve(model, scene) -> Solution`` of a solution method (``static``, ``implicit`` or
    ``explicit``) with its ``setting`` (``tol``, ``dt_factor``, ``dt_safety``), for
    :func:`models.run`.
    """
    from springfem.mechanics import explicit_static, implicit, stable_time_step

    def static(m: models.Model, scene: Scene) -> Solution:
        opts = declared(m, "spring_options", scene)
        if opts is None:  # not a spring model: its own static solve
            return with_settings(m, setting.get("model")).solve(scene)
        from springmodel.model import solve_spring

        opts = replace(opts, solver="static", tol=setting["tol"])
        sol = solve_spring(scene, opts, parallel=None)
        return Solution(sol.result, sol.u)

    def to_rest(m: models.Model, scene: Scene) -> Solution:
        system = m.system(scene)
        if solution == "implicit":
            dt = setting["dt_factor"] * stable_time_step(system)[0]
            traj = implicit(system, dt=dt, steps=5000, equilibrium_tol=setting["tol"])
            if not traj.converged:
                raise SolverError(traj.message, state=traj.x - system.x0)
            facts = {"steps": traj.steps, "iterations": traj.iterations}
            return _trajectory(scene, m, traj.x - system.x0, facts)
        info = explicit_static(system, tol=setting["tol"], dt_safety=setting["dt_safety"],
                               max_steps=400_000)  # fmt: skip
        return _trajectory(scene, m, info.x - system.x0, {"steps": info.steps, "dt": info.dt})

    return static if solution == "static" else to_rest


_WARM: set[tuple[str, str]] = set()


def _warm_up(model: str, solution: str, setting: dict) -> None:
    """Run a method once on a tiny bar so compilation and imports are not timed."""
    if (model, solution) in _WARM:
        return
    tiny = StudyScene.bundled("cantilever", {"mesh.divisions": [4, 1, 1]}).build()
    loose = dict(setting, tol=1e-2) if "tol" in setting else setting
    models.run(tiny, model, solve=solver(solution, loose))
    _WARM.add((model, solution))


def point_work(case: dict) -> dict:
    """One timed point: wall and CPU time from the scene to the answer, probes, the field at
    the level-1 vertices."""
    scene = case_level(case)
    _warm_up(case["model"], case["solution"], case["setting"])
    c0 = time.process_time()
    got = models.run(scene, case["model"], solve=solver(case["solution"], case["setting"]))
    out = {"seconds": got.seconds, "cpu_seconds": time.process_time() - c0,
           "tets": scene.mesh.n_tets}  # fmt: skip
    if not got.ok:
        msg = got.message
        status = "blew up" if "blew up" in msg or "inverted" in msg else "failed"
        return {**out, "status": status, "message": msg[:240]}
    r = got.solution.result
    facts = {k: r.info[k] for k in ("steps", "dt") if k in r.info and case["solution"] != "static"}
    return {**out, "status": "ok", "probes": r.probes,
            "u": np.asarray(got.u)[coarse_index(case, scene.mesh)], "iterations": r.iterations,
            **facts}  # fmt: skip


def step_count(n_tets: int) -> int:
    """Explicit steps per timed repeat: about 0.2 M element evaluations (>~10 ms)."""
    return int(np.clip(200_000 // max(n_tets, 1), STEP_COUNT, 500))


def step_cost_case(s: StudyScene, factor: int, n_tets: int) -> dict:
    """The cache case of the step costs on one level."""
    return s.case("speed_accuracy", VERSION, kind="step_cost", factor=factor,
                  repeats=STEP_REPEATS, steps=step_count(n_tets))  # fmt: skip


def step_cost_work(case: dict) -> dict:
    """Cost of one explicit step, the spring model and the explicit P1 FEM, interleaved."""
    from ..bench import step_costs
    from ..timing import median, median_ratio

    scene = case_level(case)
    systems = {SPRING: models.get(SPRING), EXPLICIT_FEM: models.get(EXPLICIT_FEM)}
    systems = {k: m.system(scene) for k, m in systems.items()}
    samples = step_costs(systems, case["steps"], case["repeats"])  # interleaved, shuffled
    out: dict[str, Any] = {"tets": scene.mesh.n_tets}
    for name in systems:
        out[f"{name}_wall"] = median(samples, name) / case["steps"]
        out[f"{name}_cpu"] = median(samples, name, "cpu") / case["steps"]
    out["ratio_wall"] = median_ratio(samples, SPRING, EXPLICIT_FEM)
    out["ratio_cpu"] = median_ratio(samples, SPRING, EXPLICIT_FEM, "cpu")
    return out


def pareto_front(seconds: np.ndarray, error: np.ndarray) -> np.ndarray:
    """Mask of the non-dominated points: no other point is at least as fast and as accurate
    and strictly better in one of the two.

    Examples
    --------
    >>> pareto_front(np.array([1.0, 2.0, 3.0, 2.5]), np.array([0.5, 0.1, 0.2, 0.1])).tolist()
    [True, True, False, False]
    """
    t, e = np.asarray(seconds, float), np.asarray(error, float)
    keep = np.ones(t.size, dtype=bool)
    for i in range(t.size):
        better = (t <= t[i]) & (e <= e[i]) & ((t < t[i]) | (e < e[i]))
        keep[i] = not better.any()
    return keep


def model_of(method: str) -> str:
    """The model of a method name (``xpbd 20x2 static`` -> ``xpbd``)."""
    return method.split()[0]
