"""Tables of the speed-accuracy study: the points (with the Pareto front) and step costs.

A point's error is the relative error of the scene's probe displacement (the probe of its
closed-form reference, e.g. the cantilever's ``tip``, else its first probe) against the
reference, or, on a scene without probes, the relative L2 error at the level-1 vertices;
both are in the table. Beside it, :data:`SAME` is the relative L2 error at the level-1
vertices against the ``P1-NH`` static point on the same level (where it ran): the error of a
P1 model against the Newton answer of its own mesh, e.g. XPBD's substep error.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from .. import metrics
from ..analytic import reference
from ..registry import StudyContext, Table
from ..scenes import StudyScene
from ..study_convergence.levels import level_label
from ..tables import write_table
from .cases import EXPLICIT_FEM, SPRING, STEP_COUNT, STEP_REPEATS, method_name

L2 = "L2 err (level-1 vertices)"
#: The column of the error against P1-NH static on the same level.
SAME = "L2 vs P1-NH same mesh"


def pareto_front(seconds: np.ndarray, error: np.ndarray) -> np.ndarray:
    """Mask of the non-dominated points: no other point is at least as fast and as accurate
    and strictly better in one of the two.

    Examples
    --------
    >>> pareto_front(np.array([1.0, 2.0, 3.0, 2.5]), np.array([0.5, 0.1, 0.2, 0.1])).tolist()
    [True, True, False, False]
    """
    t, e = np.asarray(seconds, float), np.asarray(error, float)
    keep = np.ones(t.size, dtype=bool)
    for i in range(t.size):
        better = (t <= t[i]) & (e <= e[i]) & ((t < t[i]) | (e < e[i]))
        keep[i] = not better.any()
    return keep


def setting_label(solution: str, setting: dict) -> str:
    """A point's setting in the tables (empty for a static solve).

    Examples
    --------
    >>> setting_label("explicit", {"tol": 1e-6, "dt_safety": 0.5})
    'tol 1e-06, dt = 0.5 dt_crit'
    >>> setting_label("static", {"model": {"substeps": 20, "iterations": 2}})
    'substeps 20, iterations 2'
    """
    if setting.get("model"):
        return ", ".join(f"{k} {v}" for k, v in setting["model"].items())
    if solution == "implicit":
        return f"dt = {setting['dt_factor']:g} dt_crit"
    if "dt_safety" in setting:
        return f"tol {setting['tol']:g}, dt = {setting['dt_safety']:g} dt_crit"
    return ""


@dataclass(frozen=True)
class Measure:
    """What a scene's points are measured by: a probe, or the level-1 field.

    Attributes
    ----------
    probe
        The probe, or ``None`` (L2 at the level-1 vertices).
    analytic
        The probe's closed-form ``(component, value, source)``, if the scene has one.
    """

    probe: str | None
    analytic: tuple[int, float, str] | None = None

    @property
    def column(self) -> str:
        return f"{self.probe}_error" if self.probe else L2

    @property
    def key(self) -> str:
        """The headline keys' prefix (``tip_error``, ``l2_error``)."""
        return f"{self.probe}_error" if self.probe else "l2_error"


def measure(s: StudyScene, ref: dict) -> Measure:
    """The measure of a scene's points (see the module docstring)."""
    hook = reference(s, None)
    if hook is not None:
        probe, component, value, source = hook
        return Measure(probe, (component, value, source))
    return Measure(next(iter(ref["probes"]), None))


def _relative(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def points_frame(
    s: StudyScene, cases: list[dict], results: list[dict], ref: dict, how: Measure
) -> pd.DataFrame:
    """One row per point: method, level, setting, status, CPU and wall time, errors against
    the reference (and the probe over its closed form), steps, message, on the Pareto front.
    """
    u_ref = np.asarray(ref["u"], float)
    same = {
        c["factor"]: np.asarray(r["u"], float)
        for c, r in zip(cases, results, strict=True)
        if (c["model"], c["solution"]) == (EXPLICIT_FEM, "static") and r["status"] == "ok"
    }
    rows = []
    for c, r in zip(cases, results, strict=True):
        ok = r["status"] == "ok"
        row = {
            "method": method_name(c["model"], c["solution"], c["setting"]),
            "factor": c["factor"],
            "mesh": level_label(s.table, c["factor"]),
            "tets": r["tets"],
            "setting": setting_label(c["solution"], c["setting"]),
            "status": r["status"],
            "seconds": r["cpu_seconds"],
            "wall_seconds": r["seconds"],
        }
        probe = r["probes"][how.probe] if ok and how.probe else None
        if how.probe is not None:
            row[how.column] = _relative(probe, ref["probes"][how.probe]) if ok else np.nan
        if how.analytic is not None:
            component, value, source = how.analytic
            row[f"{how.probe} / {source}"] = probe[component] / value if ok else np.nan
        row[L2] = metrics.relative_l2_error(np.asarray(r["u"], float), u_ref) if ok else np.nan
        if same:
            own = same.get(c["factor"]) if ok else None
            u = np.asarray(r["u"], float) if own is not None else None
            row[SAME] = np.nan if u is None else metrics.relative_l2_error(u, own)
        row["steps"] = r.get("steps", np.nan)
        row["message"] = r.get("message", "")
        rows.append(row)
    df = pd.DataFrame(rows)
    ok = df["status"] == "ok"
    df["pareto"] = False
    df.loc[ok, "pareto"] = pareto_front(
        df.loc[ok, "seconds"].to_numpy(), df.loc[ok, how.column].to_numpy()
    )
    return df


def step_frame(s: StudyScene, factors: list[int], steps: list[dict]) -> pd.DataFrame:
    """One row per level: the cost of one explicit step, spring model and explicit P1 FEM
    (``steps``: the levels' :func:`~.cases.step_cost_work` results).
    """
    a, b = method_name(SPRING, "explicit"), method_name(EXPLICIT_FEM, "explicit")
    return pd.DataFrame(
        [
            {
                "mesh": level_label(s.table, k),
                "tets": r["tets"],
                f"{a} ms/step": 1e3 * r[f"{SPRING}_wall"],
                f"{b} ms/step": 1e3 * r[f"{EXPLICIT_FEM}_wall"],
                "ratio (wall)": r["ratio_wall"],
                f"{a} CPU ms/step": 1e3 * r[f"{SPRING}_cpu"],
                f"{b} CPU ms/step": 1e3 * r[f"{EXPLICIT_FEM}_cpu"],
                "ratio (CPU)": r["ratio_cpu"],
            }
            for k, r in zip(factors, steps, strict=True)
        ]
    )


def write_tables(
    ctx: StudyContext,
    s: StudyScene,
    df: pd.DataFrame,
    sdf: pd.DataFrame | None,
    ref: dict,
    ref_text: str,
    how: Measure,
    suffix: str = "",
) -> list[Table]:
    """Write the points and step-cost tables (``sdf`` ``None``: no step costs) and the
    failures, if any; ``ref_text`` names the reference (method and level).
    """
    show = df.drop(columns=["message"]).copy()
    if how.probe is not None:
        show[f"{how.column} %"] = 100 * show.pop(how.column)
    against = f"{how.probe} displacement" if how.probe else "field at the level-1 vertices"
    context = ""
    if how.analytic is not None:
        component, value, source = how.analytic
        ratio = ref["probes"][how.probe][component] / value
        context = f"; its {how.probe} is {ratio:.4f} × {source}"
    tables = [
        ctx.table(
            show,
            f"points{suffix}",
            f"{s.label}: every (method, level, setting) point: CPU time (`seconds`) and wall "
            "time from the scene to the answer (model build and time-step estimate included; "
            "the solves are serial, so CPU time is the wall time of an idle machine, while a "
            "shared machine's wall times vary), relative error of the "
            f"{against} against {ref_text} ({ref['tets']} tets{context}), status, "
            "explicit/implicit steps, and whether the point is on the Pareto front.",
        )
    ]
    if sdf is not None:
        tables.append(
            ctx.table(
                sdf,
                f"step_cost{suffix}",
                "Cost of one explicit step (forces + update through the same solver loop), "
                "spring model vs explicit P1 neo-Hookean FEM on the same mesh: medians of "
                f"{STEP_REPEATS} alternating repeats of {STEP_COUNT}-500 steps; wall and CPU "
                "(process) time.",
            )
        )
    failed = df[df["status"] != "ok"]
    if len(failed):
        write_table(
            failed[["method", "mesh", "setting", "status", "message"]],
            ctx.path(f"failures{suffix}"),
        )
    return tables
