"""Tables of the stability study: one frame and one table per series."""

from __future__ import annotations

import pandas as pd

from ..registry import StudyContext, Table
from ..tables import write_table


def frames(cases: dict[str, list[dict]], results: dict[str, list[dict]]) -> dict[str, pd.DataFrame]:
    """The four series as frames.

    Parameters
    ----------
    cases, results
        Series name -> its cases and their results (see :func:`~.cases.grids`).

    Returns
    -------
    dict
        ``dt`` (method, tets, predicted and measured step, ratio), ``load`` (method, load
        factor, status, tip/L, message), ``lock`` (method, ν, tip ratio, volume change,
        inverted) and ``map`` (method, load factor, dt factor, status).
    """
    c, r = cases["dt"], results["dt"]
    df = pd.DataFrame([{**{k: a[k] for k in ("method", "nx", "ny")}, **b} for a, b in zip(c, r)])
    df["tets"] = df["nx"] * df["ny"] ** 2 * 6
    df = df[["method", "tets", "dt_pred", "dt_measured", "ratio"]]

    c, r = cases["load"], results["load"]
    dl = pd.DataFrame(
        [{"method": a["method"], "load_factor": a["factor"], **b} for a, b in zip(c, r)]
    )
    dl["tip/L"] = dl["tip"] / 0.1
    dl = dl[["method", "load_factor", "status", "tip/L", "message"]]

    c, r = cases["lock"], results["lock"]
    dk = pd.DataFrame([{"method": a["method"], "nu": a["nu"], **b} for a, b in zip(c, r)])

    c, r = cases["map"], results["map"]
    dm = pd.DataFrame(
        [
            {
                "method": a["method"],
                "load_factor": a["factor"],
                "dt_factor": a["dt_factor"],
                "status": b["status"],
            }
            for a, b in zip(c, r)
        ]
    )
    return {"dt": df, "load": dl, "lock": dk, "map": dm}


def write_tables(ctx: StudyContext, f: dict[str, pd.DataFrame]) -> list[Table]:
    """Write the four tables.

    Parameters
    ----------
    ctx
        Where to write.
    f
        :func:`frames`.

    Returns
    -------
    list of Table
        Critical step, largest load, locking, failure map.
    """
    return [
        Table(
            write_table(f["dt"], ctx.path("critical_dt")),
            "Predicted critical step 2/ω_max against the measured largest "
            "stable step (bisection, undamped runs from a perturbed rest "
            "state); ratio = measured / predicted.",
        ),
        Table(
            write_table(f["load"], ctx.path("max_load")),
            "Static solves of the cantilever under growing end load "
            "(factor × 0.1 Pa): status, tip deflection over length.",
        ),
        Table(
            write_table(f["lock"], ctx.path("locking")),
            "Cantilever tip deflection / Timoshenko and relative volume change "
            "against Poisson's ratio.",
        ),
        Table(
            write_table(f["map"], ctx.path("failure_map")),
            "Explicit damped dynamics on the load × time-step grid: ok, "
            "blew up, or ended with inverted elements.",
        ),
    ]
