"""The time series of a timed spring run, and the status line it ends with.

Examples
--------
>>> from types import SimpleNamespace
>>> import numpy as np
>>> info = SimpleNamespace(kinetic=np.zeros(0), times=[0.0, 0.5], steps=2)
>>> end_of_run(info, None)["status"]
'end of run at t = 0.5 s after 2 steps: rest unknown'
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from springfem.scene import Scene

from .options import SpringOptions


def dynamic_series(scene: Scene, model, opts: SpringOptions, folder) -> object:
    """The :class:`~springfem.series.SeriesWriter` of a timed run with ``[output] interval``.

    Parameters
    ----------
    scene, model, opts
        Scene, its :class:`~springmodel.model.SpringModel` and options.
    folder
        Output folder of the series, or None.

    Returns
    -------
    SeriesWriter or None
        None for equilibrium solves, without a folder or without an interval.
    """
    from springfem.scene import OutputOptions
    from springfem.series import SeriesWriter

    out = OutputOptions.of(scene)
    timed = opts.steps is not None or opts.t_end is not None
    if folder is None or out.interval is None or not timed:
        return None
    return SeriesWriter(
        Path(folder), scene.mesh, out.interval, masses=model.masses,
        potential=model.energy, probes=scene.probe_displacements if out.probes_history else None,
    )  # fmt: skip


def end_of_run(info, writer) -> dict:
    """``status`` ("end of run at t = … : at rest / still moving"), ``at_rest``, series files.

    Parameters
    ----------
    info
        Outcome of the timed solve (``kinetic``, ``times``, ``steps``).
    writer
        The run's series writer (closed here), or None.

    Returns
    -------
    dict
        ``status``, ``at_rest``, ``end_time`` and, with a writer, ``series`` and ``frames``.
    """
    from springfem.series import reached_rest

    if writer is not None:
        summary = writer.close(plot=writer.probes is not None)
        return {
            "status": summary.status_line(),
            "at_rest": summary.at_rest,
            "end_time": summary.end_time,
            "series": str(summary.pvd),
            "frames": len(summary.frames),
        }
    kinetic = np.asarray(getattr(info, "kinetic", []))
    at_rest = reached_rest(kinetic) if kinetic.size else None
    t_end = float(info.times[-1]) if len(getattr(info, "times", [])) else 0.0
    rest = {True: "at rest", False: "still moving", None: "rest unknown"}[at_rest]
    return {
        "status": f"end of run at t = {t_end:.6g} s after {info.steps} steps: {rest}",
        "at_rest": at_rest,
        "end_time": t_end,
    }
