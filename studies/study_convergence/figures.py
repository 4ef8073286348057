"""Figures of the convergence study: error rates and tip deflection against h."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..registry import Figure, StudyContext
from ..tables import save_figure
from .cases import MODELS, SIZE, Settings
from .findings import limit_sentence


def rate_figure(ctx: StudyContext, df: pd.DataFrame, rates: dict, cfg: Settings) -> Figure:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..plots import loglog_rates

    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    curves_l2, curves_tip = {}, {}
    for m in MODELS:
        d = df[df["model"] == m].sort_values("h (m)")
        curves_l2[m] = (1e3 * d["h (m)"], d["L2 err (coarse vertices)"])
        curves_tip[m] = (1e3 * d["h (m)"], d["tip err"])
    ticks = sorted(1e3 * df["h (m)"].unique())
    loglog_rates(
        a,
        curves_l2,
        "h (mm)",
        "relative L2 error at coarse vertices",
        {m: rates[m]["l2"] for m in MODELS},
        xticks=ticks,
    )
    loglog_rates(
        b,
        curves_tip,
        "h (mm)",
        "relative tip-deflection error",
        {m: rates[m]["tip"] for m in MODELS},
        xticks=ticks,
    )
    fig.tight_layout()
    a.set_title(f"displacement at the 44 level-1 vertices vs P2 (k = {cfg.ref})", fontsize=10)
    b.set_title("tip deflection", fontsize=10)
    sp, p1, p2 = rates["spring"], rates["P1"], rates["P2"]
    e_sp = df[df["model"] == "spring"].set_index("k")["L2 err (coarse vertices)"]
    e_p1 = df[df["model"] == "P1"].set_index("k")["L2 err (coarse vertices)"]
    n_below = int((e_sp < e_p1.loc[e_sp.index]).sum())
    return Figure(
        save_figure(fig, ctx.path("convergence.png")),
        "Errors against the fine P2 reference under h-refinement, log-log, fitted rates in the "
        f"legend: P2 converges fastest (L2 rate {p2['l2']:.2f}), P1 at {p1['l2']:.2f} and the "
        f"spring model at {sp['l2']:.2f}; the spring model's error is below P1's on "
        f"{n_below} of {len(e_sp)} levels.",
    )


def tip_figure(
    ctx: StudyContext,
    df: pd.DataFrame,
    rates: dict,
    w_ref: float,
    timo: float,
    cfg: Settings,
    extra: dict,
) -> Figure:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..plots import loglog_rates

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2))
    for m, mk in zip(MODELS, "o*sD", strict=True):
        d = df[df["model"] == m].sort_values("k")
        ax.plot(d["k"], d["w / w_ref"], marker=mk, label=m)
    ax.axhline(1.0, color="k", lw=0.8, label=f"P2 reference (k = {cfg.ref})")
    ax.axhline(timo / w_ref, color="gray", ls="--", lw=0.8, label="Timoshenko beam")
    ax.set_xscale("log")
    ks = sorted(df["k"].unique())
    ax.set_xticks(ks, [str(k) for k in ks])
    ax.minorticks_off()
    ax.set_xlabel("k (mesh [10, 1, 1]·k hexahedra)")
    ax.set_ylabel("tip deflection / reference")
    ax.set_title("tip deflection under refinement", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    gap = extra["gap"]
    h = 1e3 * SIZE[1] / np.asarray(gap.index, float)
    loglog_rates(
        bx,
        {"|spring / P1 − 1| (same mesh)": (h, gap.abs().values)},
        "h (mm)",
        "|spring / P1 − 1| of the tip deflection",
        {"|spring / P1 − 1| (same mesh)": extra["gap_rate"]},
        xticks=sorted(h),
    )
    bx.set_title("does the spring–P1 gap close under refinement?", fontsize=10)
    fig.tight_layout()
    return Figure(
        save_figure(fig, ctx.path("tip_deflection.png")),
        "Left: tip deflection normalised by the P2 reference under refinement. Right: the "
        "spring model's tip deflection relative to P1 on the same mesh. "
        + limit_sentence(rates, extra),
    )
