"""Findings and headline numbers of the speed-accuracy study."""

from __future__ import annotations

import pandas as pd

from .cases import EXACT, EXPLICIT_FEM, SPRING, STEP_REPEATS, method_name
from .sweeps import model_of, most_accurate, per_model_sentence, sweep_findings
from .tables import Measure

#: The explicit setting the spring model and the explicit FEM are compared at, if both ran it.
COMPARED_SETTING = "tol 1e-06, dt = 0.5 dt_crit"


def report_findings(
    df: pd.DataFrame, steps: dict | None, how: Measure, finest: str, label: str,
    tolerance: float = 0.05, cases: list[dict] | None = None,
) -> tuple[list[str], dict[str, float], str]:  # fmt: skip
    """The findings, the headline errors and the Pareto-front sentence of one scene.

    ``steps``: the step costs on the finest level (``None``: none); ``finest``: its label
    (``20x2x2``); ``cases``: the points' cases, row by row (for the plug-ins' sweeps,
    :func:`.sweeps.sweep_findings`). The headline holds the errors on the finest level (no
    timings, rounded to 4 decimals), ``<measure>_<model>_<solution>_<level>``, the sweeps'
    observed rates, and point and failure counts; the front's sentence is also the figure's
    caption.
    """
    err, key = how.column, how.key
    findings: list[str] = []
    headline: dict[str, float] = {}
    ok = df["status"] == "ok"
    good, failed = df[ok], df[~ok]
    if steps is not None:
        ratio, ratio_cpu = steps["ratio_wall"], steps["ratio_cpu"]
        findings.append(
            f"One explicit step of {SPRING} costs {ratio_cpu:.2f}x one step of the explicit "
            f"P1 neo-Hookean FEM on the same {finest} mesh ({steps['tets']} tets; CPU time, "
            f"median of {STEP_REPEATS} alternating repeats in one run; wall-clock ratio "
            f"{ratio:.2f}x on this shared machine): the spring model is "
            + ("slower per step." if ratio_cpu > 1 else "cheaper per step.")
        )

    def best(model: str, solution: str, mesh: str = finest):
        g = good[(good["method"] == method_name(model, solution)) & (good["mesh"] == mesh)]
        return g.sort_values(err).iloc[0] if len(g) else None

    def put(model: str, solution: str, row) -> None:
        headline[f"{key}_{model}_{solution}_{finest}"] = round(float(row[err]), 4)

    def pct(row, digits: int = 1) -> str:
        return f"{100 * row[err]:.{digits}f}%"

    sp, p1, p2 = best(SPRING, "static"), best("P1", "static"), best("P2", "static")
    if sp is not None and p1 is not None and p2 is not None:
        findings.append(
            f"On {finest} {SPRING} is {pct(sp)} off the reference (static Newton, "
            f"{sp['seconds']:.2f} s), P1 on the same mesh {pct(p1)} ({p1['seconds']:.2f} s) "
            f"and P2 {pct(p2, 2)} ({p2['seconds']:.2f} s)."
        )
        for m, row in ((SPRING, sp), ("P1", p1), ("P2", p2)):
            put(m, "static", row)
    se = good[(good["method"] == method_name(SPRING, "explicit")) & (good["mesh"] == finest)]
    fe = good[(good["method"] == method_name(EXPLICIT_FEM, "explicit")) & (good["mesh"] == finest)]
    common = sorted(set(se["setting"]) & set(fe["setting"]))
    if common:
        st = COMPARED_SETTING if COMPARED_SETTING in common else common[-1]
        a = se[se["setting"] == st].iloc[0]
        b = fe[fe["setting"] == st].iloc[0]
        findings.append(
            f"To rest by dynamic relaxation ({st}) on {finest}: {SPRING} {a['seconds']:.2f} s "
            f"in {int(a['steps'])} steps (error {pct(a)}), the explicit P1 FEM "
            f"{b['seconds']:.2f} s in {int(b['steps'])} steps (error {pct(b)}, the P1 static "
            "answer to the solver tolerance)."
        )
        put(EXPLICIT_FEM, "explicit", b)
        nh = best(EXPLICIT_FEM, "static")
        if sp is not None and nh is not None:
            findings.append(
                "For this static problem dynamic relaxation is the slow way to the answer: "
                f"{a['seconds'] / sp['seconds']:.0f}x {SPRING} static Newton and "
                f"{b['seconds'] / nh['seconds']:.0f}x {EXPLICIT_FEM} static Newton on "
                f"{finest}; explicit stepping pays off only when the dynamics themselves are "
                "wanted."
            )
    on_front = good[good["pareto"]]
    fam = ", ".join(
        f"{m} ({', '.join(on_front[on_front['method'] == m]['mesh'])})"
        for m in on_front["method"].unique()
    )
    n_spring_front = int(on_front["method"].str.startswith("spring").sum())
    front_text = f"{label}: Pareto front ({len(on_front)} of {len(good)} points): {fam}; " + (
        f"{n_spring_front} spring-model point(s) on it."
        if n_spring_front
        else "no spring-model point is on it: for every spring point some FEM point is both "
        "faster and more accurate."
    )
    findings.append(front_text)
    findings.append(cheapest_sentence(good, err, tolerance))
    findings.append(per_model_sentence(good, err, tolerance))
    for _, r in failed.iterrows():
        findings.append(
            f"{r['method']} on {r['mesh']} ({r['setting']}) {r['status']}: {r['message'][:140]}"
        )
    findings += peer_findings(good, err, put, pct, finest, sp, p1)
    if cases is not None:
        lines, rates = sweep_findings(df, cases, err, finest)
        findings += lines
        headline.update(rates)
    exact = df["method"].str.startswith(f"{EXACT} ")
    headline["n_points"] = float((~exact).sum())
    headline["n_failed"] = float((~ok & ~exact).sum())
    headline["n_points_exact"] = float(exact.sum())
    ex = best(EXACT, "static")
    if ex is not None:
        put(EXACT, "static", ex)
        if sp is not None and p1 is not None:
            findings.insert(
                2 if steps is not None else 1,
                f"{EXACT} (axis-volume + energy torsion + exact calibration) on {finest}: "
                f"{pct(ex)} off the reference (static Newton, {ex['seconds']:.2f} s), i.e. "
                f"P1's error on the same mesh ({pct(p1)}), where {SPRING} is {pct(sp)} off. "
                "A smaller error of the specification's element on a coarse mesh is its extra "
                "softness cancelling P1's bending stiffness (accuracy study), not accuracy; "
                "the exact element is P1 at the spring model's cost, so it converges where "
                "the specification's element does not.",
            )
    return findings, headline, front_text


def peer_findings(good, err: str, put, pct, finest: str, sp, p1) -> list[str]:
    """A sentence per plug-in model (``studies.models.plugins``) on the finest level: its
    most accurate static point (of its sweep, if it has one) and explicit point, error and
    time, beside the spring model's and P1's."""
    from .. import models

    out = []
    fine = good[good["mesh"] == finest]
    for name in dict.fromkeys(model_of(m) for m in good["method"]):
        if models.get(name).kind != "plugin":
            continue
        own = fine[fine["method"].map(model_of) == name]
        st, ex = (most_accurate(own, err, suffix) for suffix in (" static", " explicit"))
        if st is None:
            continue
        put(name, "static", st)
        text = f"{name} on {finest}: {pct(st)} off the reference ({st['method']}, "
        text += f"{st['seconds']:.2f} s"
        if ex is not None:
            put(name, "explicit", ex)
            text += f"; to rest explicitly {pct(ex)}, {ex['seconds']:.2f} s"
        text += ")"
        if p1 is not None:
            text += f"; P1 {pct(p1)} ({p1['seconds']:.2f} s)"
        if sp is not None:
            text += f", {SPRING} {pct(sp)} ({sp['seconds']:.2f} s)"
        out.append(text + ".")
    return out


def cheapest_sentence(good: pd.DataFrame, column: str, tolerance: float) -> str:
    """The cheapest point (CPU time) whose error ``column`` is at most ``tolerance``, and the
    cheapest spring-model point within it, in a sentence.

    Examples
    --------
    >>> df = pd.DataFrame({"method": ["P1 static", "spring-energy static", "P2 static"],
    ...     "mesh": ["10x1x1", "20x2x2", "10x1x1"], "seconds": [0.1, 0.5, 0.3],
    ...     "err": [0.2, 0.04, 0.01]})
    >>> overall, spring = cheapest_sentence(df, "err", 0.05).split("; ")
    >>> overall
    'Within 5% of the reference the cheapest point is P2 static on 10x1x1 (0.30 s, 1.0% off)'
    >>> spring[spring.index("spring-energy"):]
    'spring-energy static on 20x2x2 (0.50 s, 4.0% off), 1.7x its time.'
    """

    def point(r) -> str:
        return f"{r['method']} on {r['mesh']} ({r['seconds']:.2f} s, {100 * r[column]:.1f}% off)"

    within = good[good[column] <= tolerance].sort_values("seconds")
    head = f"Within {tolerance:.0%} of the reference"
    if within.empty:
        return f"{head} no point qualifies: every method's error is larger on these levels."
    first = within.iloc[0]
    text = f"{head} the cheapest point is {point(first)}"
    if str(first["method"]).startswith("spring"):
        return text + "; it is a spring-model point."
    spring = within[within["method"].str.startswith("spring")]
    if spring.empty:
        return text + "; no spring-model point is within it."
    sp = spring.iloc[0]
    ratio = sp["seconds"] / first["seconds"]
    return text + f"; the cheapest spring-model point is {point(sp)}, {ratio:.1f}x its time."
