"""Implicit (backward) Euler time integration, with step halving on a failed Newton solve.

Examples
--------
Stable far beyond the critical step (``dt_crit = 1`` here):

>>> import numpy as np
>>> from springfem.mechanics.toy import Oscillator
>>> traj = implicit(Oscillator(), dt=10.0, steps=20)
>>> round(float(traj.x[3, 0]), 3)  # damped towards the equilibrium 0.25
0.25
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable

import numpy as np
import scipy.sparse as sp

from springfem.errors import SolverError

from .blowup import blowup_error
from .context import (
    JacobianKind,
    Scale,
    SolveContext,
    note_solver,
    number_of_steps,
    reference_norm,
    scale_function,
)
from .fd_jacobian import characteristic_length
from .linsolve import LinearSolver, LinearSolverKind
from .results import Trajectory
from .system import MechanicalSystem, rigid_body_modes
from .timestep import choose_time_step


def implicit(
    system: MechanicalSystem,
    dt: float | None = None,
    steps: int | None = None,
    t_end: float | None = None,
    mass_damping: float = 0.0,
    scale: Scale = 1.0,
    tol: float = 1e-8,
    max_iter: int = 25,
    record_every: int | None = None,
    callback: Callable[[int, float, np.ndarray, np.ndarray], bool | None] | None = None,
    progress: bool = False,
    *,
    x_init: np.ndarray | None = None,
    v_init: np.ndarray | None = None,
    dt_safety: float = 0.5,
    jacobian: JacobianKind = "auto",
    linear_solver: LinearSolverKind = "auto",
    equilibrium_tol: float | None = None,
    max_substeps: int = 4,
) -> Trajectory:
    """Implicit (backward) Euler.

    Each step solves ``M (v1 - v0) / dt = f(x0 + dt v1, v1) - alpha M v1`` for ``v1`` by
    Newton with the Jacobian ``M (1 + alpha dt) + dt C + dt^2 K`` (``K`` analytic when the
    system has it, else coloured finite differences; ``C = -df/dv`` by finite differences
    when the forces depend on ``v``). Unconditionally stable for linear systems, first order
    and dissipative. A step whose Newton iteration fails is split in halves (up to
    ``max_substeps`` times).

    Parameters
    ----------
    tol
        Newton tolerance on ``|residual| / (|M v0| + dt |f(x0, v0)| + dt reference_force)``.
    equilibrium_tol
        If given, stop early when the static residual ``|f_free(x)| / reference_force``
        falls below it (pseudo-time stepping to equilibrium).

    Other parameters are as in :func:`~springfem.mechanics.explicit.explicit`
    (``jacobian`` and ``linear_solver`` as in :func:`~springfem.mechanics.static.static`;
    ``max_iter`` Newton iterations per step; ``max_substeps`` halvings of a failed step).

    Returns
    -------
    Trajectory
        Energies, final state, total Newton iterations, the final relative Newton residual
        of every step; ``converged`` false when ``equilibrium_tol`` was not reached.

    Raises
    ------
    SolverError
        When a step fails after ``max_substeps`` halvings (names step, time, node, element).
    """
    t_start = time.perf_counter()
    ctx = SolveContext(system)
    dt, dt_crit = choose_time_step(system, dt, dt_safety, scale)
    n_steps = number_of_steps(dt, steps, t_end)
    s_of = scale_function(scale)
    alpha = float(mass_damping)
    fixed = ctx.fixed
    x = np.array(ctx.x0 if x_init is None else x_init, dtype=float).reshape(ctx.n, 3)
    v = np.zeros_like(x) if v_init is None else np.array(v_init, dtype=float).reshape(ctx.n, 3)
    s = s_of(0.0)
    if fixed.size:
        x.reshape(-1)[fixed] = system.prescribed(s)
        v.reshape(-1)[fixed] = 0.0
    f_ref = reference_norm(ctx, s_of(n_steps * dt))
    length = characteristic_length(ctx.x0, ctx.tets)
    damped = ctx.has_damping(x, s, length / dt)
    record_every = int(record_every) if record_every else max(1, n_steps // 1000)
    times, kin, pot = [0.0], [ctx.kinetic(v)], [ctx.potential(x, s)]
    hist: list[float] = []
    total_iters = 0
    snapshots: deque = deque([x.copy()], maxlen=3)

    def step(x0: np.ndarray, v0: np.ndarray, t0: float, h: float, depth: int):
        """One backward-Euler step of size h, split on failure; returns x1, v1, its, r."""
        x1, v1, its, r, ok = _backward_euler_step(
            ctx, x0, v0, h, s_of(t0 + h), alpha, tol, max_iter, damped, length,
            f_ref, jacobian, linear_solver,
        )  # fmt: skip
        if ok or depth >= max_substeps:
            return x1, v1, its, r, ok
        xa, va, ia, _, oka = step(x0, v0, t0, 0.5 * h, depth + 1)
        if not oka:
            return xa, va, its + ia, r, False
        xb, vb, ib, rb, okb = step(xa, va, t0 + 0.5 * h, 0.5 * h, depth + 1)
        return xb, vb, its + ia + ib, rb, okb

    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=n_steps, desc="implicit Euler", unit="step", mininterval=0.5)
    k, t = 0, 0.0
    converged = True
    message = ""
    for k in range(1, n_steps + 1):
        ctx.step = k
        t0, t = t, k * dt
        x_new, v_new, its, r, ok = step(x, v, t0, dt, 0)
        total_iters += its
        hist.append(r)
        if not ok:
            if bar is not None:
                bar.close()
            finite = np.isfinite(x_new).all() and np.isfinite(v_new).all()
            reason = (
                f"Newton did not converge (relative residual {r:.3g} after {max_iter} "
                f"iterations, {max_substeps} step halvings)"
                if finite
                else "non-finite state"
            )
            raise blowup_error(ctx, "implicit", k, t, reason, x, x_new, dt, dt_crit, snapshots[0])
        x, v = x_new, v_new
        s = s_of(t)
        system.post_step(x, dt)
        if k % record_every == 0 or k == n_steps:
            times.append(t)
            kin.append(ctx.kinetic(v))
            pot.append(ctx.potential(x, s))
            snapshots.append(x.copy())
        if bar is not None:
            bar.update(1)
        if callback is not None and callback(k, t, x, v):
            break
        if equilibrium_tol is not None:
            r_static = float(np.linalg.norm(ctx.free_force(x, s))) / f_ref
            if r_static <= equilibrium_tol:
                message = f"equilibrium reached at step {k}: relative residual {r_static:.3g}"
                break
    if bar is not None:
        bar.close()
    if times[-1] != t:
        times.append(t)
        kin.append(ctx.kinetic(v))
        pot.append(ctx.potential(x, s))
    if equilibrium_tol is not None and not message:
        converged = False
        message = f"equilibrium not reached in {k} steps"
    return Trajectory(
        times=np.asarray(times),
        kinetic=np.asarray(kin),
        potential=np.asarray(pot),
        x=x,
        v=v,
        steps=k,
        dt=dt,
        dt_crit=dt_crit,
        integrator="backward-euler",
        converged=converged,
        wall_time=time.perf_counter() - t_start,
        iterations=total_iters,
        residual_history=hist,
        force_evaluations=ctx.n_evals,
        message=message,
    )


def _backward_euler_step(
    ctx: SolveContext,
    x0: np.ndarray,
    v0: np.ndarray,
    dt: float,
    s: float,
    alpha: float,
    tol: float,
    max_iter: int,
    damped: bool,
    length: float,
    f_ref: float,
    jacobian: JacobianKind,
    linear_solver: LinearSolverKind,
):
    system = ctx.system
    fixed, free = ctx.fixed, ctx.free
    Mf = ctx.m_dof[free]
    x1, v1 = x0.copy(), v0.copy()
    x1f, v1f, x0f, v0f = x1.reshape(-1), v1.reshape(-1), x0.reshape(-1), v0.reshape(-1)
    if fixed.size:
        p = system.prescribed(s)
        v1f[fixed] = (p - x0f[fixed]) / dt
        x1f[fixed] = p
    x1f[free] = x0f[free] + dt * v1f[free]

    def residual() -> np.ndarray:
        f = ctx.forces(x1, v1, s).reshape(-1)[free]
        return Mf * ((1.0 + dt * alpha) * v1f[free] - v0f[free]) - dt * f

    g = residual()
    f0 = ctx.forces(x0, v0, s).reshape(-1)[free]
    g_ref = float(np.linalg.norm(Mf * v0f[free]) + dt * np.linalg.norm(f0) + dt * f_ref)
    g_ref = g_ref if g_ref > 0 else 1.0
    r = float(np.linalg.norm(g)) / g_ref
    solver = None
    analytic = True
    ratio = 1.0
    its = 0
    B = rigid_body_modes(ctx.x0)[free]
    for its in range(1, max_iter + 1):  # noqa: B007 - its is reported
        if not np.isfinite(r):
            return x1, v1, its, r, False
        if r <= tol:
            return x1, v1, its - 1, r, True
        # Full Newton with an analytic tangent; with finite differences the factorised
        # Jacobian is reused while it contracts well (r drops at least twofold).
        if solver is None or analytic or ratio > 0.5:
            K = ctx.stiffness(x1, s, jacobian)
            analytic = ctx.jacobian_kind == "analytic"
            J = sp.diags(Mf * (1.0 + dt * alpha)) + dt * dt * ctx.ff(K)
            if damped:
                J = J + dt * ctx.ff(ctx.damping_matrix(x1, s, length / dt))
            solver = LinearSolver(linear_solver, B).factorize(J)
        try:
            dv = solver.solve(-g)
        except SolverError:
            return x1, v1, its, r, False
        note_solver(ctx, solver.name)
        v1f[free] += dv
        x1f[free] = x0f[free] + dt * v1f[free]
        g_new = residual()
        r_new = float(np.linalg.norm(g_new)) / g_ref
        ratio = r_new / r if r > 0 else 0.0
        g, r = g_new, r_new
    return x1, v1, max_iter, r, bool(np.isfinite(r) and r <= tol)
