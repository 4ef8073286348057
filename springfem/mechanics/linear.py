"""The linearised static solve: one tangent solve at rest, ``K(x0) du = f(x0)``.

Small-strain FEM solves ``K u = f`` with the stiffness of the rest configuration and the
loads applied on the reference configuration; this is
the same for any :class:`~springfem.mechanics.system.MechanicalSystem`, so a nonlinear model
can be compared with a linear reference *at the same kinematics*: for the spring model this
is the small-strain spring element, which docs/theory.rst#the-effective-small-strain-matrix-d-k
shows to be a P1 element with each
element's effective matrix ``D_k``. Any difference from linear P1 FEM on the same mesh is
then model error alone, with no geometric nonlinearity mixed in.

``K`` is the tangent of the internal forces alone (the system's tangent at load factor 0,
where its external forces vanish): a follower load such as a pressure is taken on the
reference surface, so its dependence on the deformed surface (the load stiffness) has no
place in a linear analysis, as in linear FEM.

Examples
--------
>>> from springfem.mechanics.toy import Oscillator
>>> info = linear_static(Oscillator())
>>> info.method, info.iterations, round(float(info.x[3, 0]), 12)
('linear', 1, 0.25)
"""

from __future__ import annotations

import time

import numpy as np

from .context import JacobianKind, SolveContext, note_solver, reference_norm
from .linsolve import LinearSolver, LinearSolverKind
from .results import SolveInfo
from .system import MechanicalSystem, check_constrained, rigid_body_modes


def linear_static(
    system: MechanicalSystem,
    jacobian: JacobianKind = "auto",
    linear_solver: LinearSolverKind = "auto",
) -> SolveInfo:
    """Solve the system linearised at rest: ``K(x0) du = f(x0)`` with prescribed ``du``.

    ``K`` is the stiffness of the internal forces (``system.stiffness(x0, 0)``: no load
    stiffness of follower loads), ``f`` the loads on the reference configuration.

    Parameters
    ----------
    system
        The system (its forces at rest are the external loads; internal forces vanish).
    jacobian
        ``auto`` (analytic stiffness when the system has one, else coloured finite
        differences), ``analytic`` or ``fd``.
    linear_solver
        ``auto``, ``direct`` or ``amg`` (see :class:`~springfem.mechanics.linsolve.LinearSolver`).

    Returns
    -------
    SolveInfo
        ``method = "linear"``, one iteration; ``converged`` is true when the linear solve
        succeeded. ``residual_history`` holds the *nonlinear* relative residual at the
        linear solution: how far the model is from equilibrium there (geometric
        nonlinearity), not a solver error.

    Raises
    ------
    SolverError
        Singular tangent (a mechanism or a missing boundary condition).
    """
    t0 = time.perf_counter()
    ctx = SolveContext(system)
    check_constrained(system)
    x0 = ctx.x0
    K = ctx.stiffness(x0, 0.0, jacobian)  # internal forces only: loads on the reference
    f = ctx.forces(x0, None, 1.0).reshape(-1)
    du = np.zeros(3 * ctx.n)
    du[ctx.fixed] = np.asarray(system.prescribed(1.0), dtype=float) - x0.reshape(-1)[ctx.fixed]
    rhs = (f - K @ du)[ctx.free]
    solver = LinearSolver(linear_solver, rigid_body_modes(x0)[ctx.free])
    du[ctx.free] = solver.solve(ctx.ff(K), rhs, where="linearised solve: ")
    note_solver(ctx, solver.name)
    x = x0 + du.reshape(-1, 3)
    f_ref = reference_norm(ctx, 1.0)
    r = float(np.linalg.norm(ctx.free_force(x, 1.0))) / f_ref if f_ref > 0 else 0.0
    return SolveInfo(
        x=x,
        converged=True,
        iterations=1,
        residual_history=[r],
        load_steps=[1.0],
        method="linear",
        jacobian=ctx.jacobian_kind,
        linear_solver=",".join(ctx.solvers_used),
        wall_time=time.perf_counter() - t0,
        reference_force=f_ref,
        force_evaluations=ctx.n_evals,
        message="linearised at rest (small strain): the residual is the nonlinear one",
    )
