"""Static equilibrium of a :class:`~springfem.mechanics.system.MechanicalSystem`: the one Newton
with line search and adaptive load stepping, a tangent predictor for moving prescribed
displacements, and dynamic relaxation as the fallback.

Examples
--------

>>> import numpy as np
>>> from springfem.mechanics.toy import Oscillator
>>> info = static(Oscillator(), tol=1e-12)
>>> info.converged, info.iterations, round(float(info.x[3, 0]), 12)
(True, 1, 0.25)
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.sparse as sp

from springfem.errors import SolverError

from .context import JacobianKind, SolveContext, note_solver, reference_norm
from .linsolve import LinearSolver, LinearSolverKind, solve_linear
from .newton import LoadStepping, NewtonSettings, newton
from .relaxation import explicit_static
from .results import SolveInfo
from .system import SINGULAR_MESSAGE, MechanicalSystem, check_constrained, rigid_body_modes

#: Explicit steps the dynamic-relaxation fallback may take after Newton gives up.
FALLBACK_MAX_STEPS = 200_000


class SpringStep:
    """One load step of a system as a :class:`~springfem.mechanics.newton.NewtonProblem`.

    The state is the positions ``(n, 3)`` with the fixed DOFs prescribed; the residual is
    ``-f_free`` (the energy gradient), relative to ``f_ref``.

    Parameters
    ----------
    ctx
        The solve context.
    s
        Load factor.
    f_ref
        Reference force norm.
    jacobian, linear_solver
        Tangent and linear solver kind.
    B
        Rigid-body modes on the free DOFs (near-nullspace of AMG).
    previous
        Holder ``{"solver": ..., "factorization": ...}`` shared by the load steps of one
        solve: the linear solver (its direct solver keeps the symbolic analysis) and the
        last tangent's factorisation, whose AMG hierarchy preconditions the next tangent's
        solves (:meth:`~springfem.mechanics.linsolve.LinearSolver.factorize`, ``reuse``).

    Attributes
    ----------
    K
        The last tangent (``None`` before the first correction).
    """

    def __init__(self, ctx: SolveContext, s, f_ref, jacobian, linear_solver, B, previous=None):
        self.ctx, self.s, self.f_ref = ctx, s, f_ref
        self.jacobian, self.linear_solver, self.B = jacobian, linear_solver, B
        self.previous = {} if previous is None else previous
        self.K = None

    def residual(self, x: np.ndarray) -> tuple[np.ndarray, float]:
        """Residual ``R`` (energy-gradient sign) and its relative norm."""
        R = -self.ctx.free_force(x, self.s)
        return R, float(np.linalg.norm(R)) / self.f_ref

    def correction(self, x: np.ndarray, R: np.ndarray):
        """Newton correction ``d = -K^-1 R`` and the re-solve with the same tangent."""
        self.K = self.ctx.stiffness(x, self.s, self.jacobian)
        # one LinearSolver per solve: its direct solver keeps the symbolic analysis
        ls = self.previous.setdefault("solver", LinearSolver(self.linear_solver, self.B))
        solver = ls.factorize(self.ctx.ff(self.K), reuse=self.previous.get("factorization"))
        d = solver.solve(-R)
        self.previous["factorization"] = solver
        note_solver(self.ctx, solver.name)
        return d, lambda b: -solver.solve(b)

    def trial(self, x: np.ndarray, alpha: float, d: np.ndarray) -> np.ndarray:
        """The state ``+ alpha d``."""
        x_try = x.copy()
        x_try.reshape(-1)[self.ctx.free] += alpha * d
        return x_try

    def energy(self, x: np.ndarray) -> float | None:
        """Potential energy at the load factor, or ``None``."""
        return self.ctx.system.energy(x, self.s)

    def constrained(self, x: np.ndarray) -> bool:
        """Whether the prescribed values are reached."""
        return True  # the fixed DOFs are prescribed before Newton starts

    def locate(self, R: np.ndarray) -> str:
        """Where the largest (or first non-finite) free residual is, for messages."""
        return ""

    def monitor(self, callback: Callable | None, offset: int):
        """The :func:`newton` monitor calling ``callback(iteration, s, x, residual)``."""
        if callback is None:
            return None

        def call(it: int, x: np.ndarray, r: float, alpha: float) -> None:
            if it > 0:
                callback(offset + it, self.s, x, r)

        return call


def static(
    system: MechanicalSystem,
    tol: float = 1e-8,
    max_iter: int = 200,
    load_steps: int = 1,
    scale: float = 1.0,
    *,
    x_init: np.ndarray | None = None,
    jacobian: JacobianKind = "auto",
    linear_solver: LinearSolverKind = "auto",
    max_cutbacks: int = 8,
    fallback: bool = True,
    raise_on_failure: bool = True,
    callback: Callable[[int, float, np.ndarray, float], None] | None = None,
) -> SolveInfo:
    """Static equilibrium ``f_free(x) = 0`` by Newton's method with load stepping.

    Each load step solves ``K dx = f`` on the free DOFs (``K`` analytic if the system has it,
    else coloured finite differences, non-symmetric for non-gradient forces) with
    :func:`solve_linear` and a backtracking line search: Armijo on the energy when the
    system has one and the step descends it, else on the residual norm. A step that does
    not converge in ``max_iter`` iterations is cut in half and retried (up to
    ``max_cutbacks`` times in a row); the increment grows back after easy steps (the rule
    of :class:`~springfem.mechanics.newton.LoadStepping`). When
    prescribed displacements change between load steps, a tangent predictor moves the free
    DOFs with them (``K_ff dx_f = -K_fc dx_c``). If Newton gives up and ``fallback`` is on,
    dynamic relaxation (:func:`explicit_static`, kinetic damping) finishes from the last
    converged state.

    Convergence: ``|f_free| <= tol * reference_force`` (the free-DOF force at the rest
    positions with the fixed DOFs prescribed at the full ``scale``: external loads plus the
    reaction to prescribed displacements).

    Parameters
    ----------
    system
        The system.
    tol
        Relative residual tolerance.
    max_iter
        Newton iterations per load step.
    load_steps
        Initial number of equal load increments up to ``scale``.
    scale
        Final load factor.
    x_init
        Starting positions (default: the rest positions).
    jacobian, linear_solver
        See :func:`stable_time_step` and :func:`solve_linear`.
    max_cutbacks
        Give up after this many halvings of the load increment in a row.
    fallback
        Finish with dynamic relaxation (at most :data:`FALLBACK_MAX_STEPS` steps) when
        Newton gives up.
    raise_on_failure
        Raise :class:`SolverError` when the solve does not converge (else return it with
        ``converged`` false and a ``message``).
    callback
        ``callback(iteration, load_factor, x, relative_residual)`` after every iteration.

    Returns
    -------
    SolveInfo
        Equilibrium positions, iterations, residual history, load steps and cut-backs.

    Raises
    ------
    SolverError
        Rigid-body modes not stopped by the constraints ("singular stiffness: ..."), a
        singular tangent at rest, or no convergence (``raise_on_failure``); ``state`` holds
        the last converged positions.
    """
    t_start = time.perf_counter()
    ctx = SolveContext(system)
    check_constrained(system)
    target = float(scale)
    f_ref = reference_norm(ctx, target)
    B = rigid_body_modes(ctx.x0)[ctx.free]
    x_conv = np.array(ctx.x0 if x_init is None else x_init, dtype=float).reshape(ctx.n, 3)
    hist: list[float] = []
    total_its = 0
    state: dict[str, Any] = {"x": x_conv, "K": None}  # last converged positions and tangent
    method = "newton"
    notes: list[str] = []
    first_attempt = [True]
    path_steps: list[float] = []  # converged load factors
    settings = NewtonSettings(tol=tol, max_iter=max_iter)
    previous: dict = {}  # the last tangent's factorisation (its AMG hierarchy is reused)

    def try_step(lam_conv: float, lam_new: float) -> tuple[bool, int, str]:
        nonlocal total_its
        s_new = lam_new * target
        x = state["x"].copy()
        xf = x.reshape(-1)
        if ctx.fixed.size:
            dp = system.prescribed(s_new) - xf[ctx.fixed]
            xf[ctx.fixed] += dp
            if np.any(dp != 0):
                # tangent predictor: move the free DOFs with the prescribed ones
                try:
                    K = sp.csr_matrix(
                        state["K"]
                        if state["K"] is not None
                        else ctx.stiffness(state["x"], lam_conv * target, jacobian)
                    )
                    rhs = -(K[ctx.free][:, ctx.fixed] @ dp)
                    dxf, name = solve_linear(ctx.ff(K), rhs, linear_solver, B)
                    note_solver(ctx, name)
                    xf[ctx.free] += dxf
                except SolverError:
                    if not path_steps:
                        raise SolverError(
                            f"{SINGULAR_MESSAGE} or the springs leave a mechanism: the "
                            "tangent stiffness at rest is singular",
                            state=state["x"],
                        ) from None
        step = SpringStep(ctx, s_new, f_ref, jacobian, linear_solver, B, previous)
        out = newton(step, x, settings, step.monitor(callback, total_its))
        ok, x, its, h, reason, K_last = (
            out.converged,
            out.state,
            out.iterations,
            out.history,
            out.reason,
            step.K,
        )
        total_its += its
        hist.extend(h)
        first, first_attempt[0] = first_attempt[0], False
        if ok:
            if reason:
                notes.append(f"load factor {s_new:.4g}: {reason}")
            state["x"], state["K"] = x, K_last
            path_steps.append(s_new)
            return True, its, ""
        if reason.startswith("singular tangent at iteration 1 ") and first:
            raise SolverError(
                f"{SINGULAR_MESSAGE} or the springs leave a mechanism: {reason}",
                state=state["x"],
            )
        return False, its, reason

    path = LoadStepping(load_steps, max_cutbacks).run(try_step)
    x_conv, steps_done, cutbacks = state["x"], path_steps, path.cutbacks
    lam_conv, last_reason = path.load, path.reason
    converged = path.converged
    s_conv = lam_conv * target
    x_final = x_conv
    steps = 0
    dt = None
    message = "; ".join(notes)
    if not converged:
        newton_message = stopped_message(
            s_conv, target, path.failed_at * target, cutbacks, last_reason
        )
        message = f"{message + '; ' if message else ''}{newton_message}"
        if fallback:
            try:
                dr = explicit_static(
                    system, tol=tol, max_steps=FALLBACK_MAX_STEPS, scale=target, x_init=x_conv,
                    raise_on_failure=False,
                )  # fmt: skip
            except SolverError as err:
                dr = None  # its first clause only: the Newton stop is the message
                message += f"; dynamic relaxation from there blew up ({first_clause(err)})"
            if dr is not None:
                ctx.n_evals += dr.force_evaluations
                hist.extend(dr.residual_history)
                steps, dt = dr.steps, dr.dt
                method = "newton+dynamic-relaxation"
                if dr.converged:
                    converged, x_final = True, dr.x
                    steps_done.append(target)
                    message += f"; dynamic relaxation converged in {dr.steps} steps"
                else:
                    message += f"; dynamic relaxation from there: {first_clause(dr.message)}"
        if not converged and raise_on_failure:
            raise SolverError(
                f"static solve did not converge: {message}", state=x_conv, load_factor=s_conv
            )
    return SolveInfo(
        x=x_final,
        converged=converged,
        iterations=total_its,
        residual_history=hist,
        load_steps=steps_done,
        method=method,
        jacobian=ctx.jacobian_kind,
        linear_solver=",".join(ctx.solvers_used) or "none",
        wall_time=time.perf_counter() - t_start,
        reference_force=f_ref,
        cutbacks=cutbacks,
        steps=steps,
        dt=dt,
        force_evaluations=ctx.n_evals,
        message=message,
    )


def stopped_message(reached: float, target: float, failed: float, cutbacks: int, why: str) -> str:
    """``stopped at load factor R of T (Newton at F: why, after N cut-backs)``.

    Parameters
    ----------
    reached, target
        The last converged load factor and the one asked for.
    failed
        The load factor whose Newton solve failed last.
    cutbacks
        Halvings of the load increment in a row before giving up.
    why
        Newton's reason.

    Returns
    -------
    str

    Examples
    --------
    >>> stopped_message(0.5, 1.0, 0.5039, 9, "line search failed at iteration 5")
    'stopped at load factor 0.5 of 1 (Newton at 0.5039: line search failed at iteration 5, after 9 cut-backs)'
    """  # noqa: E501 - the doctest's output is one line
    return (
        f"stopped at load factor {reached:.4g} of {target:.4g} (Newton at {failed:.4g}: "
        f"{why}, after {cutbacks} cut-backs)"
    )


def first_clause(err: object) -> str:
    """The text of ``err`` up to its first ``": "`` (where a long explanation starts).

    Parameters
    ----------
    err
        An exception or a message.

    Returns
    -------
    str

    Examples
    --------
    >>> first_clause("explicit integration blew up at step 20 (t = 63 s): kinetic energy grew")
    'explicit integration blew up at step 20 (t = 63 s)'
    """
    return str(err).split(": ", 1)[0]
