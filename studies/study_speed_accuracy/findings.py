"""Findings and headline numbers of the speed-accuracy study."""

from __future__ import annotations

import pandas as pd

from .cases import EXACT_METHODS, LABELS, STEP_REPEATS, Settings


def report_findings(
    df: pd.DataFrame, steps: list[dict], p: Settings
) -> tuple[list[str], dict[str, float], str]:
    """The findings, the headline tip errors and the Pareto-front sentence.

    Parameters
    ----------
    df
        The points (:func:`~.tables.points_frame`).
    steps
        The step-cost results per mesh.
    p
        The study's settings.

    Returns
    -------
    findings : list of str
    headline : dict
        Tip errors on the finest mesh (no timings), point and failure counts.
    front_text : str
        The sentence about the Pareto front (also the figure's caption).
    """
    findings: list[str] = []
    headline: dict[str, float] = {}
    ok = df["status"] == "ok"
    good, failed = df[ok], df[~ok]
    finest = p.meshes[-1]
    fmesh = f"{finest[0]}x{finest[1]}x{finest[1]}"
    s_last = steps[-1]
    ratio, ratio_cpu = s_last["ratio_wall"], s_last["ratio_cpu"]
    findings.append(
        f"One explicit step of the spring model costs {ratio_cpu:.2f}x one step of the explicit "
        f"P1 neo-Hookean FEM on the same {fmesh} mesh ({s_last['tets']} tets; CPU time, median "
        f"of {STEP_REPEATS} alternating repeats in one run; wall-clock ratio {ratio:.2f}x on "
        f"this shared machine): "
        + (
            "the spring model is slower per step."
            if ratio_cpu > 1
            else "the spring model is cheaper per step."
        )
    )

    def best(method, mesh=fmesh):
        g = good[(good["method"] == method) & (good["mesh"] == mesh)]
        return g.sort_values("tip_error").iloc[0] if len(g) else None

    sp, p1, p2 = best("spring-static"), best("fem-p1-linear"), best("fem-p2-linear")
    if sp is not None and p1 is not None and p2 is not None:
        findings.append(
            f"On {fmesh} the spring model's tip is {100 * sp['tip_error']:.1f}% off the fine P2 "
            f"reference (static Newton, {sp['seconds']:.2f} s), P1 FEM on the same mesh "
            f"{100 * p1['tip_error']:.1f}% ({p1['seconds']:.2f} s) and P2 FEM "
            f"{100 * p2['tip_error']:.2f}% ({p2['seconds']:.2f} s)."
        )
        headline[f"tip_error_spring_static_{fmesh}"] = round(float(sp["tip_error"]), 4)
        headline[f"tip_error_fem_p1_linear_{fmesh}"] = round(float(p1["tip_error"]), 4)
        headline[f"tip_error_fem_p2_linear_{fmesh}"] = round(float(p2["tip_error"]), 4)
    se = good[(good["method"] == "spring-explicit") & (good["mesh"] == fmesh)]
    fe = good[(good["method"] == "fem-explicit-p1-neo-hookean") & (good["mesh"] == fmesh)]
    common = sorted(set(se["setting"]) & set(fe["setting"]))
    if common:
        st = (
            "tol 1e-06, dt = 0.5 dt_crit"
            if "tol 1e-06, dt = 0.5 dt_crit" in common
            else (common[-1])
        )
        a = se[se["setting"] == st].iloc[0]
        b = fe[fe["setting"] == st].iloc[0]
        findings.append(
            f"To rest by dynamic relaxation ({st}) on {fmesh}: spring model {a['seconds']:.2f} s "
            f"in {int(a['steps'])} steps (tip error {100 * a['tip_error']:.1f}%), explicit P1 FEM "
            f"{b['seconds']:.2f} s in {int(b['steps'])} steps (tip error "
            f"{100 * b['tip_error']:.1f}%, the P1 static answer to the solver tolerance)."
        )
        headline[f"tip_error_fem_explicit_{fmesh}"] = round(float(b["tip_error"]), 4)
        if sp is not None:
            findings.append(
                f"For this static problem dynamic relaxation is the slow way to the answer: "
                f"{a['seconds'] / sp['seconds']:.0f}x the spring model's static Newton and "
                f"{b['seconds'] / best('fem-p1-neo-hookean')['seconds']:.0f}x FEM P1 "
                f"neo-Hookean Newton on {fmesh}; explicit stepping pays off only when the "
                f"dynamics themselves are wanted."
            )
    on_front = good[good["pareto"]]
    fam = ", ".join(
        f"{LABELS[m]} ({', '.join(on_front[on_front['method'] == m]['mesh'])})"
        for m in on_front["method"].unique()
    )
    n_spring_front = int(on_front["method"].str.startswith("spring").sum())
    front_text = f"Pareto front ({len(on_front)} of {len(good)} points): {fam}; " + (
        f"{n_spring_front} spring-model point(s) on it."
        if n_spring_front
        else "no spring-model point is on it: for every spring point some "
        "FEM point is both faster and more accurate."
    )
    findings.append(front_text)
    for _, r in failed.iterrows():
        findings.append(
            f"{LABELS[r['method']]} on {r['mesh']} ({r['setting']}) {r['status']}: "
            f"{r['message'][:140]}"
        )
    seed = ~df["method"].isin(EXACT_METHODS)  # the counts of the seed model's points
    headline["n_points"] = float(seed.sum())
    headline["n_failed"] = float((~ok & seed).sum())
    headline["n_points_exact"] = float((~seed).sum())
    ex = best("spring-exact-static")
    if ex is not None:
        headline[f"tip_error_spring_exact_static_{fmesh}"] = round(float(ex["tip_error"]), 4)
        if sp is not None and p1 is not None:
            findings.insert(
                2,
                f"The exact spring element (axis-volume + energy torsion + exact calibration) "
                f"on {fmesh}: tip {100 * ex['tip_error']:.1f}% off the fine P2 reference "
                f"(static Newton, {ex['seconds']:.2f} s), i.e. P1's error on the same mesh "
                f"({100 * p1['tip_error']:.1f}%), where the seed model is "
                f"{100 * sp['tip_error']:.1f}% off. The seed model's smaller tip error on this "
                "coarse mesh is its extra softness cancelling P1's bending stiffness (accuracy "
                "study), not accuracy; the exact element is P1 at the spring model's cost, so "
                "it converges where the seed model does not.",
            )
    return findings, headline, front_text
