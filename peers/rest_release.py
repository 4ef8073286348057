"""A run-to-rest peer (VBD, PD) released from its rest state: its own substeps as the time
integration, for the dynamics study (:class:`peers.rest_model.RestModel`'s ``release_run``
and ``step_timer``; the members of :class:`springfem.model_api.ModelPlugin`'s notes).

The static state is the peer's run to rest under the scene's loads; then undamped substeps
of the settings' own ``dt / substeps`` with the loads off (both peers are implicit: no
explicit stability bound raises their substeps, and ``dt_crit_*`` are NaN). A frame of
``substeps`` substeps advances as ``substeps`` frames of one, so the release runs frames of
one substep and reads the probe after each; the energy balance is kinetic plus the peer's
own strain energy (``strain_energy`` of its solver).

Examples
--------
>>> import inspect
>>> list(inspect.signature(release_run).parameters)[:2]
['model', 'scene']
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from springfem.errors import SolverError
from springfem.mechanics.limits import Deadline, SolveStopped, checkpoint
from springfem.scene import Scene


def _substepper(model: Any, scene: Scene) -> Any:
    """The peer's solver at frames of one undamped substep of its settings."""
    s = model._settings
    return type(model).Solver(scene, replace(s, dt=s.dt / s.substeps, substeps=1, damping=0.0))


def release_run(
    model: Any, scene: Scene, *, t_end: float, safety: float, samples: int,
    probe: tuple[np.ndarray, np.ndarray],
) -> dict[str, Any]:  # fmt: skip
    """Released from its rest state for ``t_end`` seconds (``safety`` unused: implicit).

    Returns
    -------
    dict
        ``status`` (``ok``, ``failed``, ``stopped``, ``blew up``), ``message``, ``dt``,
        ``steps``, ``frames_to_rest``, ``substeps_per_frame``, ``setting_h``, ``seconds``,
        ``dt_crit_rest``/``dt_crit_loaded`` (NaN), the probe displacement after every
        substep ``u_steps`` ``(steps + 1, 3)``; ``energy_t``, ``energy`` when ``ok``.
    """
    name = model.name
    try:
        with Deadline().watch():
            static = model._solver(scene).solve()
    except (SolverError, SolveStopped) as exc:
        stopped = isinstance(exc, SolveStopped)
        return {"status": "stopped" if stopped else "failed", "message": str(exc)[:200]}
    if not static.converged:
        return {"status": "failed", "message": f"{name}: no rest after {static.frames} frames"}
    run = _substepper(model, scene)
    h = run.settings.dt
    x = run.x0 + static.u
    v, v_old = np.zeros_like(x), np.zeros_like(x)
    a = np.zeros_like(x)
    steps = int(np.ceil(t_end / h))
    nodes, w = probe
    X = run.x0[nodes]
    U = np.full((steps + 1, 3), np.nan)
    U[0] = w @ (x[nodes] - X)
    m = run.masses[:, None]
    every = max(1, steps // int(samples))
    et, E = [0.0], [run.strain_energy(x)]
    s = model._settings
    out: dict[str, Any] = {"status": "ok", "message": "", "dt_crit_rest": np.nan,
                           "dt_crit_loaded": np.nan, "dt": h, "steps": steps,
                           "frames_to_rest": static.frames, "substeps_per_frame": s.substeps,
                           "setting_h": h}  # fmt: skip
    t0 = time.perf_counter()
    with Deadline().watch():
        for k in range(1, steps + 1):
            try:
                checkpoint()
            except SolveStopped as exc:
                out.update(status="stopped", message=f"{name}: at substep {k}: {exc}"[:200])
                break
            run.advance(x, v, v_old, a)
            if not np.isfinite(x).all():
                out.update(status="blew up", message=f"{name}: positions not finite at substep {k}")
                break
            U[k] = w @ (x[nodes] - X)
            if k % every == 0:
                et.append(k * h)
                E.append(0.5 * float(np.sum(m * v * v)) + run.strain_energy(x))
    out["seconds"] = time.perf_counter() - t0
    out["u_steps"] = U
    if out["status"] == "ok":
        out["energy_t"], out["energy"] = et, E
    return out


def step_timer(
    model: Any, scene: Scene, safety: float
) -> Callable[[int, Callable[[], None]], None]:
    """A function ``(steps, tick)`` running ``steps`` undamped substeps from rest under the
    loads, calling ``tick()`` after each (``safety`` unused: implicit)."""
    run = _substepper(model, scene)

    def go(steps: int, tick: Callable[[], None]) -> None:
        x, v, v_old = run.start()
        a = run.accelerations(x)
        for _ in range(steps):
            run.advance(x, v, v_old, a)
            tick()
        if not np.isfinite(x).all():
            raise SolverError(f"{model.name}: positions not finite in the timed substeps")

    return go


__all__ = ["release_run", "step_timer"]
