"""The figure of the speed-accuracy study: CPU time against error, with the Pareto front."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..registry import Figure, StudyContext
from ..tables import pyplot

#: Marker per model, colour per solution method (by model for the static FEM).
MARKERS = {"spring-energy": "o", "spring-exact": "*", "P1": "s", "P1-NH": "s", "P2": "D",
           "P2-NH": "D", "corotational": "^"}  # fmt: skip
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
}


def pareto_figure(
    ctx: StudyContext, df: pd.DataFrame, column: str, reference: str, front_text: str,
    label: str, suffix: str = "", reference_seconds: float | None = None,
) -> Figure:  # fmt: skip
    """Every solve's CPU time against its error ``column`` (log-log) with the Pareto front;
    the findings' sentence about the front, ``front_text``, ends the caption. The reference,
    whose error is zero by definition and has no place on a log axis, is a vertical line at
    its CPU time ``reference_seconds``.
    """
    plt = pyplot()

    good = df[(df["status"] == "ok") & (df[column] > 0)]
    fig, ax = plt.subplots(figsize=(8.5, 5.6))
    for method, grp in good.groupby("method", sort=False):
        ax.scatter(grp["seconds"], 100 * grp[column], marker=MARKERS.get(method.split()[0], "o"),
                   color=COLOURS.get(method), s=46, label=method, edgecolor="k",
                   linewidth=0.4, zorder=3)  # fmt: skip
        for _, r in grp.iterrows():
            ax.annotate(str(r["factor"]), (r["seconds"], 100 * r[column]), fontsize=6,
                        xytext=(3, 2), textcoords="offset points")  # fmt: skip
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
    ax.set_title(f"{label}: time against error (labels: refinement factor)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    caption = (
        f"CPU time against error of every solve of {label} (log-log; labels: refinement "
        f"factor of its mesh), with the Pareto front"
        + (
            f" and the reference's time (dotted; {reference}, error 0 by definition). "
            if reference_seconds is not None
            else ". "
        )
        + front_text
    )
    return ctx.figure(fig, f"pareto{suffix}.png", caption)
