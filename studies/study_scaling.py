"""Study ``scaling``: cost per explicit step and per static solve against the number of tets.

The benchmark block of :func:`reference_fem.scenes.bench_scene` (2:1:1, clamped at one end,
end traction, six tets per hexahedron) from about 1e3 to 1e5 tets:

- one explicit step (forces + symplectic-Euler update through
  :func:`springfem.mechanics.solvers.explicit`) of the spring model and of the explicit P1
  neo-Hookean FEM, serial kernels (the work per element; the parallel speed-up on this
  machine is what ``springfem bench forces`` measures), median of repeats, both in one case;
- the set-up of each (spring elements: ray casting and calibration; FEM: shape gradients);
- one static solve: the spring model's Newton (energy-consistent torsion, analytic Hessian,
  AMG above 30k DOFs) and reference FEM P1, linear and coupled neo-Hookean.

Costs are CPU (process) times, which on a shared machine are what the wall time would be
on an idle one for these serial codes; wall times are in the tables. The log-log slopes
(:func:`studies.metrics.fitted_rate`) are the headline numbers, rounded.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from springmodel.options import SpringOptions

from .metrics import fitted_rate
from .registry import Figure, StudyContext, StudyOutput, Table, study
from .tables import save_figure, write_table

TORSION = "energy"
REPEATS = 5


@dataclass(frozen=True)
class Settings:
    """Target tet counts of the explicit-step and static-solve series.

    Parameters
    ----------
    step
        Tet counts of the explicit-step series.
    static
        Tet counts of the static-solve series.
    neo_max
        Largest tet count of the neo-Hookean Newton solve.
    """

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


def _scene(n_tets: int):
    from reference_fem.scenes import bench_scene

    scene = bench_scene(n_tets)
    return scene.with_options(spring=replace(SpringOptions.of(scene), torsion=TORSION))


def _clock():
    return time.perf_counter(), time.process_time()


def _since(t):
    return time.perf_counter() - t[0], time.process_time() - t[1]


def step_case(case: dict) -> dict:
    """Set-up and per-step cost of the spring model and the explicit P1 FEM (serial)."""
    from reference_fem.explicit import ExplicitFem
    from springmodel.model import SpringModel

    from .bench import step_time

    scene = _scene(case["n_tets"])
    t = _clock()
    spring = SpringModel(scene, parallel=False)
    spring_setup = _since(t)
    t = _clock()
    fem = ExplicitFem(scene, parallel=False)
    fem_setup = _since(t)
    steps = int(np.clip(2_000_000 // scene.mesh.n_tets, 5, 200))
    systems = {"spring": spring, "fem": fem}
    for s in systems.values():
        step_time(s, 2, 1)  # warm-up
    wall = {k: [] for k in systems}
    cpu = {k: [] for k in systems}
    for _ in range(case["repeats"]):
        for name, s in systems.items():
            w, c = step_time(s, steps, 1)
            wall[name].append(w)
            cpu[name].append(c)
    out = {
        "tets": scene.mesh.n_tets,
        "nodes": scene.mesh.n_points,
        "steps": steps,
        "spring_setup_wall": spring_setup[0],
        "spring_setup_cpu": spring_setup[1],
        "fem_setup_wall": fem_setup[0],
        "fem_setup_cpu": fem_setup[1],
    }
    for name in systems:
        out[f"{name}_step_wall"] = float(np.median(wall[name]))
        out[f"{name}_step_cpu"] = float(np.median(cpu[name]))
    out["ratio_cpu"] = float(np.median(np.array(cpu["spring"]) / np.array(cpu["fem"])))
    return out


def _static_solve(scene, method: str):
    if method == "spring":
        from springmodel.model import solve_spring

        return solve_spring(
            scene, replace(SpringOptions.of(scene), solver="static", tol=1e-8), parallel=False
        )
    import reference_fem

    return reference_fem.solve(scene, order=1, law=method.removeprefix("fem-"))


_WARM: set[str] = set()


def static_case(case: dict) -> dict:
    """One static solve (from the scene, set-up included) by one method."""
    method = case["method"]
    if method not in _WARM:  # imports and compilation are not part of the cost
        _static_solve(_scene(100), method)
        _WARM.add(method)
    scene = _scene(case["n_tets"])
    t = _clock()
    sol = _static_solve(scene, method)
    wall, cpu = _since(t)
    if method == "spring":
        linear_solver = getattr(sol.info, "linear_solver", "")
    else:
        linear_solver = str(sol.result.info.get("linear_solver", ""))
    return {
        "tets": scene.mesh.n_tets,
        "wall": wall,
        "cpu": cpu,
        "dofs": 3 * scene.mesh.n_points,
        "iterations": sol.result.iterations,
        "tip": sol.result.probes["tip"],
        "linear_solver": linear_solver,
    }


def _tet_axis(ax) -> None:
    """Tet counts as 1,000 / 3,000 / 10,000 ... (one decade may hold one power of ten)."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    ax.xaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 3.0)))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:,.0f}"))
    ax.xaxis.set_minor_formatter(NullFormatter())


def _amg_threshold() -> int:
    from springfem.mechanics import DIRECT_MAX_DOFS as AMG_THRESHOLD

    return int(AMG_THRESHOLD)


STATIC_METHODS = {
    "spring": "spring model, static Newton",
    "fem-linear": "FEM P1 linear, static",
    "fem-neo-hookean/coupled": "FEM P1 neo-Hookean, Newton",
}


@study("scaling", Settings)
def run(ctx: StudyContext, p: Settings) -> StudyOutput:
    """Run the scaling study (see the module docstring).

    Parameters
    ----------
    ctx
        Output folder, cache and preset.
    p
        Tet counts.

    Returns
    -------
    StudyOutput
        Findings, step/solve/slope tables, the scaling figure, headline slopes.
    """
    import matplotlib.pyplot as plt

    out = StudyOutput(name=ctx.name, title="Cost against mesh size")

    step_cases = [
        {
            "kind": "step",
            "n_tets": n,
            "repeats": REPEATS,
            "torsion": TORSION,
            "scene": "bench_scene",
        }
        for n in p.step
    ]
    steps = ctx.cache.run(step_cases, step_case, ctx.progress, "explicit steps")
    sdf = pd.DataFrame(
        [
            {
                "tets": s["tets"],
                "nodes": s["nodes"],
                "spring_ms_per_step": 1e3 * s["spring_step_cpu"],
                "fem_ms_per_step": 1e3 * s["fem_step_cpu"],
                "spring_over_fem": s["ratio_cpu"],
                "spring_wall_ms": 1e3 * s["spring_step_wall"],
                "fem_wall_ms": 1e3 * s["fem_step_wall"],
                "spring_setup_s": s["spring_setup_cpu"],
                "fem_setup_s": s["fem_setup_cpu"],
            }
            for s in steps
        ]
    )

    static_cases = [
        {"kind": "static", "n_tets": n, "method": m, "torsion": TORSION, "scene": "bench_scene"}
        for n in p.static
        for m in STATIC_METHODS
        if not (m.startswith("fem-neo") and n > p.neo_max)
    ]
    static = ctx.cache.run(static_cases, static_case, ctx.progress, "static solves")
    tdf = pd.DataFrame(
        [
            {
                "method": c["method"],
                "tets": r["tets"],
                "dofs": r["dofs"],
                "cpu_s": r["cpu"],
                "wall_s": r["wall"],
                "newton_iterations": r["iterations"],
                "linear_solver": r["linear_solver"],
            }
            for c, r in zip(static_cases, static)
        ]
    )

    # ---- slopes
    n_step = sdf["tets"].to_numpy(float)
    slope = {
        "step_spring": fitted_rate(n_step, sdf["spring_ms_per_step"]),
        "step_fem": fitted_rate(n_step, sdf["fem_ms_per_step"]),
        "setup_spring": fitted_rate(n_step, sdf["spring_setup_s"]),
        "setup_fem": fitted_rate(n_step, sdf["fem_setup_s"]),
    }
    for m in STATIC_METHODS:
        g = tdf[tdf["method"] == m]
        slope[f"static_{m.split('/')[0]}"] = fitted_rate(g["tets"], g["cpu_s"])
    for key, value in slope.items():
        if not key.startswith("setup"):  # set-up times of a few ms are too noisy
            out.headline[f"slope_{key}"] = round(float(value), 1)

    # ---- tables
    decades = np.log10(n_step.max() / n_step.min())
    out.tables.append(
        Table(
            write_table(sdf, ctx.path("explicit_step")),
            f"Cost of one explicit step (serial kernels, forces + update through the solver loop; "
            f"CPU ms, median of {REPEATS} alternating repeats; wall ms beside) and of the set-up "
            f"(CPU s), spring model vs explicit P1 neo-Hookean FEM on the same mesh.",
        )
    )
    out.tables.append(
        Table(
            write_table(tdf, ctx.path("static_solve")),
            "One static solve from the scene (set-up, assembly, Newton or linear solve): CPU and "
            "wall seconds, Newton iterations and the linear solver used.",
        )
    )
    fits = pd.DataFrame([{"series": k, "fitted slope": v} for k, v in slope.items()])
    out.tables.append(
        Table(
            write_table(fits, ctx.path("slopes")),
            "Fitted log-log slopes of cost against tet count (1 = linear scaling).",
        )
    )

    # ---- figure
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4))
    ax = axes[0]
    for col, label, colour in (
        ("spring_ms_per_step", "spring model", "tab:red"),
        ("fem_ms_per_step", "explicit P1 FEM (neo-Hookean)", "tab:purple"),
    ):
        key = "step_spring" if col.startswith("spring") else "step_fem"
        ax.loglog(
            sdf["tets"], sdf[col], "o-", color=colour, label=f"{label}: slope {slope[key]:.2f}"
        )
    ref_x = np.array([n_step.min(), n_step.max()])
    ref_y = sdf["fem_ms_per_step"].iloc[-1] * ref_x / ref_x[-1]
    ax.loglog(ref_x, ref_y, "k:", lw=1, label="slope 1")
    _tet_axis(ax)
    ax.set_xlabel("tets")
    ax.set_ylabel("CPU ms per explicit step")
    ax.set_title("Explicit step (serial)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax = axes[1]
    colours = {"spring": "tab:red", "fem-linear": "tab:blue", "fem-neo-hookean/coupled": "tab:cyan"}
    for m, label in STATIC_METHODS.items():
        g = tdf[tdf["method"] == m]
        rate = slope["static_" + m.split("/")[0]]
        ax.loglog(g["tets"], g["cpu_s"], "s-", color=colours[m], label=f"{label}: slope {rate:.2f}")
    _tet_axis(ax)
    ax.set_xlabel("tets")
    ax.set_ylabel("CPU s per static solve")
    ax.set_title("Static solve (set-up included)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)

    # ---- findings
    last = sdf.iloc[-1]
    out.findings.append(
        f"Per explicit step the cost grows like N^{slope['step_spring']:.2f} (spring model) and "
        f"N^{slope['step_fem']:.2f} (explicit P1 FEM) over {decades:.1f} decades "
        f"({int(n_step.min())}-{int(n_step.max())} tets); at {int(last['tets'])} tets a spring "
        f"step costs {last['spring_ms_per_step']:.1f} ms, an FEM step "
        f"{last['fem_ms_per_step']:.1f} ms ({last['spring_over_fem']:.2f}x, CPU time, serial)."
    )
    big = tdf[tdf["tets"] == tdf["tets"].max()].set_index("method")
    parts = [f"{STATIC_METHODS[m]} {big.loc[m, 'cpu_s']:.1f} s" for m in big.index]
    out.findings.append(
        f"A static solve scales like N^{slope['static_spring']:.2f} (spring Newton), "
        f"N^{slope['static_fem-linear']:.2f} (FEM P1 linear) and "
        f"N^{slope['static_fem-neo-hookean']:.2f} (FEM P1 neo-Hookean Newton); at "
        f"{int(tdf['tets'].max())} tets: {', '.join(parts)}."
    )
    both = tdf.pivot(index="tets", columns="method", values="cpu_s").dropna(
        subset=["spring", "fem-linear"]
    )
    ratio = both["spring"] / both["fem-linear"]
    worst = int(ratio.idxmax())
    solver_at = tdf[(tdf["method"] == "spring") & (tdf["tets"] == worst)]["linear_solver"].iloc[0]
    out.findings.append(
        f"The spring model's static Newton solve costs {ratio.min():.1f}-{ratio.max():.1f}x the "
        f"linear FEM P1 solve on the same mesh, most at {worst} tets (linear solver there: "
        f"{solver_at}; the spring solver switches from SuperLU to AMG above "
        f"{_amg_threshold()} free DOFs, the FEM reference uses AMG throughout)."
    )
    setup_steps = last["spring_setup_s"] / last["spring_ms_per_step"] * 1e3
    out.findings.append(
        f"Set-up (spring: ray casting and calibration; FEM: shape gradients) scales like "
        f"N^{slope['setup_spring']:.2f} and N^{slope['setup_fem']:.2f}; at "
        f"{int(last['tets'])} tets it costs {last['spring_setup_s']:.2f} s vs "
        f"{last['fem_setup_s']:.2f} s, i.e. {setup_steps:.0f} spring steps."
    )
    caption = (
        f"Left: CPU time per explicit step against tet count (log-log, fitted slopes in the "
        f"legend); right: CPU time per static solve. {out.findings[0]}"
    )
    out.figures.append(Figure(save_figure(fig, ctx.path("scaling.png")), caption))
    return out
