"""Figures of the locking study: deflection against the Poisson ratio, error against cost."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..registry import Figure, StudyContext
from ..tables import pyplot
from .cases import METHODS, REFERENCE, TOLERANCE

#: Errors below this are drawn on it (the log axis has no zero).
ERROR_FLOOR = 1e-4


def _style(plt) -> tuple[dict[str, str], dict[str, str]]:
    names = list(METHODS)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    colors = dict(zip(names, colors * 2))
    markers = dict(zip(names, "os^Dv<>PXh*"))
    return colors, markers


def _ordered(handles: dict[str, object]) -> list[str]:
    """Legend keys in the order of :data:`METHODS`, other entries last."""
    rank = {m: i for i, m in enumerate(METHODS)}
    return sorted(handles, key=lambda k: rank.get(k, len(rank)))


def deflection_figure(ctx: StudyContext, df: pd.DataFrame) -> Figure:
    """The deflection as a share of the reference against ``0.5 - nu`` (log), finest level
    of every method, one panel per scene."""
    plt = pyplot()
    colors, markers = _style(plt)
    scenes = list(df.scene.unique())
    fig, axes = plt.subplots(1, len(scenes), figsize=(5.2 * len(scenes), 4.4), squeeze=False,
                             layout="constrained")  # fmt: skip
    handles: dict[str, object] = {}
    for ax, scene in zip(axes[0], scenes):
        g = df[df.scene == scene]
        tets = int(g.tets.dropna().max()) if g.tets.notna().any() else 0
        ok = g[g.status == "ok"].sort_values("factor")
        g = ok.groupby(["method", "nu"], sort=False).tail(1)  # each method's finest level run
        for m in METHODS:
            r = g[g.method == m].sort_values("nu")
            if r.empty:
                continue
            ls = "--" if m.startswith("spring") else "-"
            (h,) = ax.semilogx(0.5 - r.nu, r.deflection / r.ref_value, ls=ls,
                               marker=markers[m], color=colors[m], ms=5, lw=1.2)  # fmt: skip
            handles.setdefault(m, h)
        band = ax.axhspan(1 - TOLERANCE, 1 + TOLERANCE, color="0.85", zorder=0)
        handles.setdefault(f"within {TOLERANCE:.0%} of the reference", band)
        nus = np.sort(g.nu.unique())
        ax.set_xticks(0.5 - nus, [f"{n:g}" for n in nus])
        ax.minorticks_off()
        ax.invert_xaxis()  # nu grows to the right
        ax.set_xlabel("Poisson ratio ν (log scale in 0.5 − ν)")
        ax.set_title(f"{scene} (finest level: {tets} tets)", fontsize=10)
        shares = (g.deflection / g.ref_value).clip(0, 2).to_numpy(float)
        top = float(np.nanmax(shares)) if np.isfinite(shares).any() else 1.0
        ax.set_ylim(0.0, max(1.3, top))
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel(f"deflection / reference ({REFERENCE}, finest level)")
    keys = _ordered(handles)
    fig.legend([handles[k] for k in keys], keys, loc="outside lower center", ncol=4,
               fontsize=8)  # fmt: skip
    return ctx.figure(
        fig,
        "deflection_vs_nu.png",
        "Probe deflection as a share of the reference (P2/P1 Taylor–Hood on the finest "
        "level at the same ν) against ν on a log scale in 0.5 − ν, every method on the "
        "finest level it ran (dashed: spring elements; a method within 5 % on a coarser "
        "level does not run the finer ones); the grey band is ±5 %. A method missing at "
        "a ν did not reach full load within the study's time cap.",
    )


def error_cost_figure(ctx: StudyContext, df: pd.DataFrame) -> Figure:
    """Relative error against solve time, one panel per (scene, nu), the levels of each
    method joined coarse to fine."""
    plt = pyplot()
    from matplotlib.ticker import LogLocator, NullFormatter

    colors, markers = _style(plt)
    scenes, nus = list(df.scene.unique()), np.sort(df.nu.unique())
    size = (3.1 * len(nus), 2.9 * len(scenes) + 1.0)
    fig, axes = plt.subplots(len(scenes), len(nus), figsize=size, squeeze=False, sharey=True,
                             layout="constrained")  # fmt: skip
    handles: dict[str, object] = {}
    for i, scene in enumerate(scenes):
        for j, nu in enumerate(nus):
            ax = axes[i][j]
            g = df[(df.scene == scene) & (df.nu == nu) & (df.status == "ok") & ~df.reference]
            g = g[(g.seconds > 0) & np.isfinite(g.error)]  # what a log axis can show
            if not g.error.notna().any():
                ax.text(0.5, 0.5, f"no reference\n({REFERENCE} did not solve)",
                        ha="center", va="center", transform=ax.transAxes, fontsize=8)  # fmt: skip
            for m in METHODS:
                r = g[g.method == m].sort_values("factor")
                if r.empty:
                    continue
                (h,) = ax.loglog(r.seconds, r.error.clip(lower=ERROR_FLOOR), marker=markers[m],
                                 color=colors[m], ms=4, lw=0.8)  # fmt: skip
                handles.setdefault(m, h)
            line = ax.axhline(TOLERANCE, color="k", ls=":", lw=1)
            handles.setdefault(f"{TOLERANCE:.0%} tolerance", line)
            ax.set_title(f"{scene}, ν = {nu:g}", fontsize=9)
            ax.grid(alpha=0.3, which="major")
            if ax.get_xscale() == "log":  # a panel with nothing solved stays linear
                ax.xaxis.set_major_locator(LogLocator(numticks=4))
            for axis in (ax.xaxis, ax.yaxis):
                axis.set_minor_formatter(NullFormatter())
            if i == len(scenes) - 1:
                ax.set_xlabel("solve wall time (s)")
        axes[i][0].set_ylabel("|deflection error|")
    keys = _ordered(handles)
    fig.legend([handles[k] for k in keys], keys, loc="outside lower center", ncol=5,
               fontsize=8)  # fmt: skip
    return ctx.figure(
        fig,
        "error_vs_cost.png",
        "Relative deflection error against the reference (P2/P1 Taylor–Hood, finest level) "
        "versus static solve wall time, one panel per scene and ν; each method's three "
        "levels are joined coarse to fine (the reference itself is left out; errors below "
        f"{ERROR_FLOOR:g} are drawn at {ERROR_FLOOR:g}). Below the dotted line a method is "
        "within 5 %.",
    )
