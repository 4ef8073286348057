"""Findings and headline numbers of the convergence study."""

from __future__ import annotations

import numpy as np

from .cases import COSINE, EXACT, MIN_EXTRAPOLATION_ORDER, SPRING
from .tables import Analysis


def limit_sentence(a: Analysis) -> str:
    """What the spring–P1 gap does under refinement, and where it extrapolates to."""
    gap, rate, g_inf = a.gap, a.gap_rate, a.gap_limit
    p1 = a.plan.fem[0]
    if len(gap) == 0:
        return f"No level has both {SPRING} and {p1}."
    k0, k1 = int(gap.index[0]), int(gap.index[-1])
    word = "softer" if gap.iloc[-1] > 0 else "stiffer"
    text = (
        f"On the same mesh {SPRING}'s w is {gap.iloc[0]:+.1%} from {p1} at level {k0} and "
        f"{gap.iloc[-1]:+.1%} at level {k1} ({word}); the gap "
        + (f"shrinks at rate {rate:.2f} in h" if rate > 0 else f"does not shrink (rate {rate:.2f})")
    )
    if not np.isfinite(g_inf):
        return text + " (three finest gaps not monotone: no limit extrapolated)."
    p = a.gap_order
    if p < MIN_EXTRAPOLATION_ORDER or (abs(g_inf) >= 0.02 and g_inf * gap.iloc[-1] < 0):
        return text + (
            f"; extrapolating the three finest levels gives {g_inf:+.1%} with order {p:.2f}, "
            "which these levels are too coarse to trust (pre-asymptotic): no conclusion on "
            "the spring model's limit."
        )
    text += f" and extrapolates (three finest levels, order {p:.2f}) to {g_inf:+.1%}"
    if abs(g_inf) < 0.02:
        return text + ": the spring model converges to within ~2% of FEM's limit."
    return text + ": the spring model converges to another limit than FEM."


def report_findings(a: Analysis, quick: bool) -> list[str]:
    """The findings of one scene (``quick``: its reference is only one level above the last P2
    point).
    """
    p, r = a.plan, a.rate
    name = p.scene.label
    p1, p2 = p.fem
    df = a.levels[a.levels["status"] == "ok"]
    last = {m: df[df["model"] == m].sort_values("factor").iloc[-1] for m in r}
    rates = ", ".join(f"{m} {r[m]['l2']:.2f}" for m in r)
    tips = ", ".join(f"{m} {r[m]['tip']:.2f}" for m in r)
    out = [
        f"{name}: fitted L2 rates at the level-1 vertices against {p2} on level {p.ref} "
        f"({a.ref['tets']} tets): {rates} (w = {a.track.label}: {tips}); the asymptotic L2 "
        "rates on a smooth solution are 2 for linear elements and 3 for P2, so lower fitted "
        "rates mean pre-asymptotic levels (the bending stiffness of linear tets) or a "
        "singular solution"
        + ("; quick run: reference only one level finer than the last P2 point." if quick else "."),
    ]
    if p.notes:
        out.append(f"{name}: {'; '.join(p.notes)}.")
    if {SPRING, p1} <= set(last):
        k = int(last[p1]["factor"])
        text = (
            f"At the finest spring/{p1} level ({k}, {int(last[p1]['tets'])} tets) w is "
            f"{last[SPRING]['w / w_ref'] - 1:+.1%} from the reference for {SPRING} and "
            f"{last[p1]['w / w_ref'] - 1:+.1%} for {p1}"
        )
        if p2 in last:
            text += f" ({p2} at level {int(last[p2]['factor'])}: {last[p2]['w / w_ref'] - 1:+.2%})"
        out.append(text + ".")
    out.append(
        limit_sentence(a) + " The calibration mismatch of the specification's element shows "
        "most in the Poisson (lateral) response (accuracy study), which bending barely feels."
    )
    if a.analytic is not None:
        value, source = a.analytic
        out.append(
            f"The {p2} reference's w is {a.w_ref / value - 1:+.2%} from {source} (its "
            "idealisations: for a beam, the 3D clamping and Poisson effects at the support), "
            f"so errors are measured against {p2}, not against {source}."
        )
    if np.isfinite(a.cosine_vs_energy):
        out.append(
            f"{SPRING} (energy-consistent torsion, analytic Hessian) is the spring model here; "
            f"the specification's cosine torsion ({COSINE}) changes w by "
            f"{a.cosine_vs_energy:+.2%} at level {p.cosine}."
        )
    if {EXACT, p1, SPRING} <= set(r):
        fin = a.rates.set_index("model")
        out.append(
            f"{EXACT} (axis-volume + energy torsion + exact calibration) converges like P1: "
            f"L2 rate {r[EXACT]['l2']:.2f} ({p1} {r[p1]['l2']:.2f}), w error at the finest "
            f"level {fin.at[EXACT, 'w err at finest']:.1%} ({p1} "
            f"{fin.at[p1, 'w err at finest']:.1%}, {SPRING} "
            f"{fin.at[SPRING, 'w err at finest']:.1%}): the spring–P1 gap of the "
            "specification's element is its calibration, and the exact element has none."
        )
    return out


def headline(a: Analysis) -> dict[str, float]:
    """The headline numbers of one scene: rates, errors at the finest level, the gap.

    ``rate_l2_<model>``, ``rate_<w>_<model>`` (P1, P2), ``<w>_err_finest_<model>`` (the
    spring models and P1), ``spring-energy_over_P1_finest``, ``rate_spring-energy_P1_gap``
    and, with a closed form, ``ref_over_<its name>``; ``<w>`` is the tracked probe's name
    (``tip``).
    """
    r, w, (p1, p2) = a.rate, a.track.name, a.plan.fem
    fin = a.rates.set_index("model")
    out = {f"rate_l2_{m}": r[m]["l2"] for m in r}
    out.update({f"rate_{w}_{m}": r[m]["tip"] for m in (p1, p2) if m in r})
    out.update(
        {f"{w}_err_finest_{m}": float(fin.at[m, "w err at finest"]) for m in (SPRING, EXACT, p1)
         if m in r}
    )  # fmt: skip
    if len(a.gap):
        out[f"{SPRING}_over_{p1}_finest"] = float(a.gap.iloc[-1] + 1.0)
        out[f"rate_{SPRING}_{p1}_gap"] = a.gap_rate
    if a.analytic is not None and a.plan.scene.analytic is not None:
        out[f"ref_over_{a.plan.scene.analytic}"] = a.w_ref / a.analytic[0]
    return out
