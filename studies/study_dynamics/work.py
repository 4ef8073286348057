"""The work of one case of the dynamics study: the reference's Rayleigh period, one model
released from its static state, and the step cost of every model.

A release run: the model's static equilibrium under the scene's loads (Newton with load
stepping, :func:`springfem.mechanics.static`), then undamped symplectic Euler with the loads
off (:func:`springfem.mechanics.explicit`, ``scale = 0``) at ``safety`` × the model's own
critical step (the smaller of ``2 / omega_max`` at rest and at the loaded state). The probe
is read at every step and interpolated onto a common time grid (linear between steps: an
error of order ``(omega dt)^2 / 8`` of the amplitude, about 1e-8 here); the energy balance
``kinetic + strain - work`` (the work is zero once the loads are off) is recorded about
``samples`` times.

Examples
--------
>>> round(rayleigh_period(np.ones(1), np.array([[0.25, 0, 0]]), np.array([[1.0, 0, 0]])), 6)
3.141593
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from springfem.errors import SolverError
from springfem.scene import Scene

from .. import models
from ..realtime import probe_nodes
from ..scenes import case_scene


def own_integrator(name: str) -> Any:
    """The plug-in of model ``name`` when it brings its own time integration (a
    ``release_run``, :class:`~springfem.model_api.ModelPlugin`), else ``None``."""
    model = models.get(name)
    plugin = getattr(model, "plugin", None) or model
    return plugin if hasattr(plugin, "release_run") else None


def resampled(U: np.ndarray, step: float, t_end: float, samples: int) -> tuple[list, list]:
    """A probe trajectory ``U`` (rows at ``k * step``, NaN after a blow-up) on ``samples + 1``
    even times up to ``t_end``: lists of the times and of ``[x, y, z]`` per time.

    Examples
    --------
    >>> U = np.array([[0.0, 0, 0], [1, 2, 3], [np.nan, np.nan, np.nan]])
    >>> t, u = resampled(U, 1.0, 2.0, 2)
    >>> t, u[1], bool(np.isnan(u[2][0]))
    ([0.0, 1.0, 2.0], [1.0, 2.0, 3.0], True)
    """
    t = np.linspace(0.0, t_end, int(samples) + 1)
    tk = step * np.arange(U.shape[0])
    ok = np.isfinite(U[:, 0])
    u = np.column_stack([np.interp(t, tk[ok], U[ok, i], right=np.nan) for i in range(3)])
    return t.tolist(), u.tolist()


#: Static Newton of the preload: relative tolerance, iterations per load step.
NEWTON_TOL, NEWTON_ITER = 1e-10, 40


def rayleigh_period(masses: np.ndarray, u: np.ndarray, f: np.ndarray) -> float:
    """``2 pi sqrt(u^T M u / u^T f)``: the period of the static deflection ``u`` (n, 3) under
    the load ``f`` with lumped masses ``masses`` as a Rayleigh quotient (the first mode's
    period when ``u`` is close to it)."""
    mu = float(np.sum(masses[:, None] * u * u))
    return float(2.0 * np.pi * np.sqrt(mu / float(np.sum(f * u))))


def probe_weights(scene: Scene) -> tuple[np.ndarray, np.ndarray, str]:
    """``(nodes, weights, name)`` of the probe: the scene's first ``[[probe]]`` (linear in
    its tet), else the node farthest from the fixed nodes
    (:func:`studies.realtime.probe_nodes`)."""
    nodes, w, names = probe_nodes(scene)
    return nodes[0], w[0], names[0]


def preload(system) -> np.ndarray:
    """The static equilibrium ``x`` of ``system`` under its loads (raises
    :class:`~springfem.errors.SolverError` when Newton does not converge)."""
    from springfem.mechanics import static

    info = static(system, tol=NEWTON_TOL, max_iter=NEWTON_ITER)
    if not info.converged:
        raise SolverError(f"static preload did not converge (residual {info.residual:.2g})")
    return info.x


def period_case(case: dict[str, Any]) -> dict[str, Any]:
    """The reference's static probe displacement and Rayleigh period (seconds)."""
    scene = case_scene(case)
    system = models.get(case["model"]).system(scene)
    x = preload(system)
    u = x - system.x0
    f = system.external(x, 1.0)
    nodes, w, name = probe_weights(scene)
    return {"period": rayleigh_period(system.masses, u, f), "probe": name,
            "u_static": (w @ u[nodes]).tolist()}  # fmt: skip


def critical_steps(system, x_load: np.ndarray) -> tuple[float, float]:
    """``2 / omega_max`` at rest and at the loaded state."""
    from springfem.mechanics import stable_time_step

    return stable_time_step(system)[0], stable_time_step(system, x=x_load)[0]


def release_case(case: dict[str, Any]) -> dict[str, Any]:
    """One model released from its static state (see the module docstring).

    Returns ``status`` (``ok``, ``failed``: the static preload, ``blew up``: the
    integrator's blow-up test; ``message`` says where), the critical steps and the step
    used, the probe displacement ``u`` on the grid ``t``, and the energy balance ``energy``
    (``kinetic + strain``) at the times ``energy_t``.
    """
    from springfem.mechanics import explicit

    scene = case_scene(case)
    why = models.get(case["model"]).applies(scene)
    if why is not None:
        return {"status": "not applicable", "message": why[:200]}
    own = own_integrator(case["model"])
    if own is not None:  # its own time integration (a plug-in's release_run)
        nodes, w, _ = probe_weights(scene)
        t_end = float(case["t_end"])
        out = own.release_run(scene, t_end=t_end, safety=case["safety"],
                              samples=case["samples"], probe=(nodes, w))  # fmt: skip
        if "u_steps" in out:
            out["t"], out["u"] = resampled(out.pop("u_steps"), out["dt"], t_end, case["samples"])
        return out
    system = models.get(case["model"]).system(scene)
    try:
        x_load = preload(system)
    except SolverError as exc:
        return {"status": "failed", "message": str(exc)[:200]}
    dt_rest, dt_load = critical_steps(system, x_load)
    dt = case["safety"] * min(dt_rest, dt_load)
    t_end = float(case["t_end"])
    steps = int(np.ceil(t_end / dt))
    nodes, w, _ = probe_weights(scene)
    X = system.x0[nodes]
    U = np.full((steps + 1, 3), np.nan)
    U[0] = w @ (x_load[nodes] - X)

    def record(k: int, t: float, x: np.ndarray, v: np.ndarray) -> None:
        U[k] = w @ (x[nodes] - X)

    out: dict[str, Any] = {"status": "ok", "message": "", "dt_crit_rest": dt_rest,
                           "dt_crit_loaded": dt_load, "dt": dt, "steps": steps}  # fmt: skip
    t0 = time.perf_counter()
    try:
        traj = explicit(system, dt=dt, steps=steps, scale=0.0, x_init=x_load, callback=record,
                        record_every=max(1, steps // int(case["samples"])))  # fmt: skip
    except SolverError as exc:  # the blow-up test: an outcome of the run
        out.update(status="blew up", message=str(exc)[:200])
        traj = None
    out["seconds"] = time.perf_counter() - t0
    out["t"], out["u"] = resampled(U, dt, t_end, case["samples"])
    if traj is not None:
        out["energy_t"] = traj.times.tolist()
        out["energy"] = (traj.kinetic + traj.potential).tolist()
        out["kinetic"] = traj.kinetic.tolist()
    return out


def cost_case(case: dict[str, Any]) -> dict[str, Any]:
    """Median wall time of one explicit step of every model (a plug-in with its own time
    integration: one of its steps, its ``step_timer``), in one process, warm.

    Each model runs from rest under the scene's loads at ``safety`` × its critical step at
    rest; after one untimed warm-up run, ``rounds`` rounds run ``steps`` steps of every
    model in turn, and the time between consecutive steps (the integrator's callback) is
    collected. Returns ``{model: median seconds per step}`` under ``step_seconds``.
    """
    from springfem.mechanics import explicit, stable_time_step

    scene = case_scene(case)
    names = list(case["models"])
    own = {m: own_integrator(m).step_timer(scene, case["safety"]) for m in names
           if own_integrator(m) is not None}  # fmt: skip
    systems = {m: models.get(m).system(scene) for m in names if m not in own}
    dts = {m: case["safety"] * stable_time_step(s)[0] for m, s in systems.items()}
    times: dict[str, list[float]] = {m: [] for m in names}
    n = int(case["steps"])

    def timer(m: str):
        last: list[float] = []

        def tick(k: int, t: float, x: np.ndarray, v: np.ndarray) -> None:
            now = time.perf_counter()
            if last:
                times[m].append(now - last[0])
                last[0] = now
            else:
                last.append(now)

        return tick

    def steps(m: str, k: int, tick=None) -> None:
        if m in own:
            own[m](k, (lambda: tick(0, 0.0, None, None)) if tick else (lambda: None))
        else:
            explicit(systems[m], dt=dts[m], steps=k, record_every=k, callback=tick)

    for m in names:  # warm-up: compiled kernels, caches
        steps(m, min(20, n))
    for _ in range(int(case["rounds"])):
        for m in names:  # no energy records inside the timed steps
            steps(m, n, timer(m))
    return {"step_seconds": {m: float(np.median(v)) for m, v in times.items()}}


#: Kind -> (the work of one case, progress label).
WORK = {
    "period": (period_case, "static preload"),
    "release": (release_case, "release runs"),
    "cost": (cost_case, "cost per step"),
}
