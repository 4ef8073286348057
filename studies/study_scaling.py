"""Study ``scaling``: cost per explicit step and per static solve against the number of tets.

The benchmark block of :func:`bench_table` (2:1:1, clamped at one end, end traction, six
tets per hexahedron) from about 1e3 to 1e5 tets:

- one explicit step (forces + symplectic-Euler update through
  :func:`springfem.mechanics.explicit`) of the spring model and of the explicit P1
  neo-Hookean FEM, serial kernels (the work per element; the parallel speed-up is what
  ``springfem bench forces`` measures), median of repeats, both in one case;
- the set-up of each (spring elements: ray casting and calibration; FEM: shape gradients);
- one static solve: the spring model's Newton (energy-consistent torsion, analytic Hessian,
  AMG above 30k DOFs) and reference FEM P1, linear and coupled neo-Hookean.

Costs are CPU (process) times, which on a shared machine are what the wall time would be
on an idle one for these serial codes; wall times are in the tables. The log-log slopes
(:func:`studies.metrics.fitted_rate`) are the headline numbers, rounded.

Examples
--------
>>> Settings.quick().neo_max, bench_table(1_000)["mesh"]["divisions"]
(10000, [8, 4, 4])
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from springfem.scene import scene_from_dict

from . import models
from .metrics import fitted_rate
from .registry import StudyContext, StudyOutput, study
from .scenes import StudyScene, case_scene
from .tables import pyplot

TORSION = "energy"
REPEATS = 5
VERSION = 2
#: The static solvers: name -> label.
STATIC_METHODS = {
    "spring": "spring model, static Newton",
    "P1": "FEM P1 linear, static",
    "P1-NH": "FEM P1 neo-Hookean, Newton",
}


@dataclass(frozen=True)
class Settings:
    """Target tet counts of the explicit-step (``step``) and static-solve (``static``)
    series; no neo-Hookean Newton solve above ``neo_max`` tets."""

    step: tuple[int, ...] = (1_000, 3_000, 10_000, 30_000, 100_000, 200_000)
    static: tuple[int, ...] = (1_000, 3_000, 10_000, 30_000, 100_000)
    neo_max: int = 30_000  # the neo-Hookean Newton solve at 1e5 tets alone costs ~20 s

    @classmethod
    def full(cls) -> Settings:
        """Up to 200,000 tets."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """Up to 100,000 tets (explicit) and 10,000 (static)."""
        return cls(step=(1_000, 10_000, 100_000), static=(1_000, 3_000, 10_000), neo_max=10_000)


def bench_table(n_tets: int = 100_000) -> dict:
    """The benchmark block: 2:1:1 with about ``n_tets`` tets (six per hexahedron), clamped
    at ``x_min`` and pulled down at ``x_max``, FEM P1 with AMG."""
    k = max(1, round((n_tets / 12.0) ** (1.0 / 3.0)))
    return {
        "name": f"bench-{12 * k**3}",
        "mesh": {"generator": "box", "size": [2.0, 1.0, 1.0], "divisions": [2 * k, k, k]},
        "material": {"law": "linear", "E": 1.0e4, "nu": 0.3},
        "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
        "load": [{"type": "traction", "region": "x_max", "value": [0.0, 0.0, -1.0]}],
        "probe": [{"name": "tip", "point": [2.0, 0.5, 0.5]}],
        "fem": {"order": 1, "linear_solver": "amg"},
        "spring": {"torsion": TORSION},
    }


def bench_scene(n_tets: int, role: str) -> StudyScene:
    """The benchmark block of about ``n_tets`` tets as a study scene serving ``role``."""
    table = bench_table(n_tets)
    return StudyScene(table["name"], table, roles=(role,), params={"n_tets": n_tets})


def bundled_scenes(p: Settings) -> list[StudyScene]:
    """The blocks of the explicit-step (``step``) and static-solve (``static``) series."""
    return [bench_scene(n, "step") for n in p.step] + [bench_scene(n, "static") for n in p.static]


def _timed(fn):
    """``fn()`` and its (wall, CPU) seconds."""
    t = time.perf_counter(), time.process_time()
    out = fn()
    return out, (time.perf_counter() - t[0], time.process_time() - t[1])


def step_case(case: dict) -> dict:
    """Set-up and per-step cost of the spring model and the explicit P1 FEM (serial)."""
    from .bench import step_costs
    from .timing import median, median_ratio

    scene = case_scene(case)
    spring, spring_setup = _timed(lambda: models.SPRING.system(scene))
    fem, fem_setup = _timed(lambda: models.P1_NH.system(scene))  # explicit P1, neo-Hookean
    steps = int(np.clip(2_000_000 // scene.mesh.n_tets, 5, 200))
    systems = {"spring": spring, "fem": fem}
    samples = step_costs(systems, steps, case["repeats"])  # interleaved, shuffled
    out = {"tets": scene.mesh.n_tets, "nodes": scene.mesh.n_points, "steps": steps,
           "spring_setup_wall": spring_setup[0], "spring_setup_cpu": spring_setup[1],
           "fem_setup_wall": fem_setup[0], "fem_setup_cpu": fem_setup[1]}  # fmt: skip
    for name in systems:
        out[f"{name}_step_wall"] = median(samples, name) / steps
        out[f"{name}_step_cpu"] = median(samples, name, "cpu") / steps
    out["ratio_cpu"] = median_ratio(samples, "spring", "fem", "cpu")
    return out


def _static_solve(scene, method: str):
    """A static solve by a model of :data:`STATIC_METHODS` (the spring model: static Newton)."""
    if method == "spring":
        from springmodel.model import solve_spring

        opts = replace(models.SPRING.spring_options(scene), solver="static", tol=1e-8)
        return solve_spring(scene, opts, parallel=False)
    import reference_fem

    fem_scene, order, law = models.get(method).fem_settings(scene)
    return reference_fem.solve(fem_scene, order=order, law=law)


_WARM: set[str] = set()


def static_case(case: dict) -> dict:
    """One static solve (from the scene, set-up included) by one method."""
    method = case["method"]
    if method not in _WARM:  # imports and compilation are not part of the cost
        _static_solve(scene_from_dict(bench_table(100)), method)
        _WARM.add(method)
    scene = case_scene(case)
    sol, (wall, cpu) = _timed(lambda: _static_solve(scene, method))
    if method == "spring":
        linear_solver = getattr(sol.info, "linear_solver", "")
    else:
        linear_solver = str(sol.result.info.get("linear_solver", ""))
    return {"tets": scene.mesh.n_tets, "wall": wall, "cpu": cpu, "dofs": 3 * scene.mesh.n_points,
            "iterations": sol.result.iterations, "tip": sol.result.probes["tip"],
            "linear_solver": linear_solver}  # fmt: skip


NO_USER_SCENES = (
    "it times generated box meshes of chosen sizes (a cost curve), not one scene; "
    "`springfem bench` times a model"
)


@study("scaling", Settings, bundled_scenes, user_scenes=NO_USER_SCENES, serial=True)
def run(ctx: StudyContext, scenes: list[StudyScene], p: Settings) -> StudyOutput:
    """Time the explicit steps and static solves of the blocks (roles ``step``, ``static``)."""
    step_cases = [s.case("scaling", VERSION, kind="step", repeats=REPEATS, torsion=TORSION)
                  for s in scenes if s.serves("step")]  # fmt: skip
    static_cases = [
        s.case("scaling", VERSION, kind="static", method=m, torsion=TORSION)
        for s in scenes
        if s.serves("static")
        for m in STATIC_METHODS
        if not (m == "P1-NH" and s.params["n_tets"] > p.neo_max)
    ]
    steps = ctx.cache.run(step_cases, step_case, ctx.progress, "explicit steps")
    static = ctx.cache.run(static_cases, static_case, ctx.progress, "static solves")
    sdf = pd.DataFrame([{
        "tets": s["tets"], "nodes": s["nodes"],
        "spring_ms_per_step": 1e3 * s["spring_step_cpu"],
        "fem_ms_per_step": 1e3 * s["fem_step_cpu"],
        "spring_over_fem": s["ratio_cpu"],
        "spring_wall_ms": 1e3 * s["spring_step_wall"], "fem_wall_ms": 1e3 * s["fem_step_wall"],
        "spring_setup_s": s["spring_setup_cpu"], "fem_setup_s": s["fem_setup_cpu"],
    } for s in steps])  # fmt: skip
    tdf = pd.DataFrame([{
        "method": c["method"], "tets": r["tets"], "dofs": r["dofs"], "cpu_s": r["cpu"],
        "wall_s": r["wall"], "newton_iterations": r["iterations"],
        "linear_solver": r["linear_solver"],
    } for c, r in zip(static_cases, static)])  # fmt: skip

    n_step = sdf["tets"].to_numpy(float)
    slope = {
        "step_spring": fitted_rate(n_step, sdf["spring_ms_per_step"]),
        "step_fem": fitted_rate(n_step, sdf["fem_ms_per_step"]),
        "setup_spring": fitted_rate(n_step, sdf["spring_setup_s"]),
        "setup_fem": fitted_rate(n_step, sdf["fem_setup_s"]),
    }
    for m in STATIC_METHODS:
        g = tdf[tdf["method"] == m]
        slope[f"static_{m}"] = fitted_rate(g["tets"], g["cpu_s"])
    # the headline: the slopes, rounded (set-up times of a few ms are too noisy)
    headline = {f"slope_{k}": round(float(v), 1) for k, v in slope.items()
                if not k.startswith("setup")}  # fmt: skip

    findings = []
    last = sdf.iloc[-1]
    findings.append(
        f"Per explicit step the cost grows like N^{slope['step_spring']:.2f} (spring model) and "
        f"N^{slope['step_fem']:.2f} (explicit P1 FEM) over "
        f"{np.log10(n_step.max() / n_step.min()):.1f} decades "
        f"({int(n_step.min())}-{int(n_step.max())} tets); at {int(last['tets'])} tets a spring "
        f"step costs {last['spring_ms_per_step']:.1f} ms, an FEM step "
        f"{last['fem_ms_per_step']:.1f} ms ({last['spring_over_fem']:.2f}x, CPU time, serial)."
    )
    big = tdf[tdf["tets"] == tdf["tets"].max()].set_index("method")
    parts = [f"{STATIC_METHODS[m]} {big.loc[m, 'cpu_s']:.1f} s" for m in big.index]
    findings.append(
        f"A static solve scales like N^{slope['static_spring']:.2f} (spring Newton), "
        f"N^{slope['static_P1']:.2f} (FEM P1 linear) and "
        f"N^{slope['static_P1-NH']:.2f} (FEM P1 neo-Hookean Newton); at "
        f"{int(tdf['tets'].max())} tets: {', '.join(parts)}."
    )
    both = tdf.pivot(index="tets", columns="method", values="cpu_s").dropna(subset=["spring", "P1"])
    ratio = both["spring"] / both["P1"]
    worst = int(ratio.idxmax())
    solver_at = tdf[(tdf["method"] == "spring") & (tdf["tets"] == worst)]["linear_solver"].iloc[0]
    from springfem.mechanics import DIRECT_MAX_DOFS

    findings.append(
        f"The spring model's static Newton solve costs {ratio.min():.1f}-{ratio.max():.1f}x the "
        f"linear FEM P1 solve on the same mesh, most at {worst} tets (linear solver there: "
        f"{solver_at}; the spring solver switches from SuperLU to AMG above "
        f"{int(DIRECT_MAX_DOFS)} free DOFs, the FEM reference uses AMG throughout)."
    )
    findings.append(
        f"Set-up (spring: ray casting and calibration; FEM: shape gradients) scales like "
        f"N^{slope['setup_spring']:.2f} and N^{slope['setup_fem']:.2f}; at "
        f"{int(last['tets'])} tets it costs {last['spring_setup_s']:.2f} s vs "
        f"{last['fem_setup_s']:.2f} s, i.e. "
        f"{last['spring_setup_s'] / last['spring_ms_per_step'] * 1e3:.0f} spring steps."
    )

    fits = pd.DataFrame([{"series": k, "fitted slope": v} for k, v in slope.items()])
    tables = [
        ctx.table(sdf, "explicit_step", "Cost of one explicit step (serial kernels, forces + "
                  "update through the solver loop; CPU ms, median of "
                  f"{REPEATS} alternating repeats; wall ms beside) and of the set-up (CPU s), "
                  "spring model vs explicit P1 neo-Hookean FEM on the same mesh."),
        ctx.table(tdf, "static_solve", "One static solve from the scene (set-up, assembly, "
                  "Newton or linear solve): CPU and wall seconds, Newton iterations and the "
                  "linear solver used."),
        ctx.table(fits, "slopes", "Fitted log-log slopes of cost against tet count (1 = linear "
                  "scaling)."),
    ]  # fmt: skip

    # figure: CPU time per explicit step (left) and per static solve (right), log-log
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    fig, axes = pyplot().subplots(1, 2, figsize=(11, 4.4))
    for col, key, label, colour in (
        ("spring_ms_per_step", "step_spring", "spring model", "tab:red"),
        ("fem_ms_per_step", "step_fem", "explicit P1 FEM (neo-Hookean)", "tab:purple"),
    ):
        axes[0].loglog(sdf["tets"], sdf[col], "o-", color=colour,
                       label=f"{label}: slope {slope[key]:.2f}")  # fmt: skip
    ref_x = np.array([n_step.min(), n_step.max()])
    axes[0].loglog(ref_x, sdf["fem_ms_per_step"].iloc[-1] * ref_x / ref_x[-1], "k:", lw=1,
                   label="slope 1")  # fmt: skip
    colours = {"spring": "tab:red", "P1": "tab:blue", "P1-NH": "tab:cyan"}
    for m, label in STATIC_METHODS.items():
        g = tdf[tdf["method"] == m]
        axes[1].loglog(g["tets"], g["cpu_s"], "s-", color=colours[m],
                       label=f"{label}: slope {slope['static_' + m]:.2f}")  # fmt: skip
    for ax, ylabel, title in (
        (axes[0], "CPU ms per explicit step", "Explicit step (serial)"),
        (axes[1], "CPU s per static solve", "Static solve (set-up included)"),
    ):
        # tet counts as 1,000 / 3,000 / 10,000 ...
        ax.xaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 3.0)))
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:,.0f}"))
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set(xlabel="tets", ylabel=ylabel, title=title)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    caption = (
        "Left: CPU time per explicit step against tet count (log-log, fitted slopes in the "
        f"legend); right: CPU time per static solve. {findings[0]}"
    )
    return StudyOutput(ctx.name, "Cost against mesh size", findings, tables,
                       [ctx.figure(fig, "scaling.png", caption)], headline)  # fmt: skip
