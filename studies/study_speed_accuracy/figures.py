"""The figure of the speed-accuracy study: CPU time against tip error, Pareto front."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..registry import Figure, StudyContext
from ..tables import save_figure
from .cases import LABELS, STYLE, Settings


def pareto_figure(ctx: StudyContext, df: pd.DataFrame, p: Settings, front_text: str) -> Figure:
    """Every solve's CPU time against its tip error (log-log) with the Pareto front.

    Parameters
    ----------
    ctx
        Where to write.
    df
        The points (:func:`~.tables.points_frame`).
    p
        The study's settings.
    front_text
        The findings' sentence about the front (ends the caption).

    Returns
    -------
    Figure
    """
    import matplotlib.pyplot as plt

    rx, ry = p.reference
    good = df[df["status"] == "ok"]
    fig, ax = plt.subplots(figsize=(8.5, 5.6))
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
    caption = (
        f"CPU time against tip error of every solve of the cantilever (log-log; labels: "
        f"elements along the beam), with the Pareto front. {front_text}"
    )
    return Figure(save_figure(fig, ctx.path("pareto.png")), caption)
