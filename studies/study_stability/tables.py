"""Tables of the stability study: one frame and one table per series."""

from __future__ import annotations

import pandas as pd

from ..registry import StudyContext, Table
from ..scenes import case_scene

#: The case keys each series' frame keeps beside the scene and method, with their column names.
KEYS = {
    "dt": {},
    "load": {"factor": "load_factor"},
    "lock": {"nu": "nu"},
    "map": {"factor": "load_factor", "dt_factor": "dt_factor"},
}
#: The result columns each series' table shows.
COLUMNS = {
    "dt": ["scene", "method", "tets", "dt_pred", "dt_measured", "ratio"],
    "load": ["scene", "method", "load_factor", "status", "u/size", "message"],
    "lock": ["scene", "method", "nu", "tip_ratio", "volume_change", "inverted"],
    "map": ["scene", "method", "load_factor", "dt_factor", "status"],
}


def frames(cases: dict[str, list[dict]], results: dict[str, list[dict]]) -> dict[str, pd.DataFrame]:
    """The four series as frames: ``dt`` (scene, method, tets, predicted and measured step,
    ratio), ``load`` (load factor, status, largest |u| over the body's size, message),
    ``lock`` (ν, tip ratio, volume change, inverted) and ``map`` (load factor, dt factor,
    status).
    """
    out = {}
    for k, keys in KEYS.items():
        rows = []
        for c, r in zip(cases[k], results[k], strict=True):
            row = {"scene": c["scene"], "method": c["method"]}
            row.update({name: c[key] for key, name in keys.items()})
            if k == "dt":
                row["tets"] = case_scene(c).mesh.n_tets
            rows.append({**row, **r})
        out[k] = pd.DataFrame(rows, columns=None if rows else COLUMNS[k])
        out[k] = out[k].reindex(columns=COLUMNS[k])
    return out


def write_tables(ctx: StudyContext, f: dict[str, pd.DataFrame]) -> list[Table]:
    """Write the tables of the series that ran: critical step, largest load, locking, failure
    map.
    """
    captions = {
        "dt": (
            "critical_dt",
            "Predicted critical step 2/ω_max against the measured largest stable step "
            "(bisection, undamped runs from a perturbed rest state, loads off); ratio = "
            "measured / predicted.",
        ),
        "load": (
            "max_load",
            "Static solves under the scene's loads times the load factor: status and the "
            "largest displacement over the body's size.",
        ),
        "lock": (
            "locking",
            "Cantilever tip deflection / Timoshenko and relative volume change against "
            "Poisson's ratio.",
        ),
        "map": (
            "failure_map",
            "Explicit damped dynamics on the load × time-step grid: ok, blew up, or ended "
            "with inverted elements.",
        ),
    }
    return [ctx.table(f[k], name, caption) for k, (name, caption) in captions.items() if len(f[k])]
