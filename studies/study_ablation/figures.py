"""The figure of the ablation study: model error against solve time per scene."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..registry import Figure, StudyContext
from ..tables import save_figure
from .cases import TOLERANCE, VARIANTS


def error_cost_figure(
    ctx: StudyContext, df: pd.DataFrame, winners: pd.DataFrame, fem_times: dict[str, float]
) -> Figure:
    """Model error against static solve time, one panel per scene, winners circled.

    Parameters
    ----------
    ctx
        Where to write.
    df
        The (scene, variant) rows.
    winners
        The winners per scene.
    fem_times
        Scene -> FEM P1 solve time (a vertical line).

    Returns
    -------
    Figure
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(df.scene.unique())
    fig, axes = plt.subplots(1, len(names), figsize=(4.2 * len(names), 4.2), squeeze=False)
    markers = dict(zip(VARIANTS, "o<v^sDP*"))
    colors = dict(zip(VARIANTS, plt.rcParams["axes.prop_cycle"].by_key()["color"]))
    handles = {}
    for ax, name in zip(axes[0], names):
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
        if len(w) and "its error" in w and np.isfinite(w["its error"].iloc[0]):
            (h,) = ax.loglog(
                w["its solve time"].iloc[0],
                w["its error"].iloc[0],
                "o",
                ms=17,
                mfc="none",
                mec="k",
            )
            handles["cheapest adequate"] = h
        if name in fem_times:
            handles["FEM P1 solve time"] = ax.axvline(fem_times[name], color="k", ls=":", lw=1)
        failed = ", ".join(g[(g.status != "ok") & ~np.isfinite(g.error)].variant)
        ax.set_title(f"{name} ({int(g.tets.iloc[0])} tets)", fontsize=10)
        if failed:
            ax.text(0.03, 0.97, f"fails: {failed}", transform=ax.transAxes, fontsize=7, va="top")
        ax.set_xlabel("static solve wall time (s)")
        ax.grid(alpha=0.3, which="both")
    axes[0, 0].set_ylabel("model error vs FEM P1 (relative L2)")
    rank = {v: i for i, v in enumerate(VARIANTS)}
    keys = sorted(handles, key=lambda k: rank.get(k.split(" (not")[0], len(rank)))
    fig.legend(
        [handles[k] for k in keys],
        keys,
        loc="upper center",
        ncol=4,
        fontsize=8,
        bbox_to_anchor=(0.5, -0.02),
    )
    summary = "; ".join(
        f"{w['scene']}: {w['cheapest adequate']}"
        + (f" ({w['its error']:.3g})" if pd.notna(w.get("its error")) else "")
        for _, w in winners.iterrows()
    )
    return Figure(
        save_figure(fig, ctx.path("error_vs_cost.png")),
        "Model error against static solve time for each spring variant (hollow: the "
        "last state of a run that did not converge; variants that fail outright are "
        "named in the panel); circled: the cheapest variant within "
        f"{TOLERANCE:.0%} of the best error. Cheapest adequate (error): {summary}.",
    )
