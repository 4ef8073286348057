"""The figure of the speed-accuracy study: CPU time against error, with the Pareto front of
all points and each model's own front (its non-dominated points, a thin line of its colour).
A plug-in's sweep (``xpbd 20x2 static`` ...) is one legend entry, each point labelled with its
level and settings (``2:40x2``)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..registry import Figure, StudyContext
from ..tables import plain_log_ticks, pyplot
from .cases import SAME, model_of, pareto_front

#: Marker per model, colour per solution method (by model for the static FEM).
MARKERS = {"spring-energy": "o", "spring-exact": "*", "P1": "s", "P1-NH": "s", "P2": "D",
           "P2-NH": "D", "corotational": "^", "xpbd": "v", "mass-spring": "P"}  # fmt: skip
COLOURS = {
    "spring-energy static": "tab:red",
    "spring-energy implicit": "tab:orange",
    "spring-energy explicit": "tab:pink",
    "spring-exact static": "tab:brown",
    "spring-exact explicit": "tab:gray",
    "P1-NH explicit": "tab:purple",
    "P1 static": "tab:blue",
    "P1-NH static": "tab:cyan",
    "P2 static": "tab:green",
    "P2-NH static": "tab:olive",
    "corotational static": "gold",
    "corotational explicit": "darkgoldenrod",
    "xpbd static": "indigo",
    "mass-spring static": "limegreen",
    "mass-spring explicit": "darkgreen",
}


def _family(method: str) -> tuple[str, str]:
    """``(legend entry, point label prefix)``: a sweep point ``model SETTING solution``
    joins its model's entry, labelled by its setting."""
    parts = method.split()
    if len(parts) == 3:
        return f"{parts[0]} {parts[2]}", parts[1]
    return method, ""


def _settings(text: str) -> dict[str, str]:
    """A sweep point's settings back from its table text (``substeps 20, iterations 2``)."""
    return dict(part.rsplit(" ", 1) for part in str(text).split(", "))


def _sweep_panel(ax, good: pd.DataFrame, colour: dict) -> bool:
    """The sweeps' error against P1-NH on the same mesh (:data:`.tables.SAME`) against CPU
    time: per model and level a line through each setting's series (the other settings at
    the plug-in's defaults; solid: the first setting, dotted: the next); ``False``: nothing
    to draw."""
    from .. import models

    if SAME not in good:  # no P1-NH point finished (or the law has none)
        return False
    swept = good[(good["method"].str.split().str.len() == 3) & (good[SAME] > 0)]
    if len(swept) < 2:
        return False
    shades = ("-", ":", "-.", "--")
    for j, ((model, factor), grp) in enumerate(
        swept.groupby([swept["method"].map(model_of), "factor"])
    ):
        defaults = {k: str(v) for k, v in models.get(model).settings.items()}
        own = grp["setting"].map(_settings)
        keys = list(dict.fromkeys(k for o in own for k in o))
        alpha = 1.0 - 0.25 * (j % 3)
        ax.scatter(grp["seconds"], 100 * grp[SAME], marker=MARKERS.get(model, "o"), s=36,
                   color=colour.get(model), edgecolor="k", linewidth=0.4, alpha=alpha,
                   label=f"{model}, level {factor}", zorder=3)  # fmt: skip
        for i, key in enumerate(keys):
            on = [all(v == defaults.get(k) for k, v in o.items() if k != key) for o in own]
            line = grp[on].assign(v=[float(o[key]) for o, keep in zip(own, on) if keep])
            line = line.sort_values("v")
            if len(line) < 2:
                continue
            ax.plot(line["seconds"], 100 * line[SAME], ls=shades[i % 4], lw=0.9,
                    color=colour.get(model), alpha=alpha, zorder=2,
                    label=f"{model}, level {factor}: by {key}")  # fmt: skip
        for _, r in grp.iterrows():
            ax.annotate(f"{r['factor']}:{_family(r['method'])[1]}", (r["seconds"], 100 * r[SAME]),
                        fontsize=6, xytext=(3, 2), textcoords="offset points")  # fmt: skip
    ax.set_xscale("log")
    ax.set_yscale("log")
    plain_log_ticks(ax.xaxis, ax.yaxis)
    ax.set_xlabel("CPU time (s)")
    ax.set_ylabel(f"{SAME} (%)")
    ax.set_title("sweeps: error against P1-NH Newton, same mesh", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=6)
    return True


def pareto_figure(
    ctx: StudyContext, df: pd.DataFrame, column: str, reference: str, front_text: str,
    label: str, suffix: str = "", reference_seconds: float | None = None,
) -> Figure:  # fmt: skip
    """Every solve's CPU time against its error ``column`` (log-log) with the Pareto front of
    all points and of each model; the findings' sentence about the front, ``front_text``,
    ends the caption. The reference, whose error is zero by definition and has no place on a
    log axis, is a vertical line at its CPU time ``reference_seconds``. With plug-in sweeps
    and the same-mesh column, a second panel shows their error against P1-NH on the same
    mesh (XPBD's substep error).
    """
    plt = pyplot()

    good = df[(df["status"] == "ok") & (df[column] > 0)]
    fig, (ax, side) = plt.subplots(1, 2, figsize=(14, 7.6), width_ratios=(2.2, 1))
    entry = good["method"].map(lambda m: _family(m)[0])
    colour: dict = {}
    for method, grp in good.groupby(entry, sort=False):
        swept = len(grp["method"].iloc[0].split()) == 3
        what = "substeps x iterations" if model_of(method) == "xpbd" else "its settings"
        dots = ax.scatter(grp["seconds"], 100 * grp[column], zorder=3,
                          label=f"{method} ({what})" if swept else method,
                          marker=MARKERS.get(model_of(method), "o"), color=COLOURS.get(method),
                          s=46, edgecolor="k", linewidth=0.4)  # fmt: skip
        colour.setdefault(model_of(method), dots.get_facecolor()[0])
        for _, r in grp.iterrows():
            tag = _family(r["method"])[1]
            ax.annotate(f"{r['factor']}:{tag}" if tag else str(r["factor"]),
                        (r["seconds"], 100 * r[column]), fontsize=6, xytext=(3, 2),
                        textcoords="offset points")  # fmt: skip
    for model, grp in good.groupby(good["method"].map(model_of), sort=False):
        if len(grp) < 2:
            continue
        own = grp[pareto_front(grp["seconds"].to_numpy(), grp[column].to_numpy())]
        own = own.sort_values("seconds")
        ax.step(own["seconds"], 100 * own[column], where="post", color=colour[model], lw=0.9,
                alpha=0.6, zorder=2)  # fmt: skip
    front = good[good["pareto"]].sort_values("seconds")
    if len(front):
        fx = np.r_[front["seconds"].to_numpy(), good["seconds"].max() * 1.5]
        fy = np.r_[100 * front[column].to_numpy(), 100 * front[column].iloc[-1]]
        ax.step(fx, fy, where="post", color="k", ls="--", lw=1, label="Pareto front", zorder=2)
    if reference_seconds is not None and np.isfinite(reference_seconds):
        ax.axvline(reference_seconds, color="k", ls=":", lw=1.2, zorder=1,
                   label=f"reference {reference}: {reference_seconds:.2g} s, error 0")  # fmt: skip
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("CPU time from scene to answer (s)")
    ax.set_ylabel(f"{column} vs {reference} (%)")
    ax.set_title(f"{label}: time against error (labels: refinement factor[:settings])")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=4)
    panel = _sweep_panel(side, good, colour)
    if not panel:
        side.set_axis_off()
    fig.tight_layout()
    caption = (
        f"CPU time against error of every solve of {label} (log-log; labels: refinement "
        f"factor of its mesh, and a sweep point's settings), with the Pareto front of all "
        "points (dashed), each model's own front (thin, its colour)"
        + (
            f" and the reference's time (dotted; {reference}, error 0 by definition). "
            if reference_seconds is not None
            else ". "
        )
        + (
            "Right: the plug-in sweeps' error against P1-NH Newton on the same mesh (for "
            "XPBD the error of its substeps and iterations). "
            if panel
            else ""
        )
        + front_text
    )
    return ctx.figure(fig, f"pareto{suffix}.png", caption)
