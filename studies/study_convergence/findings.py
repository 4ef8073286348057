"""Findings of the convergence study: the sentences of the report."""

from __future__ import annotations

import numpy as np
import pandas as pd

from .cases import MIN_EXTRAPOLATION_ORDER, MODELS, Settings


def limit_sentence(rates: dict, extra: dict) -> str:
    gap, rate, g_inf = extra["gap"], extra["gap_rate"], extra["gap_limit"]
    k0, k1 = int(gap.index[0]), int(gap.index[-1])
    word = "softer" if gap.iloc[-1] > 0 else "stiffer"
    text = (
        f"On the same mesh the spring model's tip deflection is {gap.iloc[0]:+.1%} from P1 at "
        f"k = {k0} and {gap.iloc[-1]:+.1%} at k = {k1} ({word}); the gap shrinks at rate "
        f"{rate:.2f} in h"
    )
    if not np.isfinite(g_inf):
        return text + " (three finest gaps not monotone: no limit extrapolated)."
    p = extra["gap_order"]
    if p < MIN_EXTRAPOLATION_ORDER or (abs(g_inf) >= 0.02 and g_inf * gap.iloc[-1] < 0):
        return text + (
            f"; extrapolating the three finest levels gives {g_inf:+.1%} with order {p:.2f}, "
            "which these levels are too coarse to trust (pre-asymptotic): no conclusion on "
            "the spring model's limit."
        )
    text += f" and extrapolates (three finest levels, order {p:.2f}) to {g_inf:+.1%}"
    if abs(g_inf) < 0.02:
        return text + ": in bending the spring model converges to within ~2% of FEM's limit."
    return text + ": the spring model converges to a different beam than FEM."


def report_findings(
    df: pd.DataFrame,
    rates: dict,
    w_ref: float,
    timo: float,
    cfg: Settings,
    ref: dict,
    quick: bool,
    extra: dict,
) -> list[str]:
    sp, p1, p2 = rates["spring"], rates["P1"], rates["P2"]
    last = {m: df[df["model"] == m].sort_values("k").iloc[-1] for m in MODELS}
    return [
        f"Fitted L2 rates at the coarse vertices against P2 at k = {cfg.ref} "
        f"({ref['tets']} tets): P2 {p2['l2']:.2f}, P1 {p1['l2']:.2f}, spring model "
        f"{sp['l2']:.2f} (tip deflection: P2 {p2['tip']:.2f}, P1 {p1['tip']:.2f}, spring "
        f"{sp['tip']:.2f}); P1 and the spring model are still pre-asymptotic (bending "
        "stiffness of linear tets), below their asymptotic rate 2"
        + ("; quick run: reference only one level finer than the last P2 point." if quick else "."),
        f"At the finest spring/P1 level (k = {int(last['P1']['k'])}, "
        f"{int(last['P1']['tets'])} tets) the tip deflection is "
        f"{last['spring']['w / w_ref'] - 1:+.1%} from the reference for the spring model and "
        f"{last['P1']['w / w_ref'] - 1:+.1%} for P1 (P2 at k = {int(last['P2']['k'])}: "
        f"{last['P2']['w / w_ref'] - 1:+.2%}).",
        limit_sentence(rates, extra)
        + " The calibration mismatch of DESIGN §4 shows most clearly in the Poisson (lateral) "
        "response (accuracy study), which a slender beam in bending barely feels.",
        f"The P2 reference tip deflection is {w_ref / timo - 1:+.2%} from Timoshenko beam "
        "theory (3D clamping and Poisson effects at the support), so errors are measured "
        "against P2, not the beam formula.",
        f"The spring model runs with energy-consistent torsion here (analytic Hessian); the "
        f"spec's cosine torsion changes the tip deflection by {extra['cosine_vs_energy']:+.2%} "
        f"at k = {cfg.cosine_check_level}.",
    ]
