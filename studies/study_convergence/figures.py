"""Figures of the convergence study: error rates, and ``w`` and the spring–P1 gap against h."""

from __future__ import annotations

import numpy as np

from ..plots import loglog_rates
from ..registry import Figure, StudyContext
from ..tables import pyplot
from .cases import SPRING
from .findings import limit_sentence
from .tables import L2, Analysis


def _present(a: Analysis) -> list[str]:
    return [m for m in a.plan.models if m in a.rate]


def rate_figure(ctx: StudyContext, a: Analysis, suffix: str = "") -> Figure:
    """The L2 and ``w`` errors of every model against h, log-log, with fitted rates."""
    plt = pyplot()
    df = a.levels[a.levels["status"] == "ok"]
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    curves_l2, curves_w = {}, {}
    for m in _present(a):
        d = df[df["model"] == m].sort_values("h")
        curves_l2[m] = (d["h"], d[L2])
        curves_w[m] = (d["h"], d["w err"])
    ticks = sorted(df["h"].unique())
    n1 = len(a.ref["u_coarse"])
    rates = {m: a.rate[m] for m in _present(a)}
    h = "h (mean edge length)"
    l2_rates = {m: r["l2"] for m, r in rates.items()}
    loglog_rates(left, curves_l2, h, f"relative L2 error at the {n1} level-1 vertices",
                 l2_rates, xticks=ticks)  # fmt: skip
    loglog_rates(right, curves_w, h, f"relative error of {a.track.label}",
                 {m: r["tip"] for m, r in rates.items()}, xticks=ticks)  # fmt: skip
    fig.tight_layout()
    p2 = a.plan.fem[1]
    left.set_title(f"{a.plan.scene.label}: displacement vs {p2} on level {a.plan.ref}", fontsize=10)
    right.set_title(a.track.label, fontsize=10)
    p1 = a.plan.fem[0]
    e = df[df["model"].isin([SPRING, p1])].pivot(index="factor", columns="model", values=L2)
    n_below = int((e[SPRING] < e[p1]).sum()) if {SPRING, p1} <= set(e.columns) else 0
    text = ", ".join(f"{m} {rates[m]['l2']:.2f}" for m in rates)
    return ctx.figure(
        fig,
        f"convergence{suffix}.png",
        f"Errors against the {p2} reference under refinement, log-log, fitted rates in the "
        f"legend (L2: {text}); {SPRING}'s error is below {p1}'s on {n_below} of {len(e)} levels.",
    )


def tip_figure(ctx: StudyContext, a: Analysis, suffix: str = "") -> Figure:
    """``w`` over the reference per level, and ``|spring / P1 − 1|`` against h."""
    plt = pyplot()
    df = a.levels[a.levels["status"] == "ok"]
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2))
    for m, mk in zip(_present(a), "o*sD", strict=False):
        d = df[df["model"] == m].sort_values("factor")
        ax.plot(d["factor"], d["w / w_ref"], marker=mk, label=m)
    ax.axhline(1.0, color="k", lw=0.8, label=f"{a.plan.fem[1]} reference (level {a.plan.ref})")
    if a.analytic is not None:
        value, source = a.analytic
        ax.axhline(value / a.w_ref, color="gray", ls="--", lw=0.8, label=source)
    ax.set_xscale("log")
    ks = sorted(df["factor"].unique())
    ax.set_xticks(ks, [str(k) for k in ks])
    ax.minorticks_off()
    ax.set_xlabel(f"refinement factor of {a.plan.scene.label}'s mesh")
    ax.set_ylabel("w / reference")
    ax.set_title(f"{a.track.label} under refinement", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    p1 = a.plan.fem[0]
    name = f"|{SPRING} / {p1} − 1| (same mesh)"
    h = a.plan.h1 / np.asarray(a.gap.index, float)
    loglog_rates(bx, {name: (h, a.gap.abs().values)}, "h (mean edge length)",
                 f"|{SPRING} / {p1} − 1| of w", {name: a.gap_rate}, xticks=sorted(h))  # fmt: skip
    bx.set_title("does the spring–P1 gap close under refinement?", fontsize=10)
    fig.tight_layout()
    return ctx.figure(
        fig,
        f"tip_deflection{suffix}.png",
        f"Left: {a.track.label} normalised by the P2 reference under refinement. Right: the "
        "spring model's w relative to P1 on the same mesh. " + limit_sentence(a),
    )
