"""XPBD released from its rest state: its own frames as the time integration.

XPBD has no forces to integrate explicitly (:class:`peers.plugin.XPBDModel` has no
mechanical system), so its release run is its own: the static state is its run to rest
(:meth:`peers.xpbd.XPBD.solve`, ``auto`` damping) under the scene's loads, then undamped
substeps with the loads off. The substep is the settings' own ``dt / substeps`` unless that
exceeds ``safety`` times ``2 / omega_max`` of XPBD's own energy
(:class:`peers.xpbd.StableNeoHookean`, at rest and loaded, as every explicit model's step);
then the substeps per frame are raised until it does not (:mod:`.step_search` measures how
little past that bound XPBD survives). A frame of ``substeps`` substeps advances exactly as
``substeps`` frames of one, so the release runs frames of one substep and reads the probe
at every substep; the energy balance is kinetic + stable neo-Hookean strain (the loads are
off, no work). The plug-in offers it as :meth:`peers.plugin.XPBDModel.release_run` and
:meth:`~peers.plugin.XPBDModel.step_timer` (the dynamics study).

Examples
--------
>>> substeps_for(1.0 / 60.0, 20, 1e-4)   # 1/60 s frames need 167 substeps of <= 1e-4 s
167
>>> substeps_for(1.0 / 60.0, 20, 1.0)    # the setting's 20 already fit
20
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from springfem.errors import SolverError
from springfem.mechanics.limits import Deadline, SolveStopped, checkpoint
from springfem.scene import Scene

from .energy import StableNeoHookean
from .solver import XPBD, XPBDSettings


def substeps_for(dt: float, substeps: int, h_max: float) -> int:
    """The substeps per frame of ``dt`` so that ``dt / substeps <= h_max`` (at least the
    setting's ``substeps``)."""
    return max(int(substeps), math.ceil(dt / h_max * (1 - 1e-12)))


def raised_solver(
    scene: Scene, settings: XPBDSettings, safety: float, x_load: np.ndarray | None = None
) -> tuple[XPBD, tuple[float, float]]:
    """The XPBD of ``scene`` at ``settings`` with the substeps raised as the module
    docstring says; its critical steps ``(at rest, loaded)`` (loaded: at ``x_load``, else
    the rest value)."""
    from springfem.mechanics import stable_time_step

    energy = StableNeoHookean(scene)
    rest = stable_time_step(energy)[0]
    loaded = stable_time_step(energy, x=x_load)[0] if x_load is not None else rest
    n = substeps_for(settings.dt, settings.substeps, safety * min(rest, loaded))
    return XPBD(scene, replace(settings, substeps=n)), (rest, loaded)


def release_run(
    scene: Scene,
    settings: XPBDSettings,
    *,
    t_end: float,
    safety: float,
    samples: int,
    probe: tuple[np.ndarray, np.ndarray],
) -> dict[str, Any]:
    """XPBD released from its rest state for ``t_end`` seconds.

    Parameters
    ----------
    scene
        The scene (its loads make the rest state; they are off after the release).
    settings
        XPBD's settings (the substeps raised as the module docstring says).
    t_end, safety, samples
        Run length (s), the substep's bound over ``2 / omega_max``, energy records (about).
    probe
        ``(nodes, weights)``: the probe displacement is ``weights @ u[nodes]``.

    Returns
    -------
    dict
        ``status`` (``ok``, ``failed``, ``stopped``, ``blew up``) and ``message``; the
        critical steps ``dt_crit_rest``, ``dt_crit_loaded``; the substep ``dt``, ``steps``,
        ``frames_to_rest``, ``substeps_per_frame``, ``setting_h`` (the settings' own
        substep), ``seconds``; the probe displacement after every substep ``u_steps``
        ``(steps + 1, 3)`` (NaN after a stop); ``energy_t``, ``energy`` when ``ok``.
    """
    solver, _ = raised_solver(scene, settings, safety)
    try:  # the caller's time cap holds inside the frames too (checkpoint in XPBD.solve)
        with Deadline().watch():
            static = solver.solve()
    except (SolverError, SolveStopped) as exc:
        stopped = isinstance(exc, SolveStopped)
        return {"status": "stopped" if stopped else "failed", "message": str(exc)[:200]}
    if not static.converged:
        return {"status": "failed", "message": f"xpbd: no rest after {static.frames} frames"}
    x = solver.x0 + static.u
    solver, (dt_rest, dt_load) = raised_solver(scene, settings, safety, x)
    s = solver.settings
    h = s.dt / s.substeps
    run = XPBD(scene, replace(s, dt=h, substeps=1, damping=0.0))
    energy = StableNeoHookean(scene)
    steps = int(np.ceil(t_end / h))
    nodes, w = probe
    X = run.x0[nodes]
    U = np.full((steps + 1, 3), np.nan)
    U[0] = w @ (x[nodes] - X)
    v, a, m = np.zeros_like(x), np.zeros_like(x), run.masses[:, None]
    every = max(1, steps // int(samples))
    et, E = [0.0], [energy.strain_energy(x)]
    out: dict[str, Any] = {"status": "ok", "message": "", "dt_crit_rest": dt_rest,
                           "dt_crit_loaded": dt_load, "dt": h, "steps": steps,
                           "frames_to_rest": static.frames, "substeps_per_frame": s.substeps,
                           "setting_h": settings.dt / settings.substeps}  # fmt: skip
    t0 = time.perf_counter()
    with Deadline().watch():
        for k in range(1, steps + 1):
            try:
                checkpoint()
            except SolveStopped as exc:
                out.update(status="stopped", message=f"xpbd: at substep {k}: {exc}"[:200])
                break
            run.advance(x, v, a)
            if not np.isfinite(x).all():
                out.update(status="blew up", message=f"xpbd: positions not finite at substep {k}")
                break
            U[k] = w @ (x[nodes] - X)
            if k % every == 0:
                et.append(k * h)
                E.append(0.5 * float(np.sum(m * v * v)) + energy.strain_energy(x))
    out["seconds"] = time.perf_counter() - t0
    out["u_steps"] = U
    if out["status"] == "ok":
        out["energy_t"], out["energy"] = et, E
    return out


def step_timer(
    scene: Scene, settings: XPBDSettings, safety: float
) -> Callable[[int, Callable[[], None]], None]:
    """A function ``(steps, tick)`` running ``steps`` undamped XPBD substeps from rest under
    the loads, calling ``tick()`` after each (a cost measurement's clock)."""
    solver, _ = raised_solver(scene, settings, safety)
    s = solver.settings
    run = XPBD(scene, replace(s, dt=s.dt / s.substeps, substeps=1, damping=0.0))

    def go(steps: int, tick: Callable[[], None]) -> None:
        x, v = run.start()
        a = run.accelerations(x)
        for _ in range(steps):
            run.advance(x, v, a)
            tick()
        if not np.isfinite(x).all():
            raise SolverError("xpbd: positions not finite in the timed substeps")

    return go


__all__ = ["raised_solver", "release_run", "step_timer", "substeps_for"]
