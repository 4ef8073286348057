"""Run the solver a scene's ``[spring]`` section asks for."""

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


def solve_with_options(
    system: MechanicalSystem, options: SpringOptions, progress: bool = False
) -> SolveInfo | Trajectory:
    """Run the solver a scene's ``[spring]`` section asks for.

    ``static``: :func:`static` with ``tol`` and ``max_iter``. ``explicit``: :func:`explicit`
    when ``steps`` or ``t_end`` is set, else :func:`explicit_static` (to equilibrium, with
    ``mass_damping`` or kinetic damping). ``implicit``: :func:`implicit` when ``steps`` or
    ``t_end`` is set, else backward-Euler pseudo-time stepping (``dt`` or, by default,
    ``100 dt_crit``) until the static residual is below ``tol``. ``dt = None`` otherwise
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
                tol=min(o.tol, 1e-8), progress=progress, dt_safety=o.dt_safety,
            )  # fmt: skip
        dt = o.dt if o.dt is not None else 100.0 * stable_time_step(system)[0]
        return implicit(
            system, dt=dt, steps=o.max_iter * 10, mass_damping=o.mass_damping,
            progress=progress, equilibrium_tol=o.tol,
        )  # fmt: skip
    valid = ", ".join(SpringOptions.choices("solver"))
    raise ValueError(f"unknown solver {o.solver!r}; valid: {valid}")
