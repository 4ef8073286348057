"""Run the solver a scene's ``[spring]`` section asks for.

Examples
--------
>>> from springmodel.options import SpringOptions
>>> SpringOptions().solver in SpringOptions.choices("solver")
True
"""

from __future__ import annotations

import sys
from collections.abc import Callable

import numpy as np

from springfem.mechanics import (
    SolveInfo,
    Trajectory,
    explicit,
    explicit_static,
    implicit,
    linear_static,
    stable_time_step,
    static,
)
from springfem.mechanics.system import MechanicalSystem

from .options import SpringOptions

#: Pseudo-time step of backward-Euler stepping to equilibrium, in critical explicit steps
#: (backward Euler is unconditionally stable; large steps approach Newton on the statics).
PSEUDO_TIME_DT_CRIT = 100.0
#: Pseudo-time steps at most, per allowed Newton iteration (``max_iter``) of the options.
PSEUDO_TIME_STEPS_PER_ITER = 10
#: Newton tolerance of a timed implicit run: at least this tight, whatever ``tol`` says.
IMPLICIT_NEWTON_TOL = 1e-8


def print_newton(iteration: int, load_factor: float, x: np.ndarray, residual: float) -> None:
    """One stderr line per Newton iteration (``springfem solve -v``).

    Parameters
    ----------
    iteration, load_factor, x, residual
        As passed by :func:`~springfem.mechanics.static` to its ``callback``.

    Returns
    -------
    None
        Writes to stderr.
    """
    print(
        f"newton iteration {iteration}: load factor {load_factor:.4g}, "
        f"relative residual {residual:.3e}",
        file=sys.stderr,
        flush=True,
    )


def solve_with_options(
    system: MechanicalSystem,
    options: SpringOptions,
    progress: bool = False,
    callback: Callable[[int, float, np.ndarray, np.ndarray], bool | None] | None = None,
) -> SolveInfo | Trajectory:
    """Run the solver a scene's ``[spring]`` section asks for.

    Parameters
    ----------
    system
        The spring model (any :class:`~springfem.mechanics.MechanicalSystem`).
    options
        The scene's ``[spring]`` options.
    progress
        Show a progress bar (explicit and implicit runs).
    callback
        ``callback(step, t, x, v)`` after every step of a timed run (``steps`` or
        ``t_end`` set), e.g. a :class:`springfem.series.SeriesWriter`; not called by the
        equilibrium solves.

    Returns
    -------
    SolveInfo or Trajectory
        A :class:`~springfem.mechanics.SolveInfo` for the equilibrium solves, a
        :class:`~springfem.mechanics.Trajectory` for timed runs.

    Notes
    -----
    ``static``: :func:`static` with ``tol`` and ``max_iter``. ``linear``:
    :func:`~springfem.mechanics.linear_static`, one tangent solve at rest (the small-strain
    spring model, to compare with linear FEM at the same kinematics). ``explicit``: :func:`explicit`
    when ``steps`` or ``t_end`` is set, else :func:`explicit_static` (to equilibrium, with
    ``mass_damping`` or kinetic damping). ``implicit``: :func:`implicit` when ``steps`` or
    ``t_end`` is set, else backward-Euler pseudo-time stepping (``dt`` or, by default,
    :data:`PSEUDO_TIME_DT_CRIT` ``dt_crit``; at most :data:`PSEUDO_TIME_STEPS_PER_ITER`
    ``max_iter`` steps) until the static residual is below ``tol``. ``dt = None`` otherwise
    means ``dt_safety * dt_crit``.
    """
    o = options
    timed = o.steps is not None or o.t_end is not None
    if o.solver == "linear":
        return linear_static(system)
    if o.solver == "static":
        return static(
            system, tol=o.tol, max_iter=o.max_iter, callback=print_newton if progress else None
        )
    if o.solver == "explicit":
        if timed:
            return explicit(
                system, dt=o.dt, steps=o.steps, t_end=o.t_end, integrator=o.integrator,
                mass_damping=o.mass_damping, progress=progress, dt_safety=o.dt_safety,
                callback=callback,
            )  # fmt: skip
        return explicit_static(
            system, tol=o.tol, dt=o.dt, integrator=o.integrator, mass_damping=o.mass_damping,
            progress=progress, dt_safety=o.dt_safety,
        )  # fmt: skip
    if o.solver == "implicit":
        if timed:
            return implicit(
                system, dt=o.dt, steps=o.steps, t_end=o.t_end, mass_damping=o.mass_damping,
                tol=min(o.tol, IMPLICIT_NEWTON_TOL), progress=progress, dt_safety=o.dt_safety,
                callback=callback,
            )  # fmt: skip
        dt = o.dt if o.dt is not None else PSEUDO_TIME_DT_CRIT * stable_time_step(system)[0]
        return implicit(
            system, dt=dt, steps=o.max_iter * PSEUDO_TIME_STEPS_PER_ITER,
            mass_damping=o.mass_damping, progress=progress, equilibrium_tol=o.tol,
        )  # fmt: skip
    valid = ", ".join(SpringOptions.choices("solver"))
    raise ValueError(f"unknown solver {o.solver!r}; valid: {valid}")
