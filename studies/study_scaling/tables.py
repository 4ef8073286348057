"""Tables of the scaling study: explicit-step and static-solve costs, fitted slopes."""

from __future__ import annotations

import pandas as pd

from ..metrics import fitted_rate
from ..registry import StudyContext, Table
from .cases import REPEATS, STATIC_METHODS


def frames(
    steps: list[dict], static_cases: list[dict], static: list[dict]
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The explicit-step frame (one row per mesh) and the static frame (one row per solve)."""
    sdf = pd.DataFrame(
        [
            {
                "tets": s["tets"],
                "nodes": s["nodes"],
                "spring_ms_per_step": 1e3 * s["spring_step_cpu"],
                "fem_ms_per_step": 1e3 * s["fem_step_cpu"],
                "spring_over_fem": s["ratio_cpu"],
                "spring_wall_ms": 1e3 * s["spring_step_wall"],
                "fem_wall_ms": 1e3 * s["fem_step_wall"],
                "spring_setup_s": s["spring_setup_cpu"],
                "fem_setup_s": s["fem_setup_cpu"],
            }
            for s in steps
        ]
    )
    tdf = pd.DataFrame(
        [
            {
                "method": c["method"],
                "tets": r["tets"],
                "dofs": r["dofs"],
                "cpu_s": r["cpu"],
                "wall_s": r["wall"],
                "newton_iterations": r["iterations"],
                "linear_solver": r["linear_solver"],
            }
            for c, r in zip(static_cases, static)
        ]
    )
    return sdf, tdf


def slopes(sdf: pd.DataFrame, tdf: pd.DataFrame) -> dict[str, float]:
    """Fitted log-log slopes of cost against tet count per series: ``step_spring``,
    ``step_fem``, ``setup_spring``, ``setup_fem`` and ``static_<method>``.
    """
    n_step = sdf["tets"].to_numpy(float)
    slope = {
        "step_spring": fitted_rate(n_step, sdf["spring_ms_per_step"]),
        "step_fem": fitted_rate(n_step, sdf["fem_ms_per_step"]),
        "setup_spring": fitted_rate(n_step, sdf["spring_setup_s"]),
        "setup_fem": fitted_rate(n_step, sdf["fem_setup_s"]),
    }
    for m in STATIC_METHODS:
        g = tdf[tdf["method"] == m]
        slope[f"static_{m}"] = fitted_rate(g["tets"], g["cpu_s"])
    return slope


def write_tables(
    ctx: StudyContext, sdf: pd.DataFrame, tdf: pd.DataFrame, slope: dict[str, float]
) -> list[Table]:
    """Write the explicit-step, static-solve and slope tables."""
    fits = pd.DataFrame([{"series": k, "fitted slope": v} for k, v in slope.items()])
    return [
        ctx.table(
            sdf,
            "explicit_step",
            f"Cost of one explicit step (serial kernels, forces + update through the solver loop; "
            f"CPU ms, median of {REPEATS} alternating repeats; wall ms beside) and of the set-up "
            f"(CPU s), spring model vs explicit P1 neo-Hookean FEM on the same mesh.",
        ),
        ctx.table(
            tdf,
            "static_solve",
            "One static solve from the scene (set-up, assembly, Newton or linear solve): CPU and "
            "wall seconds, Newton iterations and the linear solver used.",
        ),
        ctx.table(
            fits,
            "slopes",
            "Fitted log-log slopes of cost against tet count (1 = linear scaling).",
        ),
    ]
