"""Figures of the volume-drift study: drift against time and against load factor."""

from __future__ import annotations

import numpy as np

from ..registry import Figure, StudyContext
from ..tables import save_figure
from .cases import COLORS, CUBE_STRESS, VARIANTS, Settings, analytic_drift
from .tables import Runs, compare_words, summary


def time_figure(ctx: StudyContext, runs: Runs, s: Settings) -> Figure:
    """Drift against time after a suddenly applied load (cube compressed, pulled, sag).

    Parameters
    ----------
    ctx
        Where to write.
    runs
        The study's runs.
    s
        Its settings.

    Returns
    -------
    Figure
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    dyn, sag_ref, nu = runs.dyn, runs.sag_ref, runs.nu
    panels = [("compressed", "step"), ("pulled", "step")] + ([("sag", "step")] if s.sag else [])
    fig, axes = plt.subplots(3, len(panels), figsize=(4.6 * len(panels), 9.5), squeeze=False)
    for j, (label, kind) in enumerate(panels):
        for c, lab, knd, r in dyn:
            if lab != label or knd != kind:
                continue
            v = c["variant"]
            t = np.asarray(r["t"]) * 1e3
            tag = f" ({r['status']})" if r["status"] != "ok" else ""
            kw = {"color": COLORS[v], "label": v + tag}
            axes[0, j].semilogy(t, np.abs(r["dV"]) + 1e-12, **kw)
            axes[1, j].semilogy(t, np.asarray(r["element_drift"]) + 1e-12, **kw)
            if "LMS" in v:
                axes[2, j].plot(t, r["k_median"], **kw)
                axes[2, j].fill_between(t, r["k_min"], r["k_max"], color=COLORS[v], alpha=0.15)
        if label != "sag":
            a = abs(analytic_drift(nu, CUBE_STRESS))
            for i in (0, 1):
                axes[i, j].axhline(a, color="k", ls="--", lw=1, label="analytic (static)")
            title = f"cube {label} (sudden ±{CUBE_STRESS:g} Pa)"
        else:
            if sag_ref is not None and sag_ref["status"] == "ok":
                axes[0, j].axhline(
                    abs(sag_ref["dV"]),
                    color="k",
                    ls="--",
                    lw=1,
                    label="FEM P1 neo-Hookean (static)",
                )
                axes[1, j].axhline(
                    sag_ref["element_drift"],
                    color="k",
                    ls="--",
                    lw=1,
                    label="FEM P1 neo-Hookean (static)",
                )
            title = "sag under gravity (sudden)"
        axes[0, j].set_title(title)
        axes[0, j].set_ylabel("|ΔV| / V0 (total)")
        axes[1, j].set_ylabel("Σ|ΔV_k| / V0 (elements)")
        axes[2, j].set_ylabel("LMS k_s/k_s0 (median, band min–max)")
        axes[2, j].set_yscale("log")
        axes[2, j].set_xlabel("time (ms)")
        for i in range(3):
            axes[i, j].grid(alpha=0.3, which="both")
        for i in (0, 1):
            axes[i, j].set_ylim(1e-4, 1.0)
        axes[0, j].legend(fontsize=7)
        axes[2, j].legend(fontsize=7)
    n = summary(runs)
    comp, k_spec, k_abs, a_cube = n.comp, n.k_spec, n.k_abs, n.a_cube
    return Figure(
        save_figure(fig, ctx.path("drift_vs_time.png")),
        "Volume drift against time after a suddenly applied load (top: whole-body "
        "|ΔV|/V0; middle: element drift; bottom: LMS stiffness ratio, median and min–max "
        "band). The compressed cube ends at |ΔV|/V0 = "
        + ", ".join(f"{comp[v]:.3g} ({v})" for v in VARIANTS)
        + f" against {a_cube:.2g} for the material (dashed). In compression the spec "
        f"rule ends with median k_s/k_s0 = {k_spec:.3g} and the abs rule with {k_abs:.3g}: "
        f"relative to fixed volume springs, spec ends at "
        f"{compare_words(comp['LMS spec'], comp['volume on'])} and abs at "
        f"{compare_words(comp['LMS abs'], comp['volume on'])}." + _sag_caption(dyn),
    )


def load_figure(ctx: StudyContext, runs: Runs) -> Figure:
    """Whole-body drift of the cube against signed load factor (ramps, statics, analytic).

    Parameters
    ----------
    ctx
        Where to write.
    runs
        The study's runs.

    Returns
    -------
    Figure
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    dyn, stat, nu = runs.dyn, runs.stat, runs.nu
    fig, ax = plt.subplots(figsize=(7.5, 6.5))
    for v in VARIANTS:
        for label, sign in (("compressed", -1.0), ("pulled", 1.0)):
            for c, lab, knd, r in dyn:
                if lab == label and knd == "ramp" and c["variant"] == v and r["t"]:
                    load = sign * np.asarray(r["load"])
                    ax.semilogy(
                        load,
                        np.abs(r["dV"]) + 1e-12,
                        color=COLORS[v],
                        label=f"spring {v} (slow ramp)" if sign < 0 else None,
                    )
    for v, mk in (("volume off", "s"), ("volume on", "s"), ("volume on (nnls)", "s")):
        g = stat[(stat.model == v) & (stat.status == "ok")]
        ax.semilogy(
            g.load,
            np.abs(g.dV),
            mk,
            color=COLORS[v],
            mfc="none",
            ms=9,
            label=f"spring {v} (static Newton)",
        )
    for law, mk in (("linear", "o-"), ("neo-hookean", "^-")):
        g = stat[(stat.model == f"FEM P1 {law}") & (stat.status == "ok")].sort_values("load")
        for sign in (-1.0, 1.0):
            h = g[np.sign(g.load) == sign]
            ax.semilogy(
                h.load,
                np.abs(h.dV),
                mk,
                color="k",
                ms=5,
                lw=1,
                label=f"FEM P1 {law} (static)" if sign < 0 else None,
            )
    lf = np.linspace(-1, 1, 201)
    ax.semilogy(
        lf,
        np.abs(analytic_drift(nu, lf * CUBE_STRESS)) + 1e-12,
        "k--",
        lw=0.8,
        label="analytic (1−2ν)σ/E",
    )
    ax.set_xlabel(f"signed load factor (σ / {CUBE_STRESS:g} Pa; negative = compression)")
    ax.set_ylabel("|ΔV| / V0")
    ax.set_ylim(1e-4, 1.0)
    ax.set_title(f"Cube, ν = {nu}: volume change against load")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, ncol=2, loc="upper center", bbox_to_anchor=(0.5, -0.12))
    n = summary(runs)
    fem_c = n.fem_c

    def ramp_end(label: str, v: str) -> float:
        return abs(runs.final(label, "ramp", v))

    return Figure(
        save_figure(fig, ctx.path("drift_vs_load.png")),
        "Whole-body |ΔV|/V0 of the cube against signed load factor: spring variants "
        "along slow quasi-static load ramps (lines; squares: Newton equilibria without "
        "LMS), FEM P1 linear and neo-Hookean (static), and the small-strain analytic "
        f"value. At full compression FEM neo-Hookean changes the volume by {fem_c:.2g}; "
        f"the spring model with volume springs by {ramp_end('compressed', 'volume on'):.2g}"
        f" ({ramp_end('compressed', 'volume on') / fem_c:.0f}× the material), with LMS "
        f"spec {ramp_end('compressed', 'LMS spec'):.2g}, LMS abs "
        f"{ramp_end('compressed', 'LMS abs'):.2g}, nnls calibration "
        f"{ramp_end('compressed', 'volume on (nnls)'):.2g}.",
    )


def _sag_caption(dyn: list) -> str:
    """The sag panel's sentence of the time-figure caption (empty without a sag run)."""
    sag = {c["variant"]: r for c, label, kind, r in dyn if label == "sag"}
    if not sag:
        return ""
    inverted = [v for v, r in sag.items() if r["status"] in ("inverted", "diverged")]
    diverged = [v for v, r in sag.items() if r["status"] == "diverged"]
    text = f" In the sagging block {len(inverted)} of {len(sag)} spring variants invert elements"
    if diverged:
        text += f" and {', '.join(diverged)} diverges (stopped when the element drift exceeds 1)"
    return text + "; the dashed line is the static neo-Hookean FEM drift."
