"""Tables of the locking study: every (scene, method, nu, level) with its deflection, error
and solve time; the reference per Poisson ratio; the cheapest adequate method.

The deflection is one component of the probe's displacement (Cook: ``u_y`` of the corner;
Land's beam: ``u_z`` of the tip; a user's scene: the component of the reference's largest
``|u|``). The reference at each Poisson ratio is :data:`~.cases.REFERENCE` on the finest
level; its Richardson extrapolation through the three levels
(:func:`studies.study_convergence.richardson_limit`) is shown beside it with the
observed order, not used: the study's levels are not fine enough to show that the order is
asymptotic.

Examples
--------
>>> df = pd.DataFrame({"scene": "s", "nu": 0.3, "method": ["a", "b", "c"],
...     "status": "ok", "error": [0.01, 0.2, 0.04], "seconds": [3.0, 0.1, 1.0],
...     "reference": [True, False, False]})
>>> cheapest(df, 0.05).method
'c'
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from ..registry import StudyContext, Table
from ..study_convergence import richardson_limit
from .cases import LINEAR_TETS, REFERENCE, TOLERANCE

AXES = "xyz"


def result_frame(cases: list[dict[str, Any]], results: list[dict[str, Any]]) -> pd.DataFrame:
    """One row per case: scene, method, nu, level factor, status, probe displacement,
    seconds, tets."""
    rows = []
    for c, r in zip(cases, results, strict=True):
        u = r.get("u", [np.nan] * 3)
        rows.append(
            {
                "scene": c["scene"],
                "method": c["method"],
                "nu": c["nu"],
                "factor": c["factor"],
                "tets": r.get("tets"),
                "status": r["status"],
                "load": r.get("load", np.nan),
                "ux": u[0],
                "uy": u[1],
                "uz": u[2],
                "seconds": r.get("seconds", np.nan),
                "message": r.get("message", ""),
                "component": c.get("component"),
            }
        )
    return pd.DataFrame(rows)


def deflection_component(g: pd.DataFrame) -> int:
    """The compared component of one scene: its ``component`` (a bundled scene's), else
    the axis of the largest mean ``|u|`` of the reference on the finest level."""
    given = g.component.dropna()
    if len(given):
        return int(given.iloc[0])
    ref = g[(g.method == REFERENCE) & (g.factor == g.factor.max()) & (g.status == "ok")]
    src = ref if len(ref) else g[g.status == "ok"]
    if src.empty:
        return 0
    return int(np.argmax(np.abs(src[["ux", "uy", "uz"]].to_numpy()).mean(axis=0)))


def with_errors(df: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The rows with ``deflection``, ``error`` (relative, against the reference of their
    scene and nu) and ``reference`` (the row is the reference); and the references: one row
    per (scene, nu) with the finest-level value, the Richardson limit and observed order.
    """
    out, refs = [], []
    for scene, g in df.groupby("scene", sort=False):
        g = g.copy()
        k = deflection_component(g)
        g["deflection"] = g[f"u{AXES[k]}"]
        g["axis"] = AXES[k]
        finest = g.factor.max()
        g["reference"] = (g.method == REFERENCE) & (g.factor == finest)
        for nu, gn in g.groupby("nu", sort=True):
            p2 = gn[(gn.method == REFERENCE) & (gn.status == "ok")].sort_values("factor")
            top = p2[p2.factor == finest]
            value = float(top.deflection.iloc[0]) if len(top) else np.nan
            limit, order = (np.nan, np.nan)
            if len(p2) >= 3:
                h = 1.0 / p2.factor.to_numpy(float)[-3:]
                limit, order = richardson_limit(h, p2.deflection.to_numpy(float)[-3:])
            refs.append(
                {
                    "scene": scene,
                    "nu": nu,
                    "axis": AXES[k],
                    "reference": value,
                    "tets": int(top.tets.iloc[0]) if len(top) else np.nan,
                    "richardson": limit,
                    "observed order": order,
                    "extrapolation shift": abs(limit / value - 1.0) if value else np.nan,
                }
            )
            g.loc[gn.index, "ref_value"] = value
        g["error"] = np.abs(g.deflection / g.ref_value - 1.0)
        g.loc[g.status != "ok", "error"] = np.nan
        out.append(g)
    return pd.concat(out, ignore_index=True), pd.DataFrame(refs)


def cheapest(g: pd.DataFrame, tolerance: float = TOLERANCE) -> pd.Series | None:
    """The cheapest row of ``g`` (one scene and nu) within ``tolerance`` of the reference.

    Candidates: solved (``ok``) rows other than the reference itself, with a relative
    error at most ``tolerance``; the cheapest has the smallest ``seconds`` (a tie: the
    smaller error). ``None`` when no row qualifies.
    """
    ok = g[(g.status == "ok") & ~g.reference.astype(bool) & (g.error <= tolerance)]
    if ok.empty:
        return None
    return ok.sort_values(["seconds", "error"]).iloc[0]


def answer_frame(df: pd.DataFrame, tolerance: float = TOLERANCE) -> pd.DataFrame:
    """Per (scene, nu): the cheapest method within ``tolerance``, its level, error and time,
    the reference's time, and the locked methods (every level more than ``tolerance`` off)."""
    rows = []
    for (scene, nu), g in df.groupby(["scene", "nu"], sort=False):
        win = cheapest(g, tolerance)
        ref = g[g.reference.astype(bool)]
        close = g[(g.status == "ok") & (g.error <= tolerance)].method.unique()
        unrun = g[g.status == "skipped"].method.unique()
        lin = cheapest(g[g.method.isin(LINEAR_TETS)], tolerance)
        rows.append(
            {
                "scene": scene,
                "nu": nu,
                "cheapest within tolerance": "none" if win is None else win.method,
                "its tets": np.nan if win is None else win.tets,
                "its error": np.nan if win is None else win.error,
                "its seconds": np.nan if win is None else win.seconds,
                "cheapest on linear tets": "none" if lin is None else lin.method,
                "its tets (linear)": np.nan if lin is None else lin.tets,
                "its error (linear)": np.nan if lin is None else lin.error,
                "its seconds (linear)": np.nan if lin is None else lin.seconds,
                "reference seconds": ref.seconds.iloc[0] if len(ref) else np.nan,
                "never within tolerance": ", ".join(
                    m for m in g.method.unique() if m not in close and m not in unrun
                )
                or "none",
                "not run on every level": ", ".join(m for m in unrun if m not in close) or "none",
            }
        )
    return pd.DataFrame(rows)


def cases_table(ctx: StudyContext, df: pd.DataFrame) -> Table:
    """Write the table of every (scene, method, nu, level)."""
    cols = ["scene", "method", "nu", "tets", "status", "load", "axis", "deflection", "error",
            "seconds", "message"]  # fmt: skip
    table = df[cols].sort_values(["scene", "nu", "method", "tets"], kind="stable")
    return ctx.table(
        table,
        "locking",
        "Every scene, method, Poisson ratio and mesh level: status (``partial``: the solve "
        "stopped at the load factor ``load``, by the time cap or a failure), the compared "
        "probe displacement component (``axis``), its relative error against the "
        f"reference ({REFERENCE} on the finest level at the same Poisson ratio) and the "
        "static solve's wall time (s; median of three under half a second, after an untimed "
        "warm-up solve of each method).",
    )


def reference_table(ctx: StudyContext, refs: pd.DataFrame) -> Table:
    """Write the references per (scene, nu)."""
    return ctx.table(
        refs,
        "references",
        f"The reference per scene and Poisson ratio: {REFERENCE} on the finest level, its "
        "Richardson extrapolation through the three levels (h ∝ 1 / refinement factor) with "
        "the observed order (empty: the three values are not monotone), and how far the "
        "extrapolation lies from the finest value.",
    )


def answer_table(ctx: StudyContext, answers: pd.DataFrame, tolerance: float = TOLERANCE) -> Table:
    """Write the cheapest adequate method per (scene, nu)."""
    return ctx.table(
        answers,
        "cheapest",
        f"Per scene and Poisson ratio: the cheapest method and level (smallest solve wall "
        f"time) whose deflection is within {tolerance:.0%} of the reference, excluding the "
        "reference itself (``none``: no method qualifies), the same among the methods on "
        "the mesh's own vertices (linear tets: P1-type FEM and the spring elements), the "
        f"reference's own time, the methods more than {tolerance:.0%} off on every level, "
        "and those not run on every level (predicted over the cap of a solve, or over the "
        "study's budget) and not within the tolerance where they ran.",
    )
