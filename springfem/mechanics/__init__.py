"""Solver machinery both models use: the :class:`MechanicalSystem` protocol, one linear
solver, Newton with line search and adaptive load stepping, explicit integrators, dynamic
relaxation, implicit Euler, the stable time step and a coloured finite-difference Jacobian.

Modules: :mod:`.system` (protocol, rigid-body modes), :mod:`.results` (``Trajectory``,
``SolveInfo``), :mod:`.context` (per-solve view, failure location), :mod:`.linsolve`,
:mod:`.timestep`, :mod:`.blowup`, :mod:`.explicit`, :mod:`.relaxation`, :mod:`.implicit`,
:mod:`.newton`, :mod:`.static`, :mod:`.linear` (the linearised solve), :mod:`.limits`
(time and step caps), :mod:`.modes` (zero-energy modes of a tangent), :mod:`.fd_jacobian`,
:mod:`.toy` (the one-DOF system of the examples).

Examples
--------
The one-DOF spring-mass system of :mod:`.toy` solved statically and stepped explicitly at
its stable step ``2 / omega_max``:

>>> from springfem import mechanics
>>> from springfem.mechanics.toy import Oscillator
>>> system = Oscillator()
>>> dt, omega = mechanics.stable_time_step(system)
>>> float(omega), float(dt)
(2.0, 1.0)
>>> info = mechanics.static(system)
>>> bool(info.converged)
True
"""

from .context import reference_force
from .explicit import Integrator, explicit
from .fd_jacobian import ColoredJacobian, distance2_coloring, fd_jacobian
from .implicit import implicit
from .linear import linear_static
from .linsolve import DIRECT_MAX_DOFS, LinearSolver, LinearSolverKind, solve_linear
from .modes import ZeroModes, spurious_modes, zero_modes
from .relaxation import explicit_static
from .results import SolveInfo, Trajectory
from .static import static
from .system import (
    MechanicalSystem,
    check_constrained,
    constrained_positions,
    free_dofs,
    rigid_body_modes,
)
from .timestep import stable_time_step

__all__ = [
    "DIRECT_MAX_DOFS",
    "ColoredJacobian",
    "Integrator",
    "LinearSolver",
    "LinearSolverKind",
    "MechanicalSystem",
    "SolveInfo",
    "Trajectory",
    "ZeroModes",
    "check_constrained",
    "constrained_positions",
    "distance2_coloring",
    "explicit",
    "explicit_static",
    "fd_jacobian",
    "free_dofs",
    "implicit",
    "linear_static",
    "reference_force",
    "rigid_body_modes",
    "solve_linear",
    "spurious_modes",
    "stable_time_step",
    "static",
    "zero_modes",
]
