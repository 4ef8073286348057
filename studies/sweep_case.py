"""One sweep case: build its scene, solve it with every model, measure against the reference.

:func:`run_case` is what a Dask worker (or the client, in-process) runs; it takes and
returns plain JSON-able data, so a case travels to any worker and its result is the case
file written by the client.

Row fields (one row per model)
------------------------------
``model``, ``status`` (``ok`` / ``failed`` / ``reference failed``), ``message`` (why it
failed), ``probe:<name>:u<x|y|z>`` (probe displacement, m), ``rel_l2`` (relative L2 error
over the mesh vertices against the reference), ``rel_max`` (largest nodal error over the
largest reference displacement), ``probe_error:<name>`` (relative error of the probe's
displacement vector), ``volume_change`` (relative), ``iterations``, ``wall_time`` (s, the
solve alone), ``warm`` (false for a model's first solve in its process: that time includes
numba compilation when the compile cache is cold), ``nodes``, ``tets``.

Examples
--------
>>> from studies.sweep_file import parse_sweep
>>> spec = parse_sweep({"scene": "cantilever", "models": ["P1"],
...                     "grid": {"mesh.divisions": [[4, 1, 1]]}})
>>> [(r["model"], r["status"], r["rel_l2"]) for r in run_case(spec.task(0))["rows"]]
[('P1', 'ok', 0.0)]
"""

from __future__ import annotations

import time
from typing import Any

from . import metrics
from .models import run as run_model
from .overrides import scene_with_overrides

NAN = float("nan")
_SOLVED_HERE: set[str] = set()  # models already solved in this process (compiled kernels)


def run_case(task: dict[str, Any]) -> dict[str, Any]:
    """Solve one case with each of its models.

    Parameters
    ----------
    task
        :meth:`studies.sweep_file.SweepSpec.task`: scene table and path, the case's values,
        the models and the reference.

    Returns
    -------
    dict
        ``{"values": ..., "rows": [one row per model], "seconds": case wall time}``.
    """
    t0 = time.perf_counter()
    scene = scene_with_overrides(task["scene"], task["values"].items(), path=task["scene_path"])
    models, reference = task["models"], task["reference"]
    order = [reference] + [m for m in models if m != reference]  # a failed reference is known
    solutions, failures = {}, {}
    warm = {m: m in _SOLVED_HERE for m in order}
    implausible = {}
    for m in order:
        got = run_model(scene, m, check=True)
        if got.solved:
            solutions[m] = got.solution
        else:
            failures[m] = got.message
        if got.status == "implausible":
            implausible[m] = got.message
        _SOLVED_HERE.add(m)
    ref = solutions.get(reference)
    rows = []
    for m in models:
        row: dict[str, Any] = {"model": m, "nodes": scene.mesh.n_points, "tets": scene.mesh.n_tets}
        row["warm"] = warm[m]
        sol = solutions.get(m)
        if sol is None:
            row.update(status="failed", message=failures[m])
            row.update(_probe_columns({p.name: [NAN] * 3 for p in scene.probes}))
            row.update(volume_change=NAN, iterations=None, wall_time=NAN)
        else:
            r = sol.result
            status = "ok" if ref is not None else "reference failed"
            row.update(status="implausible" if m in implausible else status)
            row.update(message=implausible.get(m, ""))
            row.update(_probe_columns(r.probes))
            row.update(
                volume_change=r.volume.get("relative_change", NAN),
                iterations=r.iterations,
                wall_time=r.wall_time,
            )
        row.update(_errors(sol, ref, [p.name for p in scene.probes]))
        rows.append(row)
    return {"values": task["values"], "rows": rows, "seconds": time.perf_counter() - t0}


def _probe_columns(probes: dict[str, list[float]]) -> dict[str, float]:
    return {f"probe:{name}:u{c}": float(u[i]) for name, u in probes.items() for i, c in
            enumerate("xyz")}  # fmt: skip


def _errors(sol, ref, probes: list[str]) -> dict[str, float]:
    out = {"rel_l2": NAN, "rel_max": NAN, **{f"probe_error:{p}": NAN for p in probes}}
    if sol is None or ref is None:
        return out
    out["rel_l2"] = metrics.relative_l2_error(sol.u, ref.u)
    out["rel_max"] = metrics.relative_max_error(sol.u, ref.u)
    for p, err in metrics.probe_error(sol.result.probes, ref.result.probes).items():
        out[f"probe_error:{p}"] = err
    return out
