"""Run the solver a scene's ``[spring]`` section asks for.

Examples
--------
>>> from springmodel.options import SpringOptions
>>> SpringOptions().solver in SpringOptions.choices("solver")
True
"""

from __future__ import annotations

from springfem.mechanics import (
    SolveInfo,
    Trajectory,
    explicit,
    explicit_static,
    implicit,
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


def solve_with_options(
    system: MechanicalSystem, options: SpringOptions, progress: bool = False
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

    Returns
    -------
    SolveInfo or Trajectory
        A :class:`~springfem.mechanics.SolveInfo` for the equilibrium solves, a
        :class:`~springfem.mechanics.Trajectory` for timed runs.

    Notes
    -----
    ``static``: :func:`static` with ``tol`` and ``max_iter``. ``explicit``: :func:`explicit`
    when ``steps`` or ``t_end`` is set, else :func:`explicit_static` (to equilibrium, with
    ``mass_damping`` or kinetic damping). ``implicit``: :func:`implicit` when ``steps`` or
    ``t_end`` is set, else backward-Euler pseudo-time stepping (``dt`` or, by default,
    :data:`PSEUDO_TIME_DT_CRIT` ``dt_crit``; at most :data:`PSEUDO_TIME_STEPS_PER_ITER`
    ``max_iter`` steps) until the static residual is below ``tol``. ``dt = None`` otherwise
    means ``dt_safety * dt_crit``.
    """
    o = options
    timed = o.steps is not None or o.t_end is not None
    if o.solver == "static":
        return static(system, tol=o.tol, max_iter=o.max_iter)
    if o.solver == "explicit":
        if timed:
            return explicit(
                system, dt=o.dt, steps=o.steps, t_end=o.t_end, integrator=o.integrator,
                mass_damping=o.mass_damping, progress=progress, dt_safety=o.dt_safety,
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
            )  # fmt: skip
        dt = o.dt if o.dt is not None else PSEUDO_TIME_DT_CRIT * stable_time_step(system)[0]
        return implicit(
            system, dt=dt, steps=o.max_iter * PSEUDO_TIME_STEPS_PER_ITER,
            mass_damping=o.mass_damping, progress=progress, equilibrium_tol=o.tol,
        )  # fmt: skip
    valid = ", ".join(SpringOptions.choices("solver"))
    raise ValueError(f"unknown solver {o.solver!r}; valid: {valid}")
