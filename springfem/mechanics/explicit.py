"""Explicit time integration: symplectic Euler and velocity Verlet, with the blow-up
monitor of :mod:`springfem.mechanics.blowup`.

Examples
--------

>>> import numpy as np
>>> from springfem.mechanics.toy import Oscillator
>>> traj = explicit(Oscillator(), dt=0.01, steps=400, integrator="verlet")
>>> bool(np.abs(traj.total_energy).max() < 1e-3)  # starts at 0; oscillates by O((omega dt)^2)
True
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from typing import Literal

import numpy as np

from .blowup import BlowupMonitor, blowup_error
from .context import Scale, SolveContext, number_of_steps, scale_function
from .results import Trajectory
from .system import MechanicalSystem
from .timestep import choose_time_step

Integrator = Literal["symplectic-euler", "verlet"]


def explicit_loop(
    ctx: SolveContext,
    *,
    dt: float,
    n_steps: int,
    integrator: Integrator,
    alpha: float,
    scale: Scale,
    x: np.ndarray,
    v: np.ndarray,
    record_every: int,
    callback: Callable | None,
    progress: bool,
    kinetic_damping: bool,
    stop_fn: Callable[[int, float, np.ndarray], tuple[bool, float]] | None,
    check_every: int,
    blowup_factor: float,
    dt_crit: float | None,
) -> tuple[Trajectory, bool]:
    """Integrate ``x``, ``v`` in place (the loop of :func:`explicit`).

    Parameters
    ----------
    ctx
        The solve context.
    dt, n_steps, integrator, alpha, scale, record_every, callback, progress
        As in :func:`explicit` (``alpha`` is the mass damping).
    x, v
        Initial positions and velocities, updated in place.
    kinetic_damping
        Zero the velocities at every kinetic-energy peak (dynamic relaxation).
    stop_fn
        ``stop_fn(step, t, x) -> (stop, residual)``, every ``check_every`` steps.
    check_every
        Steps between calls of ``stop_fn``.
    blowup_factor
        See :class:`~springfem.mechanics.blowup.BlowupMonitor`.
    dt_crit
        Critical time step for the error message (``None``: computed on failure).

    Returns
    -------
    trajectory, stopped
        The :class:`Trajectory` and whether ``callback`` or ``stop_fn`` stopped the run.
    """
    if integrator not in ("symplectic-euler", "verlet"):
        raise ValueError(f"unknown integrator {integrator!r}; valid: 'symplectic-euler', 'verlet'")
    system = ctx.system
    fixed = ctx.fixed
    has_fixed = fixed.size > 0
    inv_m = 1.0 / ctx.m[:, None]
    s_of = scale_function(scale)
    const = not callable(scale)
    xf, vf = x.reshape(-1), v.reshape(-1)
    t0 = 0.0
    s = s_of(t0)
    p_new = system.prescribed(s) if has_fixed else None
    if has_fixed:
        xf[fixed] = p_new
        vf[fixed] = 0.0 if const else (system.prescribed(s_of(t0 + dt)) - p_new) / dt
    verlet = integrator == "verlet"
    decay = np.exp(-alpha * dt * (0.5 if verlet else 1.0)) if alpha else 1.0
    # a = M^-1 f(x_n, v_n), cached: each step needs one force evaluation
    a = ctx.forces(x, v, s) * inv_m
    if has_fixed:
        a.reshape(-1)[fixed] = 0.0

    def kinetic_now() -> float:
        # Symplectic Euler is leapfrog with the stored velocity half a step behind the
        # positions; v + dt/2 a is the velocity at the positions' time (as in Verlet).
        return ctx.kinetic(v if verlet else v + 0.5 * dt * a)

    ke = ctx.kinetic(v)
    monitor = BlowupMonitor(ctx, n_steps, dt, blowup_factor, ke)
    times, kin, pot = [t0], [kinetic_now()], [ctx.potential(x, s)]
    snapshots: deque = deque([x.copy()], maxlen=3)
    x_prev = x.copy()
    residuals: list[float] = []
    kin_last = ke
    restart = False
    stopped = False
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=n_steps, desc=f"explicit {integrator}", unit="step", mininterval=0.5)
    chunk = max(1, n_steps // 200)
    k = 0
    t = t0
    for k in range(1, n_steps + 1):
        ctx.step = k
        t = t0 + k * dt
        if not const:
            s = s_of(t)
        if has_fixed:
            p_old = xf[fixed].copy()
            p_new = system.prescribed(s) if not const else p_new
            v_fixed = (p_new - p_old) / dt
        x_prev[...] = x
        a_prev = a
        if not verlet:
            # symplectic Euler: kick with f(x_n, v_n), then drift; after a kinetic-damping
            # restart from rest the first kick is a half kick (leapfrog start)
            v += (0.5 * dt if restart else dt) * a
            restart = False
            if alpha:
                v *= decay  # exact solution of dv/dt = -alpha v over dt
            if has_fixed:
                vf[fixed] = v_fixed
            x += dt * v
            if has_fixed:
                xf[fixed] = p_new
            a = ctx.forces(x, v, s) * inv_m
            if has_fixed:
                a.reshape(-1)[fixed] = 0.0
        else:
            if alpha:
                v *= decay  # Strang splitting of the mass damping around the Verlet step
            v += 0.5 * dt * a
            if has_fixed:
                vf[fixed] = v_fixed
            x += dt * v
            if has_fixed:
                xf[fixed] = p_new
            a = ctx.forces(x, v, s) * inv_m
            if has_fixed:
                a.reshape(-1)[fixed] = 0.0
            v += 0.5 * dt * a
            if alpha:
                v *= decay
        ke = ctx.kinetic(v)
        reason = monitor.check(k, ke, x, v, s)
        if reason is not None:
            if bar is not None:
                bar.close()
            err = blowup_error(ctx, "explicit", k, t, reason, x_prev, x, dt, dt_crit, snapshots[0])
            raise err
        if kinetic_damping and ke < kin_last:
            # Kinetic damping: the kinetic energy peaked about the previous positions (for
            # symplectic Euler the stored velocity is half a step behind): go back there,
            # stop, and restart from rest.
            x[...] = x_prev
            a = a_prev
            v[...] = 0.0
            if has_fixed:
                vf[fixed] = v_fixed
            restart = True
            ke = ctx.kinetic(v)
        kin_last = ke
        system.post_step(x, dt)
        if k % record_every == 0 or k == n_steps:
            times.append(t)
            kin.append(kinetic_now())
            pot.append(ctx.potential(x, s))
            snapshots.append(x.copy())
        if bar is not None and k % chunk == 0:
            bar.update(chunk)
        if callback is not None and callback(k, t, x, v):
            stopped = True
            break
        if stop_fn is not None and k % check_every == 0:
            done = stop_fn(k, t, x)
            residuals.append(done[1])
            if done[0]:
                stopped = True
                break
    if bar is not None:
        bar.close()
    if stopped and times[-1] != t:
        times.append(t)
        kin.append(kinetic_now())
        pot.append(ctx.potential(x, s))
    traj = Trajectory(
        times=np.asarray(times),
        kinetic=np.asarray(kin),
        potential=np.asarray(pot),
        x=x,
        v=v,
        steps=k,
        dt=dt,
        dt_crit=dt_crit,
        integrator=integrator,
        residual_history=residuals,
    )
    return traj, stopped


def explicit(
    system: MechanicalSystem,
    dt: float | None = None,
    steps: int | None = None,
    t_end: float | None = None,
    integrator: Integrator = "symplectic-euler",
    mass_damping: float = 0.0,
    scale: Scale = 1.0,
    record_every: int | None = None,
    callback: Callable[[int, float, np.ndarray, np.ndarray], bool | None] | None = None,
    progress: bool = False,
    *,
    x_init: np.ndarray | None = None,
    v_init: np.ndarray | None = None,
    dt_safety: float = 0.5,
    blowup_factor: float = 1e4,
) -> Trajectory:
    """Explicit time integration.

    ``symplectic-euler`` (semi-implicit Euler): ``v += dt M^-1 f(x, v); x += dt v``.
    ``verlet`` (velocity Verlet): half kick, drift, force, half kick; velocity-dependent
    forces see the half-step velocity. Mass-proportional damping ``-alpha m v`` is applied
    exactly (``v *= exp(-alpha dt)``, split symmetrically around the Verlet step). The fixed
    DOFs follow ``prescribed(scale(t))``.

    Parameters
    ----------
    system
        The system.
    dt
        Time step; default ``dt_safety * 2 / omega_max`` at the initial state.
    steps, t_end
        Number of steps, or end time (``steps = ceil(t_end / dt)``).
    integrator
        ``symplectic-euler`` or ``verlet``.
    mass_damping
        ``alpha`` (1/s).
    scale
        Load factor, or a function of time (e.g. a ramp).
    record_every
        Record energies every this many steps (default: about 1000 records).
    callback
        ``callback(step, t, x, v)``, called after every step; return ``True`` to stop.
    progress
        Show a tqdm progress bar.
    x_init, v_init
        Initial positions and velocities (default: rest, zero).
    dt_safety
        Fraction of the critical time step used when ``dt`` is ``None``.
    blowup_factor
        A step is a blow-up when its kinetic energy exceeds this factor times the largest
        kinetic energy of the first half of the run so far (a stable run from rest grows
        polynomially, by ``2^p``; an unstable one exponentially) and the velocity field
        oscillates on the unstable time scale (``omega_eff dt >= 1.5``, see
        ``BlowupMonitor``). Non-finite values are always a blow-up.

    Returns
    -------
    Trajectory
        Recorded energies, final state, steps, ``dt`` and ``dt_crit``.

    Raises
    ------
    SolverError
        On blow-up: names the step, time, node and element, ``dt`` against the critical
        step; ``state`` holds the positions recorded before the blow-up.
    """
    t_start = time.perf_counter()
    ctx = SolveContext(system)
    dt, dt_crit = choose_time_step(system, dt, dt_safety, scale)
    n_steps = number_of_steps(dt, steps, t_end)
    x = np.array(ctx.x0 if x_init is None else x_init, dtype=float).reshape(ctx.n, 3)
    v = np.zeros_like(x) if v_init is None else np.array(v_init, dtype=float).reshape(ctx.n, 3)
    record_every = int(record_every) if record_every else max(1, n_steps // 1000)
    traj, _ = explicit_loop(
        ctx,
        dt=dt,
        n_steps=n_steps,
        integrator=integrator,
        alpha=float(mass_damping),
        scale=scale,
        x=x,
        v=v,
        record_every=record_every,
        callback=callback,
        progress=progress,
        kinetic_damping=False,
        stop_fn=None,
        check_every=1,
        blowup_factor=blowup_factor,
        dt_crit=dt_crit,
    )
    traj.wall_time = time.perf_counter() - t_start
    traj.force_evaluations = ctx.n_evals
    return traj
