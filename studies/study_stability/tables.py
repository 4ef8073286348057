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
    "dt": ["scene", "method", "tets", "dt_pred", "dt_measured", "ratio", "setting_h", "failure"],
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


def survival(f: dict[str, pd.DataFrame]) -> pd.DataFrame:
    """Every method's largest step and largest load: per method of the ``dt`` series, its
    largest stable step (s) and ratio on the ``dt`` series' first scene, and, per method of
    the ``load`` series, the largest load factor solved without failure on its first scene
    (``nan`` where a method is not in the series) and the smallest that failed (``nan``:
    none of the series' factors failed).

    Examples
    --------
    >>> dt = pd.DataFrame({"scene": ["a"], "method": ["m"], "dt_measured": [2e-3],
    ...                    "ratio": [1.0]})
    >>> ld = pd.DataFrame({"scene": ["a", "a"], "method": ["m", "m"], "load_factor": [1, 10],
    ...                    "status": ["ok", "diverged"]})
    >>> survival({"dt": dt, "load": ld}).iloc[0].to_dict()["max load factor"]
    1.0
    """
    dt, dl = f["dt"], f["load"]
    dt = dt[dt.scene == dt.scene.iloc[0]] if len(dt) else dt
    dl = dl[dl.scene == dl.scene.iloc[0]] if len(dl) else dl
    rows = []
    for m in dict.fromkeys([*dt["method"], *dl["method"]]):
        d = dt[dt.method == m]
        ok = dl[(dl.method == m) & (dl.status == "ok")]["load_factor"]
        bad = dl[(dl.method == m) & (dl.status != "ok")]["load_factor"]
        rows.append({
            "method": m,
            "dt scene": d.scene.iloc[0] if len(d) else "",
            "largest step (s)": float(d.dt_measured.iloc[0]) if len(d) else float("nan"),
            "step / 2/ω_max": float(d.ratio.iloc[0]) if len(d) else float("nan"),
            "load scene": dl.scene.iloc[0] if (dl.method == m).any() else "",
            "max load factor": (float(ok.max()) if len(ok) else 0.0) if (dl.method == m).any()
            else float("nan"),
            "first failing factor": float(bad.min()) if len(bad) else float("nan"),
        })  # fmt: skip
    return pd.DataFrame(rows)


def write_tables(ctx: StudyContext, f: dict[str, pd.DataFrame]) -> list[Table]:
    """Write the tables of the series that ran: critical step, largest load, locking, failure
    map.
    """
    captions = {
        "dt": (
            "critical_dt",
            "Predicted critical step 2/ω_max against the measured largest stable step "
            "(bisection, undamped runs from a perturbed rest state, loads off); ratio = "
            "measured / predicted. XPBD (its own settings, and Jacobi): the largest substep "
            "h it survives (finite, no inverted element, energy within 100x of its start) "
            "against 2/ω_max of its own energy; setting_h is its configured substep "
            "dt/substeps, failure why the first failing step failed.",
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
    out = [ctx.table(f[k], name, caption) for k, (name, caption) in captions.items() if len(f[k])]
    if len(f["dt"]) or len(f["load"]):
        out.insert(0, ctx.table(survival(f), "survival", (
            "Every method's largest step and largest load: the largest stable explicit step "
            "(XPBD: the largest surviving substep) on the critical-step series' first scene, "
            "and the largest load factor solved without failure on the largest-load series' "
            "first scene (nan: not in that series).")))  # fmt: skip
    return out
