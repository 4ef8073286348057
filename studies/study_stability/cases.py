"""Cases of the stability study: the settings, the bundled bar, one run per series.

Every case is a :meth:`~studies.scenes.StudyScene.case` of the scene it runs on (its table
decides the result) with the series' own keys: ``method`` (a model of
:mod:`studies.models`), ``factor`` (the load factor: every load value and prescribed
displacement of the scene times it), ``dt_factor``, ``nu`` (the locking series).

Examples
--------
>>> from springfem.mechanics.toy import Oscillator
>>> dt_pred, omega, ratio = measure_critical_step(Oscillator(), steps=200, bisections=6)
>>> float(omega), float(dt_pred)   # sqrt(k / m) = 2 and 2 / omega
(2.0, 1.0)
>>> 0.5 < ratio <= 1.0   # never above the linear-stability bound 2 / omega
True
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from springfem.errors import SolverError
from springfem.mechanics.limits import SolveStopped
from springfem.scene import Scene

from .. import models
from ..analytic import extent, reference_for
from ..scenes import StudyScene, case_scene

VERSION = 3

#: Spring variants of every series: energy and cosine torsion (the scene's other options),
#: and the exact element.
SPRINGS = tuple(map(models.get, ("spring-energy", "spring-cosine", "spring-exact")))
#: The FEM of the explicit series (the explicit P1 FEM) and of the largest-load series.
FEM = (models.P1, models.P1_NH)
#: The methods of the locking series (on a scene with a beam-theory reference).
LOCK_METHODS = ("P1", "P2", "spring", "spring-exact")
#: Beyond this largest displacement over the body's size a small-strain solution is not one.
UNPHYSICAL = 0.1
#: The explicit FEM's laws (its kernels are isotropic).
EXPLICIT_LAWS = ("linear", "neo-hookean")


@dataclass(frozen=True)
class Settings:
    """Grids of the stability study: the bundled bar meshes (``(nx, ny)``: ``nx × ny × ny``
    hexahedra), run length and bisections of the critical-step series; the load factors and
    mesh of the largest-load series; the Poisson ratios and mesh of the locking series; the
    loads, time-step factors, run length and mesh of the failure map."""

    dt_meshes: tuple[tuple[int, int], ...] = ((10, 1), (20, 2))
    dt_steps: int = 2000
    dt_bisections: int = 6
    load_factors: tuple[float, ...] = (1, 10, 100, 300, 1000, 3000, 10000, 30000)
    load_mesh: tuple[int, int] = (20, 2)
    nus: tuple[float, ...] = (0.3, 0.4, 0.45, 0.49, 0.495, 0.499)
    lock_mesh: tuple[int, int] = (40, 4)
    map_loads: tuple[float, ...] = (1, 100, 1000, 3000, 10000, 30000)
    map_dt_factors: tuple[float, ...] = (0.3, 0.6, 0.9, 1.0, 1.1, 1.5)
    map_steps: int = 3000
    map_mesh: tuple[int, int] = (10, 1)

    @classmethod
    def full(cls) -> Settings:
        """The report's grids."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """Coarse grids: one mesh per series, fewer loads, factors and steps."""
        return cls(
            dt_meshes=((10, 1),),
            dt_steps=400,
            dt_bisections=4,
            load_factors=(1, 100, 1000, 3000, 10000),
            load_mesh=(10, 1),
            nus=(0.3, 0.45, 0.49, 0.499),
            lock_mesh=(20, 2),
            map_loads=(1, 1000, 10000),
            map_dt_factors=(0.5, 0.9, 1.1),
            map_steps=800,
        )


def own_steppers(names: list[str]) -> dict[str, tuple[str, Any]]:
    """The plug-ins among ``names`` with their own step search (``largest_step``) and their
    variants (``variants``, :class:`~springfem.model_api.ModelPlugin`): method name ->
    (the plug-in's name, the plug-in with the variant's settings).

    Examples
    --------
    >>> sorted(own_steppers(["mass-spring", "xpbd"]))
    ['xpbd', 'xpbd-jacobi']
    """
    out: dict[str, tuple[str, Any]] = {}
    for name in names:
        model = models.get(name)
        plugin = getattr(model, "plugin", None) or model
        if not hasattr(plugin, "largest_step"):
            continue
        out[name] = (name, plugin)
        for variant, changes in getattr(plugin, "variants", {}).items():
            out[variant] = (name, plugin.with_settings(**changes))
    return out


def bar(nx: int, ny: int, roles: tuple[str, ...]) -> StudyScene:
    """The bundled cantilever (0.1 × 0.01 × 0.01 m, E = 10 kPa, end traction 0.1 Pa) on
    ``nx × ny × ny`` hexahedra (six tets each), energy torsion, serving the series ``roles``.

    Examples
    --------
    >>> bar(10, 1, ("dt",)).build().mesh.n_tets
    60
    """
    sets = {"mesh.divisions": [nx, ny, ny], "spring.torsion": "energy"}
    return StudyScene.bundled(
        "cantilever", sets, label=f"bar {nx}x{ny}x{ny}", roles=roles, analytic="timoshenko"
    )


def bundled_scenes(q: Settings) -> list[StudyScene]:
    """The bundled bars of each series (one bar per mesh, serving every series on it)."""
    roles: dict[tuple[int, int], list[str]] = {}
    for mesh in q.dt_meshes:
        roles.setdefault(tuple(mesh), []).append("dt")
    roles.setdefault(tuple(q.load_mesh), []).append("load")
    roles.setdefault(tuple(q.lock_mesh), []).append("lock")
    roles.setdefault(tuple(q.map_mesh), []).append("map")
    return [bar(nx, ny, tuple(r)) for (nx, ny), r in roles.items()]


def series_methods(law: str) -> dict[str, tuple[str, ...]]:
    """The model names of each series (``dt``, ``load``, ``map``) for a material law.

    The explicit FEM has isotropic laws only; on an anisotropic or tissue scene the explicit
    series run the spring variants alone and the static series solve FEM with the scene's
    own law (``P1``).

    Examples
    --------
    >>> series_methods("guccione")["load"]
    ('spring-energy', 'spring-cosine', 'spring-exact', 'P1')
    """
    springs = tuple(m.name for m in SPRINGS)
    if law in EXPLICIT_LAWS:
        fem = tuple(m.name for m in FEM)
        return {"dt": (*springs, *fem), "load": (*springs, *fem), "map": (*springs, "P1-NH")}
    return {"dt": springs, "load": (*springs, "P1"), "map": springs}


def grids(scenes: list[StudyScene], q: Settings) -> dict[str, list[dict]]:
    """The cases of the four series (``dt``, ``load``, ``lock``, ``map``) on the scenes that
    serve them.
    """
    out: dict[str, list[dict]] = {"dt": [], "load": [], "lock": [], "map": []}
    for s in scenes:
        built = s.build()
        m = dict(series_methods(built.material.law))
        # the plug-in models (studies.models.plugins): static series where they apply,
        # explicit series where they have an explicit form; a plug-in's own step search
        # (largest_step) and its variants in the dt series, the variants' runs to rest
        # beside the plug-in's in the load series
        peers, peers_x = models.plugins(built), models.plugins(built, explicit=True)
        own = tuple(own_steppers(peers))
        variants = tuple(v for v in own if v not in peers)
        m = {"dt": (*m["dt"], *peers_x, *own), "load": (*m["load"], *peers, *variants),
             "map": (*m["map"], *peers_x)}  # fmt: skip

        def case(kind: str, **kw) -> dict:
            return s.case("stability", VERSION, kind=kind, **kw)  # noqa: B023

        if s.serves("dt"):
            out["dt"] += [
                case("dt", method=x, steps=q.dt_steps, bisections=q.dt_bisections) for x in m["dt"]
            ]
        if s.serves("load"):
            out["load"] += [
                case("load", method=x, factor=f) for x in m["load"] for f in q.load_factors
            ]
        if s.serves("lock") and s.analytic == "timoshenko":
            out["lock"] += [
                s.with_sets({"material.nu": nu}).case("stability", VERSION, kind="lock",
                                                      method=x, nu=nu)
                for x in LOCK_METHODS
                for nu in q.nus
            ]  # fmt: skip
        if s.serves("map"):
            out["map"] += [
                case("map", method=x, factor=f, dt_factor=d, steps=q.map_steps)
                for x in m["map"]
                for f in q.map_loads
                for d in q.map_dt_factors
            ]
    return out


def _inverted(scene: Scene, u: np.ndarray) -> int:
    return int((scene.mesh.volumes(scene.mesh.points + u.reshape(-1, 3)) <= 0).sum())


# ----------------------------------------------------------------------- critical step


def measure_critical_step(system, steps: int, bisections: int) -> tuple[float, float, float]:
    """Bisect the largest stable explicit step of ``system`` (loads off) in ``[0.5, 2]`` dt_crit.

    A step is stable when ``steps`` central-difference steps from a tiny random velocity do
    not blow up (no :class:`SolverError`). Returns the predicted step ``2 / omega_max``,
    ``omega_max``, and the measured step over the predicted one after ``bisections``
    bisections (``nan``: unstable at 0.5; ``2.0``: stable at the top of the bracket).
    """
    from springfem.mechanics import explicit, stable_time_step

    dt_pred, omega = stable_time_step(system)
    rng = np.random.default_rng(0)
    v0 = 1e-6 * rng.standard_normal(system.x0.shape)
    v0.ravel()[system.fixed_dofs] = 0.0

    def stable(f: float) -> bool:
        try:
            explicit(system, dt=f * dt_pred, steps=steps, v_init=v0, record_every=steps)
            return True
        except SolverError:
            return False

    lo, hi = 0.5, 2.0
    if not stable(lo):
        return dt_pred, omega, float("nan")
    if stable(hi):
        return dt_pred, omega, hi
    for _ in range(bisections):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return dt_pred, omega, lo


def critical_step_case(case: dict) -> dict:
    """Predicted and measured critical explicit step of one method (loads off); for a
    plug-in with its own step search, or its variant, the largest step its own run
    survives (``largest_step``, :func:`own_steppers`)."""
    scene = case_scene(case, 0.0)
    own = own_steppers(models.plugins(scene)).get(case["method"])
    if own is not None:
        return own[1].largest_step(scene, case["steps"], case["bisections"])
    system = models.get(case["method"]).system(scene)
    try:
        dt_pred, omega, ratio = measure_critical_step(system, case["steps"], case["bisections"])
    except SolveStopped as exc:  # the time cap or the study's budget: a missing value
        nan = float("nan")
        return {"dt_pred": nan, "dt_measured": nan, "ratio": nan, "failure": str(exc)[:160]}
    out = {"dt_pred": dt_pred, "dt_measured": ratio * dt_pred, "ratio": ratio}
    if ratio == 2.0:
        out["bounded"] = True
    elif ratio == ratio:  # not nan: bisected
        out["omega_max"] = omega
    return out


# -------------------------------------------------------------------------- max load


def load_case(case: dict) -> dict:
    """Static solve at one load factor by one method: ``status``, largest ``|u|`` / size.

    A solve fails as ``diverged`` (the solver), ``inverted`` (elements with J <= 0) or, for
    a small-strain law, ``unphysical`` (largest displacement beyond :data:`UNPHYSICAL` of
    the body's size: the linear solve is no solution of the large-deformation problem).
    """
    scene = case_scene(case, case["factor"])
    own = own_steppers(models.plugins(scene)).get(case["method"])
    if own is not None and own[0] != case["method"]:  # a plug-in's variant: its own solve
        got = models.run(scene, own[0], solve=lambda _, sc: own[1].solve(sc))
    else:
        got = models.run(scene, case["method"])
    if not got.ok:
        return {"status": "diverged", "message": got.message[:160], "u/size": float("nan")}
    u = got.u
    ratio = float(np.linalg.norm(u, axis=1).max() / max(extent(scene)))
    inv = _inverted(scene, u)
    if inv:
        return {"status": "inverted", "u/size": ratio, "message": f"{inv} inverted elements"}
    if got.solution.result.law in ("linear", "transverse-linear") and ratio > UNPHYSICAL:
        msg = f"small-strain kinematics beyond |u|/size = {UNPHYSICAL:g}"
        return {"status": "unphysical", "u/size": ratio, "message": msg}
    return {"status": "ok", "u/size": ratio, "message": ""}


# ----------------------------------------------------------------------- locking


def locking_case(case: dict) -> dict:
    """Tip deflection (over beam theory) and volume change at one Poisson ratio ``nu``."""
    scene = case_scene(case)
    got = models.run(scene, case["method"])
    if not got.ok:
        raise SolverError(f"{case['method']} at nu = {case['nu']}: {got.message}")
    probe, component, value, _ = reference_for("timoshenko", scene)
    res = got.solution.result
    return {
        "tip_ratio": res.probes[probe][component] / value,
        "volume_change": res.volume["relative_change"],
        "inverted": _inverted(scene, got.u),
    }


# -------------------------------------------------------------------- failure map


def failure_map_case(case: dict) -> dict:
    """Damped explicit dynamics at (load factor, dt factor): ok, blew up or inverted."""
    from springfem.mechanics import explicit, stable_time_step

    scene = case_scene(case, case["factor"])
    system = models.get(case["method"]).system(scene)
    try:
        dt_crit, omega = stable_time_step(system)
        # critical damping of the lowest bending mode is far below omega_max; a mass
        # damping of ~omega_max/200 brings the bar near rest within the run
        traj = explicit(
            system,
            dt=case["dt_factor"] * dt_crit,
            steps=case["steps"],
            mass_damping=omega / 200.0,
            record_every=case["steps"],
        )
    except SolverError as exc:
        status = "inverted" if "inverted" in str(exc) else "blew up"
        return {"status": status, "message": str(exc)[:160]}
    except SolveStopped as exc:  # the time cap or the study's budget: no verdict on the cell
        return {"status": "stopped", "message": str(exc)[:160]}
    inv = _inverted(scene, traj.x - system.x0)
    return {"status": "inverted" if inv else "ok", "inverted": inv}


#: Series -> (the work of one case, progress label).
WORK: dict[str, tuple[Any, str]] = {
    "dt": (critical_step_case, "critical dt"),
    "load": (load_case, "max load"),
    "lock": (locking_case, "locking"),
    "map": (failure_map_case, "failure map"),
}
