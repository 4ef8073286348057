"""Study ``speed_accuracy``: wall time against error, one point per method, mesh and setting.

The bundled cantilever (0.1 x 0.01 x 0.01 m, E = 1e4 Pa, nu = 0.3, end shear) on meshes of
``nx x ny x ny`` hexahedra (six tets each). Every point is one solve from the scene to the
tip displacement; its error is the relative error of the tip displacement vector against a
P2 solution on a finer mesh (Timoshenko's beam value is given for context). Methods:

- spring model (energy-consistent torsion, volume springs): ``static`` Newton, ``implicit``
  backward-Euler pseudo-time stepping to equilibrium (``dt`` a multiple of the critical
  step), ``explicit`` dynamic relaxation (:func:`springfem.mechanics.solvers.explicit_static`,
  kinetic damping) at two tolerances and two time-step safety factors;
- FEM P1 and P2, linear and coupled neo-Hookean, static (:func:`reference_fem.solve`);
- explicit P1 FEM, coupled neo-Hookean (:class:`reference_fem.explicit.ExplicitFem`), to
  equilibrium with the same solver and settings as the spring model.

The non-dominated (Pareto) points are those no other point beats in both time and error.
A separate case measures, on each mesh, the cost of one explicit step of the spring model
and of the explicit P1 FEM (median of repeats, both in the same run, same solver loop).
Timings are noisy on a shared machine: they appear in tables and findings, never in the
headline numbers.
"""

from __future__ import annotations

import re
import time
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from springfem.errors import SolverError
from springfem.scene import Scene, parse_scene
from springmodel.options import SpringOptions

from .cli import SCENES
from .metrics import timoshenko_tip_deflection
from .registry import Figure, StudyContext, StudyOutput, Table, study
from .tables import save_figure, write_table

#: The spring model's torsion law here: the energy-consistent one (conservative, so static
#: Newton has an analytic Hessian and explicit dynamics conserve energy).
TORSION = "energy"
#: Static / implicit tolerances (relative residual).
STATIC_TOL = 1e-8
IMPLICIT_TOL = 1e-6
STEP_REPEATS = 7
STEP_COUNT = 20

FEM_STATIC = {
    "fem-p1-linear": (1, "linear"),
    "fem-p1-neo-hookean": (1, "neo-hookean/coupled"),
    "fem-p2-linear": (2, "linear"),
    "fem-p2-neo-hookean": (2, "neo-hookean/coupled"),
}
LABELS = {
    "spring-static": "spring, static Newton",
    "spring-implicit": "spring, implicit to rest",
    "spring-explicit": "spring, explicit to rest",
    "fem-explicit-p1-neo-hookean": "explicit P1 FEM (neo-Hookean), to rest",
    "fem-p1-linear": "FEM P1 linear, static",
    "fem-p1-neo-hookean": "FEM P1 neo-Hookean, static",
    "fem-p2-linear": "FEM P2 linear, static",
    "fem-p2-neo-hookean": "FEM P2 neo-Hookean, static",
}
STYLE = {  # marker, colour
    "spring-static": ("o", "tab:red"),
    "spring-implicit": ("o", "tab:orange"),
    "spring-explicit": ("o", "tab:pink"),
    "fem-explicit-p1-neo-hookean": ("^", "tab:purple"),
    "fem-p1-linear": ("s", "tab:blue"),
    "fem-p1-neo-hookean": ("s", "tab:cyan"),
    "fem-p2-linear": ("D", "tab:green"),
    "fem-p2-neo-hookean": ("D", "tab:olive"),
}


@dataclass(frozen=True)
class Settings:
    """Meshes and solver settings of the speed-accuracy study.

    Parameters
    ----------
    meshes
        ``(nx, ny)`` cantilever meshes (``nx × ny × ny`` hexahedra) of the points.
    reference
        ``(nx, ny)`` of the fine P2 reference.
    explicit
        ``(tol, dt_safety)`` settings of the explicit runs.
    implicit
        Time-step factor of the implicit runs -> largest ``(nx, ny)`` it runs on.
    """

    meshes: tuple[tuple[int, int], ...] = ((10, 1), (20, 2), (40, 4))
    reference: tuple[int, int] = (60, 6)
    explicit: tuple[tuple[float, float], ...] = ((1e-3, 0.3), (1e-6, 0.3), (1e-6, 0.5))
    implicit: dict[float, tuple[int, int]] = field(
        default_factory=lambda: {100.0: (20, 2), 1e4: (40, 4)}
    )

    @classmethod
    def full(cls) -> Settings:
        """Three meshes up to 40 × 4 × 4, reference 60 × 6 × 6."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """Two meshes, reference 40 × 4 × 4."""
        return cls(
            meshes=((10, 1), (20, 2)),
            reference=(40, 4),
            explicit=((1e-6, 0.5),),
            implicit={100.0: (10, 1), 1e4: (20, 2)},  # dt factor -> largest mesh
        )


def cantilever_text(nx: int, ny: int) -> str:
    """The bundled cantilever scene with ``nx x ny x ny`` hexahedra."""
    text = (SCENES / "cantilever.toml").read_text()
    return re.sub(r"divisions\s*=\s*\[[^\]]*\]", f"divisions = [{nx}, {ny}, {ny}]", text, count=1)


def _scene(case: dict) -> Scene:
    scene = parse_scene(case["scene_text"])
    return scene.with_options(spring=replace(SpringOptions.of(scene), torsion=TORSION))


def timoshenko_tip(scene: Scene) -> float:
    """Timoshenko tip deflection (m, positive down) of the cantilever scene."""
    lo, hi = scene.mesh.bounding_box()
    L, b, h = (hi - lo).tolist()
    traction = scene.loads[0].value
    force = float(-traction[2]) * b * h
    return timoshenko_tip_deflection(force, L, b, h, scene.material.E, scene.material.nu)


# ----------------------------------------------------------------------------- cases


def _solve(scene: Scene, method: str, setting: dict) -> tuple[np.ndarray, dict]:
    """Run one method on a scene: vertex displacement and solver facts."""
    if method in FEM_STATIC:
        import reference_fem

        order, law = FEM_STATIC[method]
        sol = reference_fem.solve(scene, order=order, law=law)
        return sol.u_vertices, {"iterations": sol.result.iterations}
    from springfem.mechanics import explicit_static, implicit, stable_time_step

    if method == "spring-static":
        from springmodel.model import solve_spring

        sol = solve_spring(
            scene, replace(SpringOptions.of(scene), solver="static", tol=STATIC_TOL), parallel=None
        )
        return sol.u, {"iterations": sol.result.iterations}
    if method == "fem-explicit-p1-neo-hookean":
        from reference_fem.explicit import ExplicitFem

        system = ExplicitFem(scene, law="neo-hookean")
    else:
        from springmodel.model import SpringModel

        system = SpringModel(scene, parallel=None)
    if method == "spring-implicit":
        dt = setting["dt_factor"] * stable_time_step(system)[0]
        traj = implicit(system, dt=dt, steps=5000, equilibrium_tol=IMPLICIT_TOL)
        if not traj.converged:
            raise SolverError(traj.message, state=traj.x - system.x0)
        return traj.x - system.x0, {"steps": traj.steps, "iterations": traj.iterations}
    info = explicit_static(
        system, tol=setting["tol"], dt_safety=setting["dt_safety"], max_steps=400_000
    )
    return info.x - system.x0, {"steps": info.steps, "dt": info.dt}


_WARM: set[str] = set()


def _warm_up(method: str, setting: dict) -> None:
    """Run a method once on a tiny mesh so compilation and imports are not timed."""
    if method in _WARM:
        return
    tiny = {"scene_text": cantilever_text(4, 1)}
    loose = dict(setting, tol=1e-2) if "tol" in setting else setting
    try:
        _solve(_scene(tiny), method, loose)
    except SolverError:
        pass
    _WARM.add(method)


def point_case(case: dict) -> dict:
    """One (method, mesh, setting) point: wall time from the scene to the answer, tip."""
    scene = _scene(case)
    _warm_up(case["method"], case["setting"])
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        u, facts = _solve(scene, case["method"], case["setting"])
    except SolverError as exc:
        msg = str(exc)
        status = "blew up" if "blew up" in msg or "inverted" in msg else "failed"
        return {
            "status": status,
            "seconds": time.perf_counter() - t0,
            "cpu_seconds": time.process_time() - c0,
            "message": msg[:240],
        }
    return {
        "status": "ok",
        "seconds": time.perf_counter() - t0,
        "cpu_seconds": time.process_time() - c0,
        "tip": scene.probe_displacements(u)["tip"],
        "tets": scene.mesh.n_tets,
        **facts,
    }


def reference_case(case: dict) -> dict:
    """The reference tip displacement: P2 linear on the finest mesh."""
    import reference_fem

    scene = _scene(case)
    sol = reference_fem.solve(scene, order=2, law="linear")
    return {
        "tip": sol.result.probes["tip"],
        "tets": scene.mesh.n_tets,
        "timoshenko": timoshenko_tip(scene),
    }


def step_count(n_tets: int) -> int:
    """Explicit steps per timed repeat: about 0.2 M element evaluations (>~10 ms)."""
    return int(np.clip(200_000 // max(n_tets, 1), STEP_COUNT, 500))


def step_cost_case(case: dict) -> dict:
    """Cost of one explicit step, spring model and explicit P1 FEM, measured alternately."""
    from reference_fem.explicit import ExplicitFem
    from springmodel.model import SpringModel

    from .bench import step_time

    scene = _scene(case)
    systems = {"spring": SpringModel(scene, parallel=None), "fem": ExplicitFem(scene)}
    wall = {k: [] for k in systems}
    cpu = {k: [] for k in systems}
    for system in systems.values():  # warm-up
        step_time(system, 2, 1)
    for _ in range(case["repeats"]):
        for name, system in systems.items():
            w, c = step_time(system, case["steps"], 1)
            wall[name].append(w)
            cpu[name].append(c)
    out = {"tets": scene.mesh.n_tets}
    for name in systems:
        out[f"{name}_wall"] = float(np.median(wall[name]))
        out[f"{name}_cpu"] = float(np.median(cpu[name]))
    out["ratio_wall"] = float(np.median(np.array(wall["spring"]) / np.array(wall["fem"])))
    out["ratio_cpu"] = float(np.median(np.array(cpu["spring"]) / np.array(cpu["fem"])))
    out["parallel"] = {
        k: bool(
            getattr(s, "parallel", False) or getattr(getattr(s, "kernel", None), "parallel", False)
        )
        for k, s in systems.items()
    }
    return out


def cases_for(p: Settings) -> list[dict]:
    """All (method, mesh, setting) points of a plan."""
    out = []
    for nx, ny in p.meshes:
        base = {
            "kind": "point",
            "mesh": [nx, ny],
            "scene_text": cantilever_text(nx, ny),
            "torsion": TORSION,
        }
        for method in FEM_STATIC:
            out.append({**base, "method": method, "setting": {}})
        out.append({**base, "method": "spring-static", "setting": {"tol": STATIC_TOL}})
        for factor, (mx, _) in p.implicit.items():
            if nx <= mx:
                out.append(
                    {
                        **base,
                        "method": "spring-implicit",
                        "setting": {"dt_factor": factor, "tol": IMPLICIT_TOL},
                    }
                )
        for tol, safety in p.explicit:
            for method in ("spring-explicit", "fem-explicit-p1-neo-hookean"):
                out.append({**base, "method": method, "setting": {"tol": tol, "dt_safety": safety}})
    return out


# ----------------------------------------------------------------------------- analysis


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


def setting_label(method: str, setting: dict) -> str:
    if method == "spring-implicit":
        return f"dt = {setting['dt_factor']:g} dt_crit"
    if "dt_safety" in setting:
        return f"tol {setting['tol']:g}, dt = {setting['dt_safety']:g} dt_crit"
    return ""


def _relative_error(tip, ref) -> float:
    tip, ref = np.asarray(tip, float), np.asarray(ref, float)
    return float(np.linalg.norm(tip - ref) / np.linalg.norm(ref))


@study("speed_accuracy", Settings)
def run(ctx: StudyContext, p: Settings) -> StudyOutput:
    """Run the speed-accuracy study (see the module docstring).

    Parameters
    ----------
    ctx
        Output folder, cache and preset.
    p
        Meshes and solver settings.

    Returns
    -------
    StudyOutput
        Findings, points and step-cost tables, the Pareto figure, headline numbers.
    """
    import matplotlib.pyplot as plt

    out = StudyOutput(name=ctx.name, title="Speed against accuracy")

    rx, ry = p.reference
    ref = ctx.cache.run(
        [
            {
                "kind": "reference",
                "mesh": [rx, ry],
                "scene_text": cantilever_text(rx, ry),
                "torsion": TORSION,
            }
        ],
        reference_case,
        ctx.progress,
        "reference P2",
    )[0]
    ref_tip = np.asarray(ref["tip"])
    timo = ref["timoshenko"]

    cases = cases_for(p)
    results = ctx.cache.run(cases, point_case, ctx.progress, "points")
    rows = []
    for c, r in zip(cases, results):
        nx, ny = c["mesh"]
        row = {
            "method": c["method"],
            "mesh": f"{nx}x{ny}x{ny}",
            "tets": 6 * nx * ny * ny,
            "setting": setting_label(c["method"], c["setting"]),
            "status": r["status"],
            "seconds": r.get("cpu_seconds", r["seconds"]),
            "wall_seconds": r["seconds"],
            "tip_error": np.nan,
            "tip_over_timoshenko": np.nan,
            "steps": r.get("steps", np.nan),
            "message": r.get("message", ""),
        }
        if r["status"] == "ok":
            row["tip_error"] = _relative_error(r["tip"], ref_tip)
            row["tip_over_timoshenko"] = -r["tip"][2] / timo
        rows.append(row)
    df = pd.DataFrame(rows)
    ok = df["status"] == "ok"
    df["pareto"] = False
    df.loc[ok, "pareto"] = pareto_front(
        df.loc[ok, "seconds"].to_numpy(), df.loc[ok, "tip_error"].to_numpy()
    )

    steps = ctx.cache.run(
        [
            {
                "kind": "step_cost",
                "mesh": [nx, ny],
                "scene_text": cantilever_text(nx, ny),
                "torsion": TORSION,
                "repeats": STEP_REPEATS,
                "steps": step_count(6 * nx * ny * ny),
            }
            for nx, ny in p.meshes
        ],
        step_cost_case,
        ctx.progress,
        "step cost",
    )
    sdf = pd.DataFrame(
        [
            {
                "mesh": f"{nx}x{ny}x{ny}",
                "tets": s["tets"],
                "spring_ms_per_step": 1e3 * s["spring_wall"],
                "fem_ms_per_step": 1e3 * s["fem_wall"],
                "ratio_wall": s["ratio_wall"],
                "spring_cpu_ms": 1e3 * s["spring_cpu"],
                "fem_cpu_ms": 1e3 * s["fem_cpu"],
                "ratio_cpu": s["ratio_cpu"],
            }
            for (nx, ny), s in zip(p.meshes, steps)
        ]
    )

    # ---- tables
    show = df.drop(columns=["message"]).copy()
    show["tip_error_%"] = 100 * show.pop("tip_error")
    out.tables.append(
        Table(
            write_table(show, ctx.path("points")),
            f"Every (method, mesh, setting) point: CPU time (`seconds`) and wall time from the "
            f"scene to the tip displacement (model build and time-step estimate included; the "
            f"solves are serial, so CPU time is the wall time of an idle machine, while this "
            f"shared machine's wall times varied up to 3x), relative tip error "
            f"against P2 on {rx}x{ry}x{ry} ({ref['tets']} tets; its tip is "
            f"{-ref_tip[2] / timo:.4f} x Timoshenko), status, explicit/implicit steps, and whether "
            f"the point is on the Pareto front.",
        )
    )
    out.tables.append(
        Table(
            write_table(sdf, ctx.path("step_cost")),
            f"Cost of one explicit step (forces + update through the same solver loop), spring "
            f"model vs explicit P1 neo-Hookean FEM on the same mesh: medians of {STEP_REPEATS} "
            f"alternating repeats of {STEP_COUNT}-500 steps; wall and CPU (process) time.",
        )
    )
    failed = df[~ok]
    if len(failed):
        write_table(
            failed[["method", "mesh", "setting", "status", "message"]], ctx.path("failures")
        )

    # ---- figure
    fig, ax = plt.subplots(figsize=(8.5, 5.6))
    good = df[ok]
    for method, grp in good.groupby("method", sort=False):
        marker, colour = STYLE[method]
        ax.scatter(
            grp["seconds"],
            100 * grp["tip_error"],
            marker=marker,
            color=colour,
            s=46,
            label=LABELS[method],
            edgecolor="k",
            linewidth=0.4,
            zorder=3,
        )
        for _, r in grp.iterrows():
            ax.annotate(
                r["mesh"].split("x")[0],
                (r["seconds"], 100 * r["tip_error"]),
                fontsize=6,
                xytext=(3, 2),
                textcoords="offset points",
            )
    front = good[good["pareto"]].sort_values("seconds")
    if len(front):
        fx = np.r_[front["seconds"].to_numpy(), good["seconds"].max() * 1.5]
        fy = np.r_[100 * front["tip_error"].to_numpy(), 100 * front["tip_error"].iloc[-1]]
        ax.step(fx, fy, where="post", color="k", ls="--", lw=1, label="Pareto front", zorder=2)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("CPU time from scene to answer (s)")
    ax.set_ylabel(f"tip error vs P2 {rx}x{ry}x{ry} (%)")
    ax.set_title("Cantilever: time against error (labels: elements along the beam)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="best")

    # ---- findings
    finest = p.meshes[-1]
    fmesh = f"{finest[0]}x{finest[1]}x{finest[1]}"
    s_last = steps[-1]
    ratio, ratio_cpu = s_last["ratio_wall"], s_last["ratio_cpu"]
    out.findings.append(
        f"One explicit step of the spring model costs {ratio_cpu:.2f}x one step of the explicit "
        f"P1 neo-Hookean FEM on the same {fmesh} mesh ({s_last['tets']} tets; CPU time, median "
        f"of {STEP_REPEATS} alternating repeats in one run; wall-clock ratio {ratio:.2f}x on "
        f"this shared machine): "
        + (
            "the spring model is slower per step."
            if ratio_cpu > 1
            else "the spring model is cheaper per step."
        )
    )

    def best(method, mesh=fmesh):
        g = good[(good["method"] == method) & (good["mesh"] == mesh)]
        return g.sort_values("tip_error").iloc[0] if len(g) else None

    sp, p1, p2 = best("spring-static"), best("fem-p1-linear"), best("fem-p2-linear")
    if sp is not None and p1 is not None and p2 is not None:
        out.findings.append(
            f"On {fmesh} the spring model's tip is {100 * sp['tip_error']:.1f}% off the fine P2 "
            f"reference (static Newton, {sp['seconds']:.2f} s), P1 FEM on the same mesh "
            f"{100 * p1['tip_error']:.1f}% ({p1['seconds']:.2f} s) and P2 FEM "
            f"{100 * p2['tip_error']:.2f}% ({p2['seconds']:.2f} s)."
        )
        out.headline[f"tip_error_spring_static_{fmesh}"] = round(float(sp["tip_error"]), 4)
        out.headline[f"tip_error_fem_p1_linear_{fmesh}"] = round(float(p1["tip_error"]), 4)
        out.headline[f"tip_error_fem_p2_linear_{fmesh}"] = round(float(p2["tip_error"]), 4)
    se = good[(good["method"] == "spring-explicit") & (good["mesh"] == fmesh)]
    fe = good[(good["method"] == "fem-explicit-p1-neo-hookean") & (good["mesh"] == fmesh)]
    common = sorted(set(se["setting"]) & set(fe["setting"]))
    if common:
        st = (
            "tol 1e-06, dt = 0.5 dt_crit"
            if "tol 1e-06, dt = 0.5 dt_crit" in common
            else (common[-1])
        )
        a = se[se["setting"] == st].iloc[0]
        b = fe[fe["setting"] == st].iloc[0]
        out.findings.append(
            f"To rest by dynamic relaxation ({st}) on {fmesh}: spring model {a['seconds']:.2f} s "
            f"in {int(a['steps'])} steps (tip error {100 * a['tip_error']:.1f}%), explicit P1 FEM "
            f"{b['seconds']:.2f} s in {int(b['steps'])} steps (tip error "
            f"{100 * b['tip_error']:.1f}%, the P1 static answer to the solver tolerance)."
        )
        out.headline[f"tip_error_fem_explicit_{fmesh}"] = round(float(b["tip_error"]), 4)
        if sp is not None:
            out.findings.append(
                f"For this static problem dynamic relaxation is the slow way to the answer: "
                f"{a['seconds'] / sp['seconds']:.0f}x the spring model's static Newton and "
                f"{b['seconds'] / best('fem-p1-neo-hookean')['seconds']:.0f}x FEM P1 "
                f"neo-Hookean Newton on {fmesh}; explicit stepping pays off only when the "
                f"dynamics themselves are wanted."
            )
    on_front = good[good["pareto"]]
    fam = ", ".join(
        f"{LABELS[m]} ({', '.join(on_front[on_front['method'] == m]['mesh'])})"
        for m in on_front["method"].unique()
    )
    n_spring_front = int(on_front["method"].str.startswith("spring").sum())
    front_text = f"Pareto front ({len(on_front)} of {len(good)} points): {fam}; " + (
        f"{n_spring_front} spring-model point(s) on it."
        if n_spring_front
        else "no spring-model point is on it: for every spring point some "
        "FEM point is both faster and more accurate."
    )
    out.findings.append(front_text)
    for _, r in failed.iterrows():
        out.findings.append(
            f"{LABELS[r['method']]} on {r['mesh']} ({r['setting']}) {r['status']}: "
            f"{r['message'][:140]}"
        )
    out.headline["n_points"] = float(len(df))
    out.headline["n_failed"] = float(len(failed))

    caption = (
        f"CPU time against tip error of every solve of the cantilever (log-log; labels: "
        f"elements along the beam), with the Pareto front. {front_text}"
    )
    out.figures.append(Figure(save_figure(fig, ctx.path("pareto.png")), caption))
    return out
