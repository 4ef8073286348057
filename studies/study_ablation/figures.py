"""The figure of the ablation study: model error against solve time per scene."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..registry import Figure, StudyContext
from ..tables import pyplot
from .cases import ALL_VARIANTS, TOLERANCE


def error_cost_figure(
    ctx: StudyContext, df: pd.DataFrame, winners: pd.DataFrame, fem_times: dict[str, float]
) -> Figure:
    """Model error against static solve time, one panel per scene, winners circled, the FEM P1
    solve time a vertical line.
    """
    plt = pyplot()

    names = list(df.scene.unique())
    ncol = min(len(names), 3)
    nrow = -(-len(names) // ncol)
    from matplotlib.ticker import LogLocator, NullFormatter

    fig, axes = plt.subplots(
        nrow, ncol, figsize=(4.4 * ncol, 4.0 * nrow + 1.2), squeeze=False, layout="constrained"
    )
    markers = dict(zip(ALL_VARIANTS, "o<v^sDP*XH"))
    colors = dict(zip(ALL_VARIANTS, plt.rcParams["axes.prop_cycle"].by_key()["color"]))
    handles = {}
    for ax, name in zip(axes.ravel(), names):
        g = df[df.scene == name]
        for _, r in g.iterrows():
            kw = {"color": colors[r.variant], "ms": 8, "ls": "none"}
            if r.status == "ok":
                (h,) = ax.loglog(r.solve_time, r.error, markers[r.variant], **kw)
                handles.setdefault(r.variant, h)
            elif np.isfinite(r.error) and np.isfinite(r.solve_time):
                (h,) = ax.loglog(r.solve_time, r.error, markers[r.variant], mfc="none", **kw)
                handles.setdefault(r.variant + " (not converged: last state)", h)
        w = winners[winners.scene == name]
        for tag, ms, mec in (("", 17, "k"), (" (with exact)", 21, "r")):  # circle the winners
            col = f"its error{tag}"
            if len(w) and col in w and np.isfinite(w[col].iloc[0]):
                t = w[f"its solve time{tag}"].iloc[0]
                (h,) = ax.loglog(t, w[col].iloc[0], "o", ms=ms, mfc="none", mec=mec)
                handles[f"cheapest adequate{tag}"] = h
        if name in fem_times:
            handles["FEM P1 solve time"] = ax.axvline(fem_times[name], color="k", ls=":", lw=1)
        failed = ", ".join(g[(g.status != "ok") & ~np.isfinite(g.error)].variant)
        title = f"{name} ({int(g.tets.iloc[0])} tets)" + (f"\nfails: {failed}" if failed else "")
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("static solve wall time (s)")
        ax.grid(alpha=0.3, which="both")
        for axis in (ax.xaxis, ax.yaxis):  # decade labels only: no crowded minor labels
            axis.set_minor_formatter(NullFormatter())
        lo, hi = ax.get_ylim()
        if hi / lo < 100:  # under 2 decades: label 1 and 3 of each decade too
            ax.yaxis.set_major_locator(LogLocator(subs=(1.0, 3.0)))
    for ax in axes.ravel()[len(names) :]:
        ax.set_visible(False)
    for row in axes:
        row[0].set_ylabel("model error vs FEM P1 (relative L2)")
    rank = {v: i for i, v in enumerate(ALL_VARIANTS)}
    keys = sorted(handles, key=lambda k: rank.get(k.split(" (not")[0], len(rank)))
    fig.legend([handles[k] for k in keys], keys, loc="outside lower center", ncol=4, fontsize=8)
    summary = "; ".join(
        f"{w['scene']}: {w['cheapest adequate']}"
        + (f" ({w['its error']:.3g})" if pd.notna(w.get("its error")) else "")
        for _, w in winners.iterrows()
    )
    return ctx.figure(
        fig,
        "error_vs_cost.png",
        "Model error against static solve time for each spring variant (hollow: the "
        "last state of a run that did not converge; variants that fail outright are "
        "named in the panel); circled: the cheapest variant within "
        f"{TOLERANCE:.0%} of the best error among the specification's parts (black) and with "
        "the exact element included (red). FEM P1 has the scene's law (linear except the "
        f"sag). Cheapest adequate (error): {summary}.",
    )
