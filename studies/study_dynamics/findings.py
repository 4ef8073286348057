"""Findings of the dynamics study: how far each spring element's probe strays from explicit
P1 over the run, whether its energy balance holds, and what a step costs.

Examples
--------
>>> import pandas as pd
>>> df = pd.DataFrame({"scene": "b", "model": ["P1", "spring-exact"], "status": "ok",
...     "static error": [0.0, 0.0015], "L2 error (run)": [0.0, 0.01], "max error": [0.0, 0.02],
...     "energy drift": [1e-6, 2e-6], "dt (s)": [1e-5, 1e-5], "step (µs)": [100.0, 120.0],
...     "cost / P1 step": [1.0, 1.2], "message": ""})
>>> f, h = report_findings(df, {"b": "P1"}, {"b": 0.1})
>>> "spring-exact: probe L2 error 1% over the run (max 2%, static 0.15%)" in f[0]
True
>>> h["b_spring-exact_l2_error"], h["b_spring-exact_cost_ratio"]
(0.01, 1.2)
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .cases import own_integrator

#: Headline key -> table column, per spring model.
HEADLINE = {"l2_error": "L2 error (run)", "max_error": "max error",
            "energy_drift": "energy drift", "cost_ratio": "cost / P1 step"}  # fmt: skip


def _pct(x: float) -> str:
    if not np.isfinite(x):
        return "n/a"
    return f"{x:.2g}" if x < 1e-4 else f"{100 * x:.2g}%"


def _steps(ok: pd.DataFrame) -> str:
    spread = float(np.ptp(ok["dt (s)"]) / ok["dt (s)"].max())
    if spread < 0.01:
        return (
            f" The stable steps agree within {spread:.2g} (relative): the spring elements' "
            "small-strain tangent is P1's, so none buys a larger step."
        )
    best = ok.loc[ok["dt (s)"].idxmax()]
    above = float(ok["dt (s)"].max() / ok["dt (s)"].min() - 1.0)
    return f" The largest stable step is {best.model}'s, {above:.1%} above the smallest."


def _peer_notes(ok: pd.DataFrame) -> list[str]:
    """What the plug-in peers' rows mean: the energy change of a model with its own time
    integration (undamped), the mass-spring network's error (its material, not its
    integration)."""
    out = []
    for _, r in ok.iterrows():
        own = own_integrator(r.model)
        if own is None:
            continue
        conf = float(getattr(own, "setting_step", np.nan))
        over = conf / min(r["dt_crit rest (s)"], r["dt_crit loaded (s)"])
        out.append(
            f"{r.scene}: {r.model} runs its own undamped steps at h = {r['dt (s)']:.3g} s (the "
            f"explicit models' rule; its configured step {conf:.3g} s is {over:.3g}× the "
            "2/ω_max of its energy here; the stability study measures how far past that bound "
            "it survives) and its energy changes by "
            f"{r['energy change (end)']:.2g} of the initial energy over the run: the position "
            "projection dissipates, where the symplectic explicit steps only oscillate."
        )
    for _, r in ok[ok.model == "mass-spring"].iterrows():
        out.append(
            f"{r.scene}: the mass-spring network's probe error ({_pct(r['static error'])} "
            "static) is its material's, not its time integration's: an edge network obeys the "
            "Cauchy relations (its ν is not the scene's: 1/4 if isotropic, 5/31 along an axis "
            "on the six-tet box lattice), so no spring stiffness fits the scene's material "
            "(docs/peers.rst)."
        )
    return out


def report_findings(
    df: pd.DataFrame, refs: dict[str, str], t_end: dict[str, float], quick: bool = False
) -> tuple[list[str], dict[str, float]]:
    """Findings sentences and headline numbers from the study's table.

    Parameters
    ----------
    df
        :func:`~studies.study_dynamics.tables.result_frame`.
    refs
        Scene label -> reference model.
    t_end
        Scene label -> run length (seconds).
    quick
        The quick preset (said in the first sentence).

    Returns
    -------
    findings, headline
    """
    out: list[str] = []
    head: dict[str, float] = {}
    for scene, g in df.groupby("scene", sort=False):
        ref = refs[scene]
        r0 = g[g.model == ref].iloc[0]
        springs = g[g.model != ref]
        parts = []
        for _, r in springs.iterrows():
            if r.status != "ok":
                parts.append(f"{r.model}: {r.status} ({r.message})")
                continue
            parts.append(
                f"{r.model}: probe L2 error {_pct(r['L2 error (run)'])} over the run (max "
                f"{_pct(r['max error'])}, static {_pct(r['static error'])})"
            )
            for key, col in HEADLINE.items():
                v = float(r[col])
                head[f"{scene}_{r.model}_{key}"] = float(f"{v:.3g}") if np.isfinite(v) else v
        preset = " (quick preset)" if quick else ""
        out.append(
            f"{scene}{preset}: released from the static state and run {t_end[scene] * 1e3:.3g} ms "
            f"against explicit {ref} of the same law on the same mesh, " + "; ".join(parts) + "."
        )
        ok = g[g.status == "ok"]
        drift = ", ".join(f"{r.model} {r['energy drift']:.2g}" for _, r in ok.iterrows())
        out.append(
            f"{scene}: undamped, every model keeps its own energy balance (kinetic + strain − "
            f"work) within a relative {ok['energy drift'].max():.2g} of its initial energy "
            f"({drift}): the symplectic step's O((ω dt)²) oscillation, no drift."
            if np.all(ok["energy drift"] < 1e-3)
            else f"{scene}: energy drift relative to the initial energy: {drift}."
        )
        out += _peer_notes(ok)
        cost = ", ".join(
            f"{r.model} {r['step (µs)']:.3g} µs ({r['cost / P1 step']:.2f}× P1) at dt "
            f"{r['dt (s)']:.3g} s"
            for _, r in ok.iterrows()
            if r.model != ref
        )
        out.append(
            f"{scene}: one step of explicit {ref} costs {r0['step (µs)']:.3g} µs at dt "
            f"{r0['dt (s)']:.3g} s; {cost} (median over the steps, interleaved in one process, "
            "warm; XPBD: one substep)." + _steps(ok)
        )
        head[f"{scene}_{ref}_energy_drift"] = float(f"{r0['energy drift']:.3g}")
        head[f"{scene}_{ref}_step_us"] = float(f"{r0['step (µs)']:.3g}")
    return out, head
