"""The figure of the scaling study: cost per explicit step and per static solve."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..registry import Figure, StudyContext
from ..tables import pyplot
from .cases import STATIC_METHODS


def _tet_axis(ax) -> None:
    """Tet counts as 1,000 / 3,000 / 10,000 ... (one decade may hold one power of ten)."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    ax.xaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 3.0)))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:,.0f}"))
    ax.xaxis.set_minor_formatter(NullFormatter())


def scaling_figure(
    ctx: StudyContext, sdf: pd.DataFrame, tdf: pd.DataFrame, slope: dict[str, float], caption: str
) -> Figure:
    """CPU time per explicit step and per static solve against tet count (log-log)."""
    plt = pyplot()

    n_step = sdf["tets"].to_numpy(float)
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
    ax = axes[1]
    colours = {"spring": "tab:red", "P1": "tab:blue", "P1-NH": "tab:cyan"}
    for m, label in STATIC_METHODS.items():
        g = tdf[tdf["method"] == m]
        rate = slope["static_" + m.split("/")[0]]
        ax.loglog(g["tets"], g["cpu_s"], "s-", color=colours[m], label=f"{label}: slope {rate:.2f}")
    for ax, ylabel, title in (
        (axes[0], "CPU ms per explicit step", "Explicit step (serial)"),
        (axes[1], "CPU s per static solve", "Static solve (set-up included)"),
    ):
        _tet_axis(ax)
        ax.set_xlabel("tets")
        ax.set_ylabel(ylabel)
        ax.set_title(title)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    return ctx.figure(fig, "scaling.png", caption)
