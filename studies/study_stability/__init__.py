"""Study ``stability``: where each method fails.

1. Critical time step: the measured largest stable explicit step (bisection on runs from a
   perturbed rest state, loads off) against the predicted ``2 / omega_max``, for the spring
   variants, the explicit P1 FEM and the plug-in models with a mechanical system; for a
   plug-in with its own step search (XPBD, Gauss–Seidel and Jacobi) the largest substep it
   survives, against ``2 / omega_max`` of its own energy.
2. Largest load survived: the scene's loads times growing factors, solved statically by the
   spring variants, small-strain FEM (past 10 % of the body's size its solution is no
   solution: ``unphysical``), neo-Hookean Newton and the plug-in models; what fails is
   recorded. A summary (``survival``) gives every method's largest step and load.
3. Near-incompressibility, on a scene with a beam-theory reference (the bundled bar): tip
   deflection and volume change against Poisson's ratio for P1 (locks), P2 and the springs.
4. Failure map: load factor × time-step factor, explicit damped dynamics, per method.

Bundled: the cantilever bar (0.1 × 0.01 × 0.01 m) on the settings' meshes; ``--scene FILE``
runs every series but the locking one on the user's scene. The explicit FEM has isotropic
laws only: on an anisotropic scene the explicit series run the spring variants.
:mod:`.cases` holds the settings, the bar and one run per series.

Examples
--------
>>> [s.label for s in bundled_scenes(Settings.quick())]
['bar 10x1x1', 'bar 20x2x2']
>>> dt = pd.DataFrame({"scene": ["a"], "method": ["m"], "dt_measured": [2e-3],
...                    "ratio": [1.0]})
>>> ld = pd.DataFrame({"scene": ["a", "a"], "method": ["m", "m"], "load_factor": [1, 10],
...                    "status": ["ok", "diverged"]})
>>> survival({"dt": dt, "load": ld}).iloc[0].to_dict()["max load factor"]
1.0
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .. import models
from ..registry import Figure, StudyContext, StudyOutput, study
from ..scenes import StudyScene, case_scene
from ..tables import plain_log_ticks, pyplot
from .cases import LOCK_METHODS, UNPHYSICAL, WORK, Settings, bundled_scenes, grids, own_steppers

__all__ = ["Settings", "bundled_scenes", "run", "survival"]

#: The case keys each series' frame keeps beside the scene and method, with their column names.
KEYS = {
    "dt": {},
    "load": {"factor": "load_factor"},
    "lock": {"nu": "nu"},
    "map": {"factor": "load_factor", "dt_factor": "dt_factor"},
}
#: The result columns each series' table shows.
COLUMNS = {
    "dt": ["scene", "method", "tets", "dt_pred", "dt_measured", "ratio", "setting_h", "failure"],
    "load": ["scene", "method", "load_factor", "status", "u/size", "message"],
    "lock": ["scene", "method", "nu", "tip_ratio", "volume_change", "inverted"],
    "map": ["scene", "method", "load_factor", "dt_factor", "status"],
}


def frames(cases: dict[str, list[dict]], results: dict[str, list[dict]]) -> dict[str, pd.DataFrame]:
    """The four series as frames: ``dt`` (scene, method, tets, predicted and measured step,
    ratio), ``load`` (load factor, status, largest |u| over the body's size, message),
    ``lock`` (ν, tip ratio, volume change, inverted) and ``map`` (load factor, dt factor,
    status).
    """
    out = {}
    for k, keys in KEYS.items():
        rows = []
        for c, r in zip(cases[k], results[k], strict=True):
            row = {"scene": c["scene"], "method": c["method"]}
            row.update({name: c[key] for key, name in keys.items()})
            if k == "dt":
                row["tets"] = case_scene(c).mesh.n_tets
            rows.append({**row, **r})
        out[k] = pd.DataFrame(rows, columns=None if rows else COLUMNS[k])
        out[k] = out[k].reindex(columns=COLUMNS[k])
    return out


def survival(f: dict[str, pd.DataFrame]) -> pd.DataFrame:
    """Every method's largest step and ratio on the ``dt`` series' first scene, its largest
    load factor solved without failure on the ``load`` series' first scene (``nan``: not in
    the series) and the smallest that failed (``nan``: none)."""
    dt, dl = f["dt"], f["load"]
    dt = dt[dt.scene == dt.scene.iloc[0]] if len(dt) else dt
    dl = dl[dl.scene == dl.scene.iloc[0]] if len(dl) else dl
    rows = []
    for m in dict.fromkeys([*dt["method"], *dl["method"]]):
        d = dt[dt.method == m]
        ok = dl[(dl.method == m) & (dl.status == "ok")]["load_factor"]
        bad = dl[(dl.method == m) & (dl.status != "ok")]["load_factor"]
        rows.append({
            "method": m,
            "dt scene": d.scene.iloc[0] if len(d) else "",
            "largest step (s)": float(d.dt_measured.iloc[0]) if len(d) else float("nan"),
            "step / 2/ω_max": float(d.ratio.iloc[0]) if len(d) else float("nan"),
            "load scene": dl.scene.iloc[0] if (dl.method == m).any() else "",
            "max load factor": (float(ok.max()) if len(ok) else 0.0) if (dl.method == m).any()
            else float("nan"),
            "first failing factor": float(bad.min()) if len(bad) else float("nan"),
        })  # fmt: skip
    return pd.DataFrame(rows)


def locking_figure(ctx: StudyContext, dk: pd.DataFrame, q: Settings) -> Figure:
    """Tip deflection over Timoshenko and volume change against Poisson's ratio."""
    plt = pyplot()

    nus = list(q.nus)
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
    return ctx.figure(
        fig,
        "locking.png",
        f"Tip deflection over Timoshenko against ν: from ν = {min(nus)} to "
        f"{max(nus)}, P1 goes {lo['P1']:.2f} → {hi['P1']:.2f}, "
        f"P2 {lo['P2']:.2f} → {hi['P2']:.2f}, spring "
        f"{lo['spring']:.2f} → {hi['spring']:.2f}.",
    )


def failure_map_figure(
    ctx: StudyContext, dm: pd.DataFrame, q: Settings, methods: tuple[str, ...]
) -> Figure:
    """The failure map, one panel per method: ok, inverted or blew up on the load × dt grid."""
    plt = pyplot()
    from matplotlib.colors import ListedColormap

    lf, df_ = list(q.map_loads), list(q.map_dt_factors)
    mmethods = [m for m in methods if m in set(dm.method)]
    codes = {"ok": 0, "inverted": 1, "blew up": 2, "not run": 3}  # not run: stopped, skipped
    fig, axes = plt.subplots(1, len(mmethods), figsize=(4.2 * len(mmethods), 3.8), sharey=True)
    axes = np.atleast_1d(axes)
    cmap = ListedColormap(["#4caf50", "#ff9800", "#d32f2f", "#bdbdbd"])
    for a, m in zip(axes, mmethods):
        g = dm[dm.method == m]
        grid = np.array(
            [
                [
                    codes.get(g[(g.load_factor == f) & (g.dt_factor == d)].status.iloc[0], 3)
                    for d in df_
                ]
                for f in lf
            ]
        )
        a.imshow(grid, cmap=cmap, vmin=0, vmax=3, origin="lower", aspect="auto")
        a.set_xticks(range(len(df_)), [f"{d:g}" for d in df_])
        a.set_yticks(range(len(lf)), [f"{f:g}" for f in lf])
        a.set_xlabel("dt / dt_crit (predicted)")
        a.set_title(m)
        for i in range(len(lf)):
            for j in range(len(df_)):
                a.text(j, i, list(codes)[grid[i, j]], ha="center", va="center", fontsize=7)
    axes[0].set_ylabel("load factor")
    ran = dm[dm["status"].isin(codes) & (dm["status"] != "not run")]
    ok_share = ran.groupby("method")["status"].apply(lambda s: float((s == "ok").mean()))
    return ctx.figure(
        fig,
        "failure_map.png",
        "Failure map (green ok, orange inverted elements, red blew up, grey not run: the "
        "budget stopped or skipped it) of "
        "explicit damped runs; share of the cells that ran that run ok: "
        + ", ".join(f"{m} {v:.0%}" for m, v in ok_share.items())
        + ".",
    )


def survival_figure(ctx: StudyContext, sv: pd.DataFrame, dt: pd.DataFrame) -> Figure:
    """Every method's largest stable step (left) and largest load factor solved (right), the
    plug-in peers in red; ``≥`` marks a method no factor of the series failed."""
    plt = pyplot()
    fig, ax = plt.subplots(1, 2, figsize=(11, 0.42 * len(sv) + 1.9), layout="constrained")
    y = np.arange(len(sv))
    peers = {*models.plugins(), *own_steppers(models.plugins())}
    colours = ["tab:red" if m in peers else "tab:blue" for m in sv.method]
    step, load = sv["largest step (s)"].to_numpy(), sv["max load factor"].to_numpy()
    ax[0].scatter(step, y, c=colours, s=40, zorder=3)
    for i, v in enumerate(step):
        if v == v:
            ax[0].annotate(f"{v:.3g} s", (v, i), xytext=(6, -3), textcoords="offset points",
                           fontsize=8)  # fmt: skip
    h = dt["setting_h"].dropna()
    if len(h):
        ax[0].axvline(float(h.iloc[0]), color="k", ls="--", lw=1,
                      label=f"XPBD's configured substep {float(h.iloc[0]):.3g} s")  # fmt: skip
        ax[0].legend(fontsize=8, loc="upper left")
    ax[0].set_xscale("log")
    plain_log_ticks(ax[0].xaxis)
    ax[0].set_xlabel("largest stable step (s): explicit step; XPBD: substep")
    ax[0].set_title(f"largest step ({sv['dt scene'].iloc[0]})")
    solved = np.where(load > 0, load, np.nan)  # 0: failed at every factor (no log position)
    ax[1].scatter(solved, y, c=colours, s=40, zorder=3)
    for i, (v, bad) in enumerate(zip(load, sv["first failing factor"])):
        if v != v:
            where = ("axes fraction", "data")
            ax[1].annotate("not in this series", (0.02, i), xytext=(0, -3), fontsize=8,
                           xycoords=where, textcoords="offset points")  # fmt: skip
            continue
        if v <= 0:
            ax[1].scatter([bad], [i], marker="x", c=[colours[i]], s=40, zorder=3)
            text, at = f"fails at every factor (first: {bad:g})", bad
        else:
            text, at = ("≥ " if bad != bad else "") + f"{v:g}", v
        ax[1].annotate(text, (at, i), xytext=(6, -3), textcoords="offset points", fontsize=8)
    ax[1].set_xscale("log")
    ax[1].set_xlabel("largest load factor solved without failure (≥: none of the series failed)")
    ax[1].set_title(f"largest load ({sv['load scene'].iloc[0]})")
    for a in ax:
        a.set_yticks(y, list(sv.method))
        a.set_ylim(len(sv) - 0.5, -0.5)
        a.margins(x=0.25)
        a.grid(alpha=0.3, which="both")
    steps = ", ".join(f"{m} {v:.3g} s" for m, v in zip(sv.method, step) if v == v)
    return ctx.figure(
        fig,
        "survival.png",
        "Largest stable step (left; XPBD: its largest surviving substep, the dashed line its "
        "configured one) and largest load factor solved (right) of every method, the plug-in "
        f"peers in red: {steps}.",
    )


@study("stability", Settings, bundled_scenes)
def run(ctx: StudyContext, scenes: list[StudyScene], settings: Settings) -> StudyOutput:
    """Critical steps, largest loads, locking and the failure map.

    Headline: ``dt_ratio_<method>`` (median measured/predicted step over the meshes),
    ``<plug-in>_setting_over_limit_<method>`` (a configured step over the largest that
    survives), ``max_load_<method>``, ``locking_tip_ratio_<method>`` (at the largest ν).
    """
    cases = grids(scenes, settings)
    res = {k: ctx.cache.run(cases[k], fn, ctx.progress, label) for k, (fn, label) in WORK.items()}
    f = frames(cases, res)
    findings: list[str] = []
    headline: dict[str, float] = {}
    tables, figures = [], []
    if len(f["dt"]) or len(f["load"]):
        tables.append(ctx.table(survival(f), "survival", (
            "Every method's largest step and largest load: the largest stable explicit step "
            "(XPBD: the largest surviving substep) on the critical-step series' first scene, "
            "and the largest load factor solved without failure on the largest-load series' "
            "first scene (nan: not in that series).")))  # fmt: skip
    if len(f["dt"]) and len(f["load"]):
        figures.append(survival_figure(ctx, survival(f), f["dt"]))

    if len(dt := f["dt"]):
        ratios = dt.groupby("method", sort=False)["ratio"].median()
        headline.update({f"dt_ratio_{m}": round(float(r), 2) for m, r in ratios.items()})
        own = own_steppers(models.plugins())  # a plug-in's own step search: own finding
        findings.append(
            "Measured/predicted critical step (median over meshes): "
            + ", ".join(f"{m} {r:.2f}" for m, r in ratios.items() if m not in own)
            + " — the linearised bound 2/ω_max predicts the explicit limit of the gradient-"
            "consistent models; a ratio far from 1 flags forces whose linearisation misleads."
        )
        over: dict[str, list[float]] = {}
        for scene, g in dt[dt.method.isin(tuple(own))].groupby("scene", sort=False):
            parts = []
            for _, r in g.iterrows():
                if r.ratio != r.ratio:
                    parts.append(f"{r.method} fails at every step tried ({r.failure})")
                    continue
                o = float(r.setting_h / r.dt_measured)
                over.setdefault(r.method, []).append(o)
                parts.append(
                    f"{r.method} {r.ratio:.2f} × 2/ω_max ({r.dt_measured:.3g} s; the "
                    f"configured {r.setting_h:.3g} s is {o:.2f} of it"
                    + (f"; beyond it: {r.failure}" if r.failure else "")
                    + ")"
                )
            findings.append(
                f"Largest surviving step of the models with their own dynamics on {scene} "
                "(undamped, loads off, the explicit runs' perturbation; against 2/ω_max of "
                "each one's own energy): " + "; ".join(parts)
                + (" — on this scene their own integration does not lift the explicit limit "
                   "of their energy by much: a little past it the energy grows without bound."
                   if (g.ratio < 4).all() else ".")
            )  # fmt: skip
        for m, v in over.items():
            headline[f"{own[m][0]}_setting_over_limit_{m}"] = round(float(np.median(v)), 3)
        tables.append(ctx.table(dt, "critical_dt",
            "Predicted critical step 2/ω_max against the measured largest stable step "
            "(bisection, undamped runs from a perturbed rest state, loads off); ratio = "
            "measured / predicted. XPBD (its own settings, and Jacobi): the largest substep "
            "h it survives (finite, no inverted element, energy within 100x of its start) "
            "against 2/ω_max of its own energy; setting_h is its configured substep "
            "dt/substeps, failure why the first failing step failed."))  # fmt: skip

    if len(dl := f["load"]):
        first = dl[dl.scene == dl.scene.iloc[0]]
        survive = {}
        for m in dict.fromkeys(first["method"]):
            ok = first[(first.method == m) & (first.status == "ok")]["load_factor"]
            survive[m] = headline[f"max_load_{m}"] = float(ok.max()) if len(ok) else 0.0
        findings.append(
            f"Largest load factor solved without failure ({dl.scene.iloc[0]}, of "
            + ", ".join(f"{x:g}" for x in dict.fromkeys(first["load_factor"])) + "): "
            + ", ".join(f"{m} {v:g}" for m, v in survive.items())
            + "; failures are recorded as 'diverged' (solver), 'inverted' (J ≤ 0 elements) "
            f"or, for a small-strain law, 'unphysical' (largest displacement beyond "
            f"{UNPHYSICAL:.0%} of the body's size, where small-strain kinematics no longer "
            "describe the body)."
        )  # fmt: skip
        tables.append(ctx.table(dl, "max_load",
            "Static solves under the scene's loads times the load factor: status and the "
            "largest displacement over the body's size."))  # fmt: skip

    if len(dk := f["lock"]):
        hi = dk[dk.nu == max(settings.nus)].set_index("method")["tip_ratio"]
        for m in LOCK_METHODS:
            headline[f"locking_tip_ratio_{m}"] = round(float(hi[m]), 3)
        findings.append(
            f"Near incompressibility (ν = {max(settings.nus)}) the P1 cantilever keeps "
            f"{hi['P1']:.0%} of the Timoshenko deflection (locking), P2 {hi['P2']:.0%}, "
            f"the spring model {hi['spring']:.0%}, the exact spring element "
            f"{hi['spring-exact']:.0%}: it is P1's element at small strain, so it locks like "
            "P1 — the freedom from locking of the specification's element is its calibration "
            "error, not a virtue of springs."
        )
        tables.append(ctx.table(dk, "locking", "Cantilever tip deflection / Timoshenko and "
                                "relative volume change against Poisson's ratio."))  # fmt: skip
        figures.insert(len(figures) and 1, locking_figure(ctx, dk, settings))

    dm = f["map"]
    ran = dm[dm["status"].isin(RAN)] if len(dm) else dm
    if len(ran):  # the cells the budget stopped or skipped are no verdict either way
        share = ran.groupby("method", sort=False)["status"].apply(lambda s: (s == "ok").mean())
        missing = len(dm) - len(ran)
        findings.append(
            "Share of the load × time-step grid that runs ok in damped explicit dynamics: "
            + ", ".join(f"{m} {v:.0%}" for m, v in share.items())
            + (f" ({missing} cells not run: the budget stopped or skipped them)" if missing else "")
            + "."
        )
    elif len(dm):
        findings.append("No cell of the failure map ran within the budget.")
    if len(dm):
        tables.append(ctx.table(dm, "failure_map",
            "Explicit damped dynamics on the load × time-step grid: ok, blew up, or ended "
            "with inverted elements."))  # fmt: skip
        figures.append(failure_map_figure(ctx, dm, settings, tuple(dict.fromkeys(dm["method"]))))
    return StudyOutput(
        name=ctx.name,
        title=f"Stability: where each method fails ({', '.join(s.label for s in scenes)})",
        findings=findings,
        tables=tables,
        figures=figures,
        headline=headline,
    )


#: Failure-map statuses of a run that ended (not stopped or skipped by the budget).
RAN = ("ok", "inverted", "blew up")
