"""Figures of the volume-drift study: drift against time and against load factor."""

from __future__ import annotations

import numpy as np

from ..registry import Figure, StudyContext
from ..tables import pyplot
from .cases import COLORS, DYNAMIC
from .tables import MEASURE_WORDS, Runs, compare_words


def _reference_lines(ax, runs: Runs, scene: str) -> None:
    """Dashed lines of the material's drift: the closed form, else the static FEM."""
    ref, m = runs.volume.get(scene), runs.material(scene)
    if ref:
        for i in (0, 1):
            ax[i].axhline(abs(ref[0]), color="k", ls="--", lw=1, label=f"{ref[1]} (static)")
    elif m:
        label = f"{m} (static)"
        ax[0].axhline(abs(runs.stat(scene, m)), color="k", ls="--", lw=1, label=label)
        ax[1].axhline(runs.stat(scene, m, "element_drift"), color="k", ls="--", lw=1, label=label)


def time_figure(ctx: StudyContext, runs: Runs) -> Figure:
    """Drift against time after a suddenly applied load, one column per scene."""
    plt = pyplot()

    panels = [s.label for s in runs.scenes if "step" in runs.kinds(s.label)]
    fig, axes = plt.subplots(3, len(panels), figsize=(4.6 * len(panels), 9.5), squeeze=False)
    for j, scene in enumerate(panels):
        ax = axes[:, j]
        for m in DYNAMIC:
            r = runs.run(scene, "step", m)
            if r is None:
                continue
            t = np.asarray(r["t"]) * 1e3
            tag = f" ({r['status']})" if r["status"] != "ok" else ""
            kw = {"color": COLORS[m], "label": m + tag}
            ax[0].semilogy(t, np.abs(r["dV"]) + 1e-12, **kw)
            ax[1].semilogy(t, np.asarray(r["element_drift"]) + 1e-12, **kw)
            if "lms" in m:
                ax[2].plot(t, r["k_median"], **kw)
                ax[2].fill_between(t, r["k_min"], r["k_max"], color=COLORS[m], alpha=0.15)
        _reference_lines(ax, runs, scene)
        ax[0].set_title(f"{scene} (sudden load)")
        ax[0].set_ylabel("|ΔV| / V0 (total)")
        ax[1].set_ylabel("Σ|ΔV_k| / V0 (elements)")
        ax[2].set_ylabel("LMS k_s/k_s0 (median, band min–max)")
        ax[2].set_yscale("log")
        ax[2].set_xlabel("time (ms)")
        for i in range(3):
            ax[i].grid(alpha=0.3, which="both")
        for i in (0, 1):
            ax[i].set_ylim(1e-4, 1.0)
        ax[0].legend(fontsize=7)
        ax[2].legend(fontsize=7)
    return ctx.figure(
        fig,
        "drift_vs_time.png",
        "Volume drift against time after a suddenly applied load (top: whole-body "
        "|ΔV|/V0; middle: element drift; bottom: LMS stiffness ratio, median and min–max "
        "band); dashed: the material's static drift (closed form, else FEM)."
        + "".join(_time_caption(runs, s) for s in panels),
    )


def _time_caption(runs: Runs, scene: str) -> str:
    """One scene's sentence of the time figure's caption."""
    key = runs.measure(scene)
    ends = {m: abs(runs.final(scene, "step", m, key)) for m in DYNAMIC}
    text = f" {scene}: {MEASURE_WORDS[key]} ends at " + ", ".join(
        f"{v:.3g} ({m})" for m, v in ends.items()
    )
    k_spec = runs.final(scene, "step", "spring-lms-spec", "k_median")
    k_abs = runs.final(scene, "step", "spring-lms-abs", "k_median")
    text += (
        f"; median k_s/k_s0 {k_spec:.3g} (spec) and {k_abs:.3g} (abs), which end at "
        f"{compare_words(ends['spring-lms-spec'], ends['spring-volume-on'])} and "
        f"{compare_words(ends['spring-lms-abs'], ends['spring-volume-on'])} of fixed volume "
        "springs"
    )
    bad = [m for m in DYNAMIC if (runs.run(scene, "step", m) or {}).get("status") != "ok"]
    if bad:
        text += "; not ok: " + ", ".join(
            f"{m} ({runs.run(scene, 'step', m)['status']})" for m in bad
        )
    return text + "."


def load_figure(ctx: StudyContext, runs: Runs) -> Figure:
    """Whole-body drift against signed load factor along the slow ramps, with the static
    equilibria and the closed form.
    """
    plt = pyplot()

    scenes = [s.label for s in runs.scenes if "ramp" in runs.kinds(s.label)]
    fig, ax = plt.subplots(figsize=(7.5, 6.5))
    st = runs.static
    for i, scene in enumerate(scenes):
        sign, first = runs.sign(scene), i == 0
        for m in DYNAMIC:
            r = runs.run(scene, "ramp", m)
            if r is not None and r["t"]:
                ax.semilogy(
                    sign * np.asarray(r["load"]),
                    np.abs(r["dV"]) + 1e-12,
                    color=COLORS[m],
                    label=f"{m} (slow ramp)" if first else None,
                )
        for m in ("spring-volume-off", "spring-volume-on", "spring-volume-nnls"):
            g = st[(st.scene == scene) & (st.model == m) & (st.status == "ok")]
            ax.semilogy(
                sign * g.load,
                np.abs(g.dV),
                "s",
                color=COLORS[m],
                mfc="none",
                ms=9,
                label=f"{m} (static Newton)" if first else None,
            )
        for m, mk in (("P1", "o-"), ("P1-NH", "^-")):
            g = st[(st.scene == scene) & (st.model == m) & (st.status == "ok")].sort_values("load")
            if len(g):
                ax.semilogy(
                    sign * g.load,
                    np.abs(g.dV),
                    mk,
                    color="k",
                    ms=5,
                    lw=1,
                    label=f"{m} (static)" if first else None,
                )
        ref = runs.volume.get(scene)
        if ref:
            lf = np.linspace(0.0, 1.0, 101)
            ax.semilogy(
                sign * lf, abs(ref[0]) * lf + 1e-12, "k--", lw=0.8, label=ref[1] if first else None
            )
    ax.set_xlabel("signed load factor (negative: the material loses volume)")
    ax.set_ylabel("|ΔV| / V0")
    ax.set_ylim(1e-4, 1.0)
    ax.set_title(f"Volume change against load ({', '.join(scenes)})")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, ncol=2, loc="upper center", bbox_to_anchor=(0.5, -0.12))
    scene = scenes[0]
    m = runs.material(scene)
    fem = abs(runs.stat(scene, m)) if m else np.nan

    def end(model: str) -> float:
        return abs(runs.final(scene, "ramp", model))

    return ctx.figure(
        fig,
        "drift_vs_load.png",
        "Whole-body |ΔV|/V0 against signed load factor: spring variants along slow "
        "quasi-static load ramps (lines; squares: Newton equilibria without LMS), same-mesh "
        f"P1 FEM (static) and the closed form. At full load on {scene} the material "
        f"({m}) changes the volume by {fem:.2g}; the spring model with volume springs by "
        f"{end('spring-volume-on'):.2g} ({end('spring-volume-on') / fem:.2g}× the "
        f"material), with LMS spec {end('spring-lms-spec'):.2g}, LMS abs "
        f"{end('spring-lms-abs'):.2g}, nnls calibration {end('spring-volume-nnls'):.2g}, "
        f"the exact element {end('spring-exact'):.2g}.",
    )
