"""Study ``stability``: where each method fails.

1. Critical time step: the measured largest stable explicit step (bisection on runs from a
   perturbed rest state) against the predicted ``2 / omega_max``, for spring variants and
   the explicit P1 FEM step.
2. Largest load survived: a cantilever loaded ever harder, solved statically by the spring
   model (energy and cosine torsion), linear FEM (survives any load but its deformed mesh
   inverts) and neo-Hookean Newton (diverges or inverts); what fails is recorded.
3. Near-incompressibility: tip deflection against Poisson's ratio for P1 (locks), P2 and
   the spring model, with the spring model's volume change.
4. Failure map: load factor × time-step factor, explicit damped dynamics, per method.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from springfem.errors import SolverError
from springfem.scene import Scene, parse_scene
from springmodel.options import SpringOptions

from .metrics import timoshenko_tip_deflection
from .registry import Figure, StudyContext, StudyOutput, Table, study
from .tables import save_figure, write_table

BAR = """
name = "stability-bar"
[mesh]
generator = "box"
size = [0.1, 0.01, 0.01]
divisions = [{nx}, {ny}, {ny}]
split = "six"
[material]
law = "{law}"
E = 1.0e4
nu = {nu}
density = 1000.0
[axes]
fiber = [1.0, 0.0, 0.0]
sheet = [0.0, 1.0, 0.0]
[[boundary]]
region = "x_min"
fix = ["x", "y", "z"]
[[load]]
type = "traction"
region = "x_max"
value = [0.0, 0.0, {traction}]
[[probe]]
name = "tip"
point = [0.1, 0.005, 0.005]
[spring]
torsion = "{torsion}"
"""

SPRING_VARIANTS = ("energy", "cosine")


def bar_scene(
    nx: int = 20,
    ny: int = 2,
    nu: float = 0.3,
    traction: float = -0.1,
    law: str = "linear",
    torsion: str = "energy",
) -> Scene:
    """The cantilever bar of the bundled scene at a chosen resolution, ν, load and law."""
    return parse_scene(BAR.format(nx=nx, ny=ny, nu=nu, traction=traction, law=law, torsion=torsion))


def _system(scene: Scene, method: str):
    """A MechanicalSystem for explicit runs: spring variants or the explicit P1 FEM."""
    if method.startswith("spring-"):
        from springmodel.model import SpringModel

        return SpringModel(scene, replace(SpringOptions.of(scene), torsion=method.split("-", 1)[1]))
    from reference_fem.explicit import ExplicitFem

    return ExplicitFem(scene, law=method.split("-", 1)[1])


def _inverted(scene: Scene, u: np.ndarray) -> int:
    return int((scene.mesh.volumes(scene.mesh.points + u.reshape(-1, 3)) <= 0).sum())


# ----------------------------------------------------------------------- critical step


def critical_step_case(case: dict) -> dict:
    """Predicted and measured critical explicit step of one method on one mesh."""
    from springfem.mechanics import explicit, stable_time_step

    scene = bar_scene(case["nx"], case["ny"], traction=0.0)
    system = _system(scene, case["method"])
    dt_pred, omega = stable_time_step(system)
    rng = np.random.default_rng(0)
    v0 = 1e-6 * rng.standard_normal(system.x0.shape)
    v0.ravel()[system.fixed_dofs] = 0.0

    def stable(f: float) -> bool:
        try:
            explicit(
                system, dt=f * dt_pred, steps=case["steps"], v_init=v0, record_every=case["steps"]
            )
            return True
        except SolverError:
            return False

    lo, hi = 0.5, 2.0
    if not stable(lo):
        return {"dt_pred": dt_pred, "dt_measured": float("nan"), "ratio": float("nan")}
    if stable(hi):
        return {"dt_pred": dt_pred, "dt_measured": hi * dt_pred, "ratio": hi, "bounded": True}
    for _ in range(case["bisections"]):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return {"dt_pred": dt_pred, "dt_measured": lo * dt_pred, "ratio": lo, "omega_max": omega}


# -------------------------------------------------------------------------- max load


def load_case(case: dict) -> dict:
    """Static solve of the bar at one load factor by one method; what (if anything) fails."""
    scene = bar_scene(case["nx"], case["ny"], traction=-0.1 * case["factor"])
    method = case["method"]
    try:
        if method.startswith("spring-"):
            from springmodel.model import solve_spring

            sol = solve_spring(
                scene, replace(SpringOptions.of(scene), torsion=method.split("-", 1)[1])
            )
            u = sol.u
        else:
            import reference_fem

            sol = reference_fem.solve(scene, order=1, law=method.split("-", 1)[1])
            u = sol.u_vertices
    except SolverError as exc:
        return {"status": "diverged", "message": str(exc)[:160], "tip": float("nan")}
    inv = _inverted(scene, u)
    tip = float(-scene.probe_displacements(u)["tip"][2])
    if inv:
        return {
            "status": "inverted",
            "inverted": inv,
            "tip": tip,
            "message": f"{inv} inverted elements",
        }
    if method == "fem-linear" and tip > 0.1 * 0.1:
        # small-strain kinematics: a deflection beyond 10% of the length is not a solution
        # of the large-deformation problem, however well the linear system solves
        return {
            "status": "unphysical",
            "inverted": 0,
            "tip": tip,
            "message": "linear kinematics beyond tip/L = 0.1",
        }
    return {"status": "ok", "inverted": 0, "tip": tip, "message": ""}


# ----------------------------------------------------------------------- locking


def locking_case(case: dict) -> dict:
    """Tip deflection (normalised by Timoshenko) and volume change at one ν."""
    scene = bar_scene(case["nx"], case["ny"], nu=case["nu"])
    method = case["method"]
    if method == "spring":
        from springmodel.model import solve_spring

        sol = solve_spring(scene)
        res, u = sol.result, sol.u
    else:
        import reference_fem

        sol = reference_fem.solve(scene, order=int(method[-1]), law="linear")
        res, u = sol.result, sol.u_vertices
    ref = timoshenko_tip_deflection(0.1 * 1e-4, 0.1, 0.01, 0.01, 1.0e4, case["nu"])
    return {
        "tip_ratio": -res.probes["tip"][2] / ref,
        "volume_change": res.volume["relative_change"],
        "inverted": _inverted(scene, u),
    }


# -------------------------------------------------------------------- failure map


def failure_map_case(case: dict) -> dict:
    """Damped explicit dynamics at (load factor, dt factor): ok, blew up or inverted."""
    from springfem.mechanics import explicit, stable_time_step

    scene = bar_scene(case["nx"], case["ny"], traction=-0.1 * case["factor"])
    system = _system(scene, case["method"])
    dt_crit, omega = stable_time_step(system)
    # critical damping of the lowest bending mode is far below omega_max; a mass damping
    # of ~omega_max/200 brings the bar near rest within the run
    try:
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
    inv = _inverted(scene, traj.x - system.x0)
    return {"status": "inverted" if inv else "ok", "inverted": inv}


# ------------------------------------------------------------------------------ run


@dataclass(frozen=True)
class Settings:
    """Grids of the stability study (bars of ``nx × ny × ny`` hexahedra).

    Parameters
    ----------
    dt_meshes, dt_steps, dt_bisections
        Meshes, run length and bisection count of the critical-time-step search.
    load_factors, load_mesh
        Load multiples and mesh of the largest-load series.
    nus, lock_mesh
        Poisson ratios and mesh of the locking series.
    map_loads, map_dt_factors, map_steps
        Load multiples, time-step factors and run length of the failure map (10 × 1 × 1).
    """

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


@study("stability", Settings)
def run(ctx: StudyContext, settings: Settings) -> StudyOutput:
    """Run the stability study (see the module docstring).

    Parameters
    ----------
    ctx
        Output folder, cache and preset.
    settings
        Grids of the four series.

    Returns
    -------
    StudyOutput
        Findings, four tables, figures and headline numbers.
    """
    import matplotlib.pyplot as plt

    q = settings
    out = StudyOutput(name=ctx.name, title="Stability: where each method fails")
    methods_dyn = ["spring-energy", "spring-cosine", "fem-neo-hookean", "fem-linear"]

    # 1. critical time step
    meshes = list(q.dt_meshes)
    cases = [
        {
            "kind": "dt",
            "method": m,
            "nx": nx,
            "ny": ny,
            "steps": q.dt_steps,
            "bisections": q.dt_bisections,
        }
        for m in methods_dyn
        for nx, ny in meshes
    ]
    res = ctx.cache.run(cases, critical_step_case, ctx.progress, "critical dt")
    df = pd.DataFrame(
        [{**{k: c[k] for k in ("method", "nx", "ny")}, **r} for c, r in zip(cases, res)]
    )
    df["tets"] = df["nx"] * df["ny"] ** 2 * 6
    df = df[["method", "tets", "dt_pred", "dt_measured", "ratio"]]
    out.tables.append(
        Table(
            write_table(df, ctx.path("critical_dt")),
            "Predicted critical step 2/ω_max against the measured largest "
            "stable step (bisection, undamped runs from a perturbed rest "
            "state); ratio = measured / predicted.",
        )
    )
    ratios = df.groupby("method")["ratio"].median()
    for m, r in ratios.items():
        out.headline[f"dt_ratio_{m}"] = round(float(r), 2)
    out.findings.append(
        "Measured/predicted critical step (median over meshes): "
        + ", ".join(f"{m} {r:.2f}" for m, r in ratios.items())
        + " — the linearised bound 2/ω_max predicts the explicit limit of the gradient-"
        "consistent models; a ratio far from 1 flags forces whose linearisation misleads."
    )

    # 2. largest load survived
    factors = list(q.load_factors)
    nx, ny = q.load_mesh
    lmethods = ["spring-energy", "spring-cosine", "fem-linear", "fem-neo-hookean"]
    cases = [
        {"kind": "load", "method": m, "factor": f, "nx": nx, "ny": ny}
        for m in lmethods
        for f in factors
    ]
    res = ctx.cache.run(cases, load_case, ctx.progress, "max load")
    dl = pd.DataFrame(
        [{"method": c["method"], "load_factor": c["factor"], **r} for c, r in zip(cases, res)]
    )
    dl["tip/L"] = dl["tip"] / 0.1
    dl = dl[["method", "load_factor", "status", "tip/L", "message"]]
    out.tables.append(
        Table(
            write_table(dl, ctx.path("max_load")),
            "Static solves of the cantilever under growing end load "
            "(factor × 0.1 Pa): status, tip deflection over length.",
        )
    )
    survive = {}
    for m in lmethods:
        ok = dl[(dl.method == m) & (dl.status == "ok")]["load_factor"]
        survive[m] = float(ok.max()) if len(ok) else 0.0
        out.headline[f"max_load_{m}"] = survive[m]
    out.findings.append(
        "Largest load factor solved without failure: "
        + ", ".join(f"{m} {v:g}" for m, v in survive.items())
        + "; failures are recorded as 'diverged' (solver), 'inverted' (J ≤ 0 elements) or, "
        "for linear FEM, 'unphysical' (tip deflection beyond 10% of the length, where "
        "small-strain kinematics no longer describe the bar)."
    )

    # 3. locking
    nus = list(q.nus)
    nx, ny = q.lock_mesh
    cases = [
        {"kind": "lock", "method": m, "nu": nu, "nx": nx, "ny": ny}
        for m in ("fem-p1", "fem-p2", "spring")
        for nu in nus
    ]
    res = ctx.cache.run(cases, locking_case, ctx.progress, "locking")
    dk = pd.DataFrame([{"method": c["method"], "nu": c["nu"], **r} for c, r in zip(cases, res)])
    out.tables.append(
        Table(
            write_table(dk, ctx.path("locking")),
            "Cantilever tip deflection / Timoshenko and relative volume change "
            "against Poisson's ratio.",
        )
    )
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    for m, g in dk.groupby("method"):
        ax[0].plot(g["nu"], g["tip_ratio"], "o-", label=m)
        ax[1].semilogy(g["nu"], np.abs(g["volume_change"]) + 1e-16, "o-", label=m)
    ax[0].axhline(1.0, color="k", lw=0.8, ls="--", label="Timoshenko")
    ax[0].set_xlabel("Poisson's ratio ν")
    ax[0].set_ylabel("tip deflection / Timoshenko")
    ax[0].set_title("bending vs ν (P1 locks as ν → 0.5)")
    ax[1].set_xlabel("Poisson's ratio ν")
    ax[1].set_ylabel("|ΔV| / V0")
    ax[1].set_title("volume change vs ν")
    for a in ax:
        a.grid(alpha=0.3)
        a.legend()
    hi = dk[dk.nu == max(nus)].set_index("method")["tip_ratio"]
    lo = dk[dk.nu == min(nus)].set_index("method")["tip_ratio"]
    out.figures.append(
        Figure(
            save_figure(fig, ctx.path("locking.png")),
            f"Tip deflection over Timoshenko against ν: from ν = {min(nus)} to "
            f"{max(nus)}, P1 goes {lo['fem-p1']:.2f} → {hi['fem-p1']:.2f}, "
            f"P2 {lo['fem-p2']:.2f} → {hi['fem-p2']:.2f}, spring "
            f"{lo['spring']:.2f} → {hi['spring']:.2f}.",
        )
    )
    for m in ("fem-p1", "fem-p2", "spring"):
        out.headline[f"locking_tip_ratio_{m}"] = round(float(hi[m]), 3)
    out.findings.append(
        f"Near incompressibility (ν = {max(nus)}) the P1 cantilever keeps "
        f"{hi['fem-p1']:.0%} of the Timoshenko deflection (locking), P2 {hi['fem-p2']:.0%}, "
        f"the spring model {hi['spring']:.0%}."
    )

    # 4. failure map
    lf = list(q.map_loads)
    df_ = list(q.map_dt_factors)
    nx, ny = (10, 1)
    mmethods = ["spring-energy", "spring-cosine", "fem-neo-hookean"]
    cases = [
        {
            "kind": "map",
            "method": m,
            "factor": f,
            "dt_factor": d,
            "nx": nx,
            "ny": ny,
            "steps": q.map_steps,
        }
        for m in mmethods
        for f in lf
        for d in df_
    ]
    res = ctx.cache.run(cases, failure_map_case, ctx.progress, "failure map")
    dm = pd.DataFrame(
        [
            {
                "method": c["method"],
                "load_factor": c["factor"],
                "dt_factor": c["dt_factor"],
                "status": r["status"],
            }
            for c, r in zip(cases, res)
        ]
    )
    out.tables.append(
        Table(
            write_table(dm, ctx.path("failure_map")),
            "Explicit damped dynamics on the load × time-step grid: ok, "
            "blew up, or ended with inverted elements.",
        )
    )
    codes = {"ok": 0, "inverted": 1, "blew up": 2}
    fig, axes = plt.subplots(1, len(mmethods), figsize=(4.2 * len(mmethods), 3.8), sharey=True)
    from matplotlib.colors import ListedColormap

    cmap = ListedColormap(["#4caf50", "#ff9800", "#d32f2f"])
    for a, m in zip(axes, mmethods):
        g = dm[dm.method == m]
        grid = np.array(
            [
                [codes[g[(g.load_factor == f) & (g.dt_factor == d)].status.iloc[0]] for d in df_]
                for f in lf
            ]
        )
        a.imshow(grid, cmap=cmap, vmin=0, vmax=2, origin="lower", aspect="auto")
        a.set_xticks(range(len(df_)), [f"{d:g}" for d in df_])
        a.set_yticks(range(len(lf)), [f"{f:g}" for f in lf])
        a.set_xlabel("dt / dt_crit (predicted)")
        a.set_title(m)
        for i in range(len(lf)):
            for j in range(len(df_)):
                a.text(j, i, list(codes)[grid[i, j]], ha="center", va="center", fontsize=7)
    axes[0].set_ylabel("load factor")
    ok_share = dm.groupby("method")["status"].apply(lambda s: float((s == "ok").mean()))
    out.figures.append(
        Figure(
            save_figure(fig, ctx.path("failure_map.png")),
            "Failure map (green ok, orange inverted elements, red blew up) of "
            "explicit damped runs; share of the grid that runs ok: "
            + ", ".join(f"{m} {v:.0%}" for m, v in ok_share.items())
            + ".",
        )
    )
    return out
