"""Tables of the dynamics study: the probe error against explicit P1 over time, the energy
balance, the stable step and the cost per step of each model.

Error measures (the probe displacement vector ``u(t)`` on the common time grid): the
relative L2 error over the run ``sqrt(sum |u - u_ref|^2 / sum |u_ref|^2)`` and the max
error ``max |u - u_ref| / max |u_ref|``. Energy drift: ``max |E(t) - E(0)| / E(0)`` of the
model's own balance ``E = kinetic + strain - work``.

Examples
--------
>>> t = [0.0, 1.0, 2.0]
>>> ref = {"status": "ok", "t": t, "u": [[0, 0, 1.0], [0, 0, -1.0], [0, 0, 1.0]]}
>>> m = {"status": "ok", "t": t, "u": [[0, 0, 1.0], [0, 0, -0.9], [0, 0, 1.0]]}
>>> l2, mx = probe_errors(m, ref)
>>> round(l2, 4), round(mx, 4)
(0.0577, 0.1)
>>> round(energy_drift({"energy": [2.0, 2.1, 1.98]}), 12)
0.05
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from ..registry import StudyContext, Table


def probe_errors(run: dict[str, Any], ref: dict[str, Any]) -> tuple[float, float]:
    """Relative L2 and max probe error of ``run`` against ``ref`` over the common grid
    (``nan`` when either did not finish)."""
    if run.get("status") != "ok" or ref.get("status") != "ok":
        return float("nan"), float("nan")
    u, r = np.asarray(run["u"]), np.asarray(ref["u"])
    d = np.linalg.norm(u - r, axis=1)
    n = np.linalg.norm(r, axis=1)
    return float(np.sqrt(np.sum(d**2) / np.sum(n**2))), float(d.max() / n.max())


def energy_drift(run: dict[str, Any]) -> float:
    """``max |E(t) - E(0)| / E(0)`` of the recorded balance (``nan`` without one)."""
    E = np.asarray(run.get("energy", []), dtype=float)
    if E.size < 2 or not np.all(np.isfinite(E)) or E[0] == 0:
        return float("nan")
    return float(np.abs(E - E[0]).max() / abs(E[0]))


def energy_change(run: dict[str, Any]) -> float:
    """``(E(end) - E(0)) / E(0)`` of the recorded balance (``nan`` without one): its sign
    tells dissipation from gain."""
    E = np.asarray(run.get("energy", []), dtype=float)
    if E.size < 2 or not np.all(np.isfinite(E)) or E[0] == 0:
        return float("nan")
    return float((E[-1] - E[0]) / abs(E[0]))


def dominant(u: list[float]) -> int:
    """The component of the largest static probe displacement."""
    return int(np.argmax(np.abs(np.asarray(u))))


def result_frame(
    runs: list[tuple[dict, dict]], costs: dict[str, dict[str, float]], refs: dict[str, str]
) -> pd.DataFrame:
    """One row per (scene, model): status, static probe error, errors over time, energy
    drift, critical and used steps, cost per step and per simulated second.

    Parameters
    ----------
    runs
        ``(case, result)`` of every release run.
    costs
        Scene label -> model -> median seconds per step.
    refs
        Scene label -> its reference model.
    """
    by = {(c["scene"], c["model"]): r for c, r in runs}
    rows = []
    for c, r in runs:
        scene, m = c["scene"], c["model"]
        ref = by.get((scene, refs[scene]), {})
        l2, mx = probe_errors(r, ref)
        step = costs.get(scene, {}).get(m, np.nan)
        u0, r0 = np.asarray(r.get("u", [[np.nan] * 3])[0]), np.asarray(ref.get("u", [[0] * 3])[0])
        rows.append(
            {
                "scene": scene,
                "model": m,
                "status": r["status"],
                "static error": float(np.linalg.norm(u0 - r0) / np.linalg.norm(r0)),
                "L2 error (run)": l2,
                "max error": mx,
                "energy drift": energy_drift(r),
                "energy change (end)": energy_change(r),
                "dt_crit rest (s)": r.get("dt_crit_rest", np.nan),
                "dt_crit loaded (s)": r.get("dt_crit_loaded", np.nan),
                "dt (s)": r.get("dt", np.nan),
                "steps": r.get("steps", np.nan),
                "step (µs)": step * 1e6,
                "cost / P1 step": step / costs.get(scene, {}).get(refs[scene], np.nan),
                "cost per simulated ms (s)": step / r.get("dt", np.nan) * 1e-3,
                "message": r.get("message", ""),
            }
        )
    return pd.DataFrame(rows)


def dynamics_table(ctx: StudyContext, df: pd.DataFrame, t_end: dict[str, float]) -> Table:
    """The study's table (every model of every scene)."""
    runs = ", ".join(f"{s}: {t * 1e3:.3g} ms" for s, t in t_end.items())
    caption = (
        "Each model released from its own static state under the scene's loads (undamped "
        f"symplectic Euler, {runs}), probe displacement against explicit P1 of the same law on "
        "the same mesh: static error, relative L2 error over the run and max error; energy "
        "drift max |E(t) - E(0)| / E(0) of kinetic + strain - work and its change at the end; "
        "critical step 2/ω_max at rest and loaded, the step used; median wall time of one "
        "step (interleaved, one process, warm) and its ratio to P1's. XPBD integrates by its "
        "own undamped substeps (the step is its substep, at most the safety times 2/ω_max of "
        "its own energy; the static state its run to rest); a plug-in model that does not "
        "apply to the scene has a row saying why (not applicable), no numbers."
    )
    return ctx.table(df, "dynamics", caption)
