"""Tables of the speed-accuracy study: the points (with the Pareto front) and step costs."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..registry import StudyContext, Table
from ..tables import write_table
from .cases import STEP_COUNT, STEP_REPEATS, Settings


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


def setting_label(method: str, setting: dict) -> str:
    if method == "spring-implicit":
        return f"dt = {setting['dt_factor']:g} dt_crit"
    if "dt_safety" in setting:
        return f"tol {setting['tol']:g}, dt = {setting['dt_safety']:g} dt_crit"
    return ""


def _relative_error(tip, ref) -> float:
    tip, ref = np.asarray(tip, float), np.asarray(ref, float)
    return float(np.linalg.norm(tip - ref) / np.linalg.norm(ref))


def points_frame(cases: list[dict], results: list[dict], ref: dict) -> pd.DataFrame:
    """One row per point: method, mesh, setting, status, CPU and wall time, tip error
    against the reference, tip over Timoshenko, steps, message, on the Pareto front.

    Parameters
    ----------
    cases, results
        The points and their results (:func:`~.cases.point_case`).
    ref
        The reference result (:func:`~.cases.reference_case`).

    Returns
    -------
    DataFrame
    """
    ref_tip = np.asarray(ref["tip"])
    timo = ref["timoshenko"]
    rows = []
    for c, r in zip(cases, results):
        nx, ny = c["mesh"]
        row = {
            "method": c["method"],
            "mesh": f"{nx}x{ny}x{ny}",
            "tets": 6 * nx * ny * ny,
            "setting": setting_label(c["method"], c["setting"]),
            "status": r["status"],
            "seconds": r.get("cpu_seconds", r["seconds"]),
            "wall_seconds": r["seconds"],
            "tip_error": np.nan,
            "tip_over_timoshenko": np.nan,
            "steps": r.get("steps", np.nan),
            "message": r.get("message", ""),
        }
        if r["status"] == "ok":
            row["tip_error"] = _relative_error(r["tip"], ref_tip)
            row["tip_over_timoshenko"] = -r["tip"][2] / timo
        rows.append(row)
    df = pd.DataFrame(rows)
    ok = df["status"] == "ok"
    df["pareto"] = False
    df.loc[ok, "pareto"] = pareto_front(
        df.loc[ok, "seconds"].to_numpy(), df.loc[ok, "tip_error"].to_numpy()
    )
    return df


def step_frame(meshes, steps: list[dict]) -> pd.DataFrame:
    """One row per mesh: the cost of one explicit step, spring model and explicit P1 FEM.

    Parameters
    ----------
    meshes
        ``(nx, ny)`` of each mesh.
    steps
        Their results (:func:`~.cases.step_cost_case`).

    Returns
    -------
    DataFrame
    """
    return pd.DataFrame(
        [
            {
                "mesh": f"{nx}x{ny}x{ny}",
                "tets": s["tets"],
                "spring_ms_per_step": 1e3 * s["spring_wall"],
                "fem_ms_per_step": 1e3 * s["fem_wall"],
                "ratio_wall": s["ratio_wall"],
                "spring_cpu_ms": 1e3 * s["spring_cpu"],
                "fem_cpu_ms": 1e3 * s["fem_cpu"],
                "ratio_cpu": s["ratio_cpu"],
            }
            for (nx, ny), s in zip(meshes, steps)
        ]
    )


def write_tables(
    ctx: StudyContext, df: pd.DataFrame, sdf: pd.DataFrame, ref: dict, p: Settings
) -> list[Table]:
    """Write the points and step-cost tables (and the failures, if any).

    Parameters
    ----------
    ctx
        Where to write.
    df, sdf
        :func:`points_frame` and :func:`step_frame`.
    ref
        The reference result.
    p
        The study's settings.

    Returns
    -------
    list of Table
    """
    rx, ry = p.reference
    ref_tip = np.asarray(ref["tip"])
    timo = ref["timoshenko"]
    ok = df["status"] == "ok"
    show = df.drop(columns=["message"]).copy()
    show["tip_error_%"] = 100 * show.pop("tip_error")
    points = Table(
        write_table(show, ctx.path("points")),
        f"Every (method, mesh, setting) point: CPU time (`seconds`) and wall time from the "
        f"scene to the tip displacement (model build and time-step estimate included; the "
        f"solves are serial, so CPU time is the wall time of an idle machine, while this "
        f"shared machine's wall times varied up to 3x), relative tip error "
        f"against P2 on {rx}x{ry}x{ry} ({ref['tets']} tets; its tip is "
        f"{-ref_tip[2] / timo:.4f} x Timoshenko), status, explicit/implicit steps, and whether "
        f"the point is on the Pareto front.",
    )
    costs = Table(
        write_table(sdf, ctx.path("step_cost")),
        f"Cost of one explicit step (forces + update through the same solver loop), spring "
        f"model vs explicit P1 neo-Hookean FEM on the same mesh: medians of {STEP_REPEATS} "
        f"alternating repeats of {STEP_COUNT}-500 steps; wall and CPU (process) time.",
    )
    failed = df[~ok]
    if len(failed):
        write_table(
            failed[["method", "mesh", "setting", "status", "message"]], ctx.path("failures")
        )
    return [points, costs]
