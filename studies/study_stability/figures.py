"""Figures of the stability study: locking against ν, and the failure map."""

from __future__ import annotations

import numpy as np
import pandas as pd

from .. import models
from ..registry import Figure, StudyContext
from ..tables import plain_log_ticks, pyplot
from .cases import Settings, own_steppers


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
