"""The FEM's adapter to the one Newton (:func:`springfem.mechanics.newton.newton`):
:class:`FemStep` (displacement form, the prescribed values reached by the update), a secant
predictor, and the shared load-stepping rule :class:`springfem.mechanics.newton.LoadStepping`.

The load factor ``lambda`` scales every load and every prescribed displacement. A load step
that fails (too many iterations, a growing or non-finite residual, an inverted element, a
failed linear solve) is retried with a smaller increment (the shared rule); when it gives
up, the solve stops with :class:`~springfem.errors.SolverError` whose ``state`` is the last
converged vertex displacement and ``load_factor`` its load factor. A ``--max-time`` cap or
Ctrl-C stops it with :class:`~springfem.mechanics.limits.SolveStopped` carrying the same two
fields, wherever the solve is (:mod:`springfem.mechanics.limits`).

Each tangent is factorised once (:meth:`~springfem.mechanics.linsolve.LinearSolver.factorize`,
the symbolic analysis kept across iterations and load steps) and reused by the line
search's re-solves. The wall time per phase (``assembly`` of residual and tangent,
``factorization``, ``solve``, ``line search``, ``predictor``) is in
:attr:`NewtonReport.phases`; ``progress`` receives every iteration (load step, load,
iteration, residual, step length).

Convergence: ``|R_free| <= tol * max(|f_int|, |f_ext|)`` with the prescribed values reached.

An iterative linear solve is inexact Newton (Eisenstat & Walker 1996, SIAM J. Sci. Comput.
17, choice 2): its relative residual may be the forcing term ``eta_k = 0.9 (r_k /
r_{k-1})^2``, at most :data:`ETA_MAX`, at least ``0.9 eta_{k-1}^2`` when that is above
0.1, and at least :data:`ETA_FLOOR` times ``tol / r_k`` (no solve more accurate than the
last step needs). A factorisation ignores it.

Examples
--------
Inverted elements reject a state: a trial is backtracked, a start fails the load step.

>>> import numpy as np
>>> from springfem.mechanics.newton import RejectedState
>>> err = InvertedElements(np.array([3, 7]), "(first at x = [0.1, 0.0, 0.0])")
>>> isinstance(err, RejectedState), str(err)
(True, '2 inverted element(s) (J <= 0): [3, 7] (first at x = [0.1, 0.0, 0.0])')
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from springfem.errors import SolverError
from springfem.mechanics.limits import Deadline, SolveStopped, checkpoint
from springfem.mechanics.linsolve import Factorization, LinearSolver
from springfem.mechanics.newton import (
    LoadStepping,
    NewtonOutcome,
    NewtonSettings,
    RejectedState,
    newton,
)
from springfem.mechanics.phases import PhaseTimes

#: The largest forcing term (:func:`forcing_term`).
ETA_MAX = 0.1
#: The forcing term is at least this times ``tol / r``.
ETA_FLOOR = 0.2


def forcing_term(r: float, r_prev: float | None, eta_prev: float | None, tol: float) -> float:
    """The relative tolerance of an iterative Newton correction (module docstring).

    Parameters
    ----------
    r, r_prev
        Relative residual now and at the previous correction (``None``: none yet).
    eta_prev
        The previous forcing term (``None``: none yet).
    tol
        Newton's tolerance.

    Returns
    -------
    float
        ``eta`` in ``(0, ETA_MAX]``.

    Examples
    --------
    >>> forcing_term(1e-2, None, None, 1e-10)
    0.1
    >>> round(forcing_term(1e-4, 1e-2, 0.1, 1e-10), 8)  # 0.9 * (1e-2)^2
    9e-05
    >>> forcing_term(1e-9, 1e-5, 1e-3, 1e-10)  # the floor: 0.2 tol / r
    0.02
    """
    if r_prev is None or eta_prev is None or r_prev <= 0:
        eta = ETA_MAX
    else:
        eta = 0.9 * (r / r_prev) ** 2
        if 0.9 * eta_prev**2 > 0.1:
            eta = max(eta, 0.9 * eta_prev**2)
    eta = max(eta, ETA_FLOOR * tol / max(r, 1e-300))
    return float(min(ETA_MAX, eta))


class InvertedElements(RejectedState):
    """Raised by a problem's residual when elements have ``J <= 0``.

    Parameters
    ----------
    elements
        Indices of the inverted elements (kept as :attr:`elements`).
    where
        Context appended to the message.
    """

    def __init__(self, elements: np.ndarray, where: str = ""):
        msg = f"{len(elements)} inverted element(s) (J <= 0): {elements[:5].tolist()}"
        super().__init__(msg + (f" {where}" if where else ""))
        self.elements = elements


class NonlinearProblem(Protocol):
    """What the FEM's Newton needs of a discrete problem (a ``FemProblem``).

    Attributes
    ----------
    n_dofs, free, fixed_dofs, fixed_values
        DOF count, boolean mask of the free DOFs, the prescribed DOFs and their values at
        load factor 1.
    """

    @property
    def n_dofs(self) -> int: ...

    @property
    def free(self) -> np.ndarray: ...

    @property
    def fixed_dofs(self) -> np.ndarray: ...

    @property
    def fixed_values(self) -> np.ndarray: ...

    def residual(self, u: np.ndarray, scale: float) -> tuple[np.ndarray, float]: ...

    def energy(self, u: np.ndarray, scale: float) -> float | None: ...

    def residual_tangent(self, u: np.ndarray, scale: float): ...

    def solve_linear(self, K, b: np.ndarray, symmetric: bool, where: str) -> np.ndarray: ...

    linear_solver: LinearSolver  # ``factorize(K, free, symmetric)``

    def state(self, u: np.ndarray) -> np.ndarray: ...


@dataclass
class NewtonOptions:
    """Settings of :func:`solve_nonlinear`.

    Parameters
    ----------
    tol
        Relative residual tolerance ``|R_free| / max(|f_int|, |f_ext|)``.
    max_iter
        Newton iterations per load step.
    load_steps
        Nominal number of load increments.
    max_cutbacks
        Increment halvings in a row before giving up (see ``LoadStepping``).
    max_backtracks
        Line-search halvings of a Newton step.
    verbose
        Print the residual history and, at the end, the phase table to stderr.
    on_step
        Called as ``on_step(load, u)`` with each converged load step, in order (e.g. to
        record a pressure-volume curve).
    progress
        Called as ``progress(event)`` at the start of each Newton iteration and after each
        accepted step: ``event`` has ``step`` (load step, from 1), ``load``,
        ``iteration``, ``residual`` (relative) and ``alpha`` (line-search step length, 0 at
        the start).
    reuse
        Modified Newton (:class:`~springfem.mechanics.newton.NewtonSettings`): reuse the
        last tangent's factorisation while each iteration lowers the residual to at most
        this fraction of the previous one (0: a fresh tangent every iteration).
    """

    tol: float = 1e-10
    max_iter: int = 25
    load_steps: int = 1
    max_cutbacks: int = 8
    max_backtracks: int = 8
    verbose: bool = False
    on_step: Callable[[float, np.ndarray], None] | None = None
    progress: Callable[[dict], None] | None = None
    reuse: float = 0.0


@dataclass
class NewtonReport:
    """Outcome of :func:`solve_nonlinear`.

    Attributes
    ----------
    converged
        The full load was reached.
    iterations
        Newton iterations of the accepted steps.
    steps
        Per accepted step: ``load``, ``iterations`` and relative ``residuals``.
    cutbacks
        Failed steps (each halved the increment).
    phases
        Wall seconds per phase (:class:`~springfem.mechanics.phases.PhaseTimes`).
    """

    converged: bool = False
    iterations: int = 0
    steps: list[dict] = field(default_factory=list)
    cutbacks: int = 0
    phases: PhaseTimes = field(default_factory=PhaseTimes)


def _log(opts: NewtonOptions, msg: str) -> None:
    if opts.verbose:
        print(msg, file=sys.stderr, flush=True)


class FemStep:
    """One load step of a :class:`NonlinearProblem` as a
    :class:`~springfem.mechanics.newton.NewtonProblem` (displacement form: the state is the
    full DOF vector, the prescribed values are reached by the first full update).

    Parameters
    ----------
    problem
        The discrete problem.
    scale
        Load factor ``lambda`` (of the loads and the prescribed values).
    phases
        Where the wall time of the phases goes (``None``: a new one).
    kept
        Holder of the last tangent ``K`` and its ``factor``, shared by the load steps of a
        solve, for :meth:`reused_correction` (modified Newton).
    tol
        Newton's tolerance (for the forcing term of an iterative solve).
    """

    def __init__(
        self,
        problem: NonlinearProblem,
        scale: float,
        phases: PhaseTimes | None = None,
        kept: dict | None = None,
        tol: float = 1e-10,
    ):
        self.problem, self.scale = problem, scale
        self.target = scale * problem.fixed_values
        self.free_ids = np.flatnonzero(problem.free)
        self.phases = PhaseTimes() if phases is None else phases
        self.phase = "line search"  # the phase of the next residual evaluation
        self.kept = {} if kept is None else kept  # the last tangent and its factorisation
        self.tol = tol
        self.r = np.inf  # the last relative residual evaluated
        self._eta: tuple[float, float] | None = None  # (r, eta) at the last correction

    def residual(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """Residual ``R`` (energy-gradient sign) and its relative norm."""
        checkpoint()
        with self.phases(self.phase):
            R, ref = self.problem.residual(u, self.scale)
        self.r = float(np.linalg.norm(R[self.problem.free]) / max(ref, 1e-300))
        return R, self.r

    def correction(self, u: np.ndarray, R: np.ndarray):
        """Newton correction ``d = -K^-1 R`` and the re-solve with the same tangent."""
        p, times = self.problem, self.phases
        checkpoint()
        last = self.kept.pop("factor", None)
        self.kept.pop("K", None)  # the last tangent is not used again: free it first
        if isinstance(last, Factorization):
            last.shed()  # its AMG hierarchy may precondition the new tangent
        else:
            last = None
        with times("assembly"):
            _, K, symmetric, _ = p.residual_tangent(u, self.scale)
        checkpoint()
        with times("factorization"):
            factor = p.linear_solver.factorize(K, p.free, symmetric, reuse=last)
        self.kept.update(K=K, factor=factor)
        return self._solve(u, R, K, factor)

    def reused_correction(self, u: np.ndarray, R: np.ndarray):
        """The correction with the last tangent's factorisation (modified Newton), or
        ``None`` when there is none."""
        if self.kept.get("factor") is None:
            return None
        return self._solve(u, R, self.kept["K"], self.kept["factor"])

    def _solve(self, u: np.ndarray, R: np.ndarray, K, factor):
        times, p = self.phases, self.problem
        du = np.zeros_like(u)
        du[p.fixed_dofs] = self.target - u[p.fixed_dofs]
        b = -R - (K @ du if not self.constrained(u) else 0.0)
        r_prev, eta_prev = self._eta if self._eta is not None else (None, None)
        eta = forcing_term(self.r, r_prev, eta_prev, self.tol)
        self._eta = (self.r, eta)
        inexact = isinstance(factor, Factorization)  # else a wrapper's own solve(b)
        with times("solve"):
            du += factor.solve(b, eta) if inexact else factor.solve(b)

        def resolve(rhs: np.ndarray) -> np.ndarray:
            with times("line search"):
                return -(factor.solve(rhs, eta) if inexact else factor.solve(rhs))

        return du, resolve

    def trial(self, u: np.ndarray, alpha: float, du: np.ndarray) -> np.ndarray:
        """The state ``+ alpha d``."""
        t = u + alpha * du
        if alpha == 1.0:
            t[self.problem.fixed_dofs] = self.target
        return t

    def energy(self, u: np.ndarray) -> float | None:
        """Potential energy at the load factor, or ``None``."""
        return self.problem.energy(u, self.scale)

    def constrained(self, u: np.ndarray) -> bool:
        """Whether the prescribed values are reached."""
        return bool(np.abs(u[self.problem.fixed_dofs] - self.target).max(initial=0.0) == 0.0)

    def locate(self, R: np.ndarray) -> str:
        """Where the largest (or first non-finite) free residual is, for messages."""
        Rf = R[self.free_ids]
        bad = np.flatnonzero(~np.isfinite(Rf))
        if bad.size:
            return f" at FE node {int(self.free_ids[bad[0]]) // 3}"
        if not Rf.size:
            return ""
        worst = int(self.free_ids[np.argmax(np.abs(Rf))])
        return f"; largest residual at FE node {worst // 3}, component {'xyz'[worst % 3]}"


def newton_step(
    problem: NonlinearProblem,
    u: np.ndarray,
    scale: float,
    opts: NewtonOptions,
    label: str,
    deadline: Deadline | None = None,
    last_good: np.ndarray | None = None,
    phases: PhaseTimes | None = None,
    step: int = 0,
    kept: dict | None = None,
) -> NewtonOutcome:
    """Iterate to equilibrium at load factor ``scale`` from ``u`` with the one Newton.

    Parameters
    ----------
    problem
        The discrete problem.
    u
        Start DOF vector.
    scale
        Load factor.
    opts
        Settings.
    label
        Prefix of the progress lines.
    deadline
        The solve's ``--max-time`` cap (checked once per iteration), if any.
    last_good
        The last converged vertex displacements, handed over when the cap stops the solve.
    phases
        Where the wall time of the phases goes.
    step
        Number of the load step (for ``opts.progress``).
    kept
        The tangent holder of :class:`FemStep` (shared by the load steps).

    Returns
    -------
    NewtonOutcome
        See :func:`springfem.mechanics.newton.newton`.

    Raises
    ------
    SolveStopped
        The ``deadline`` passed.
    """

    def monitor(it: int, state: np.ndarray, rel: float, alpha: float) -> None:
        if deadline is not None:
            deadline.check(f"{label}, iteration {it}", rel, last_good)
        if opts.progress is not None:
            event = {"step": step, "load": scale, "iteration": it, "residual": rel}
            opts.progress({**event, "alpha": alpha})
        if 0 < alpha < 1.0:
            _log(opts, f"  {label} line search alpha = {alpha:g}")
        _log(opts, f"  {label} iteration {it:2d}  |R|/|f| = {rel:.3e}")

    settings = NewtonSettings(opts.tol, opts.max_iter, opts.max_backtracks, opts.reuse)
    step_problem = FemStep(problem, scale, phases, kept, opts.tol)
    return newton(step_problem, u.copy(), settings, monitor)


def _predict(
    problem: NonlinearProblem,
    u: np.ndarray,
    lam: float,
    target: float,
    prev: tuple[float, np.ndarray] | None,
) -> np.ndarray:
    """Secant predictor from the last two converged states, if it lowers the residual."""
    if prev is None or lam <= prev[0]:
        return u
    guess = u + (target - lam) / (lam - prev[0]) * (u - prev[1])
    guess[problem.fixed_dofs] = target * problem.fixed_values
    base = u.copy()
    base[problem.fixed_dofs] = target * problem.fixed_values
    try:
        r_guess = np.linalg.norm(problem.residual(guess, target)[0][problem.free])
        r_base = np.linalg.norm(problem.residual(base, target)[0][problem.free])
    except InvertedElements:
        return u
    return guess if np.isfinite(r_guess) and r_guess < r_base else u


def solve_nonlinear(
    problem: NonlinearProblem, opts: NewtonOptions, u0: np.ndarray | None = None
) -> tuple[np.ndarray, NewtonReport]:
    """Adaptive load stepping from ``lambda = 0`` (displacement ``u0``) to ``lambda = 1``.

    Parameters
    ----------
    problem
        The discrete problem.
    opts
        Newton and load-stepping settings.
    u0
        Start displacement (default zero).

    Returns
    -------
    u, report
        The converged DOF vector and the :class:`NewtonReport`.

    Raises
    ------
    SolverError
        When the load stepping gives up; ``state`` holds the last converged vertex
        displacements and ``load_factor`` their load factor.
    SolveStopped
        The ``--max-time`` cap passed or Ctrl-C: ``state`` and ``load_factor`` as above.
    """
    report = NewtonReport()
    state: dict[str, Any] = {
        "u": np.zeros(problem.n_dofs) if u0 is None else u0.copy(),
        "prev": None,
    }
    state["load"] = 0.0
    deadline = Deadline()
    times = report.phases
    kept: dict = {}  # the last tangent and its factorisation (modified Newton)

    def try_step(lam: float, target: float) -> tuple[bool, int, str]:
        step = len(report.steps) + 1
        label = f"step {step} (load {target:.4g})"
        with times("predictor"):
            start = _predict(problem, state["u"], lam, target, state["prev"])
        last_good = problem.state(state["u"])
        out = newton_step(
            problem, start, target, opts, label, deadline, last_good, times, step, kept
        )
        if not out.converged:
            _log(opts, f"  {label} failed: {out.reason}; load increment cut")
            return False, 0, out.reason
        u_new, hist, its = out.state, out.history, out.iterations
        report.iterations += its
        report.steps.append({"load": target, "iterations": its, "residuals": hist})
        _log(opts, f"step {len(report.steps)}: load {target:.4g} converged in {its} iterations")
        state["prev"] = (lam, state["u"])  # last converged (load, displacement)
        state["u"], state["load"] = u_new, target
        if opts.on_step is not None:
            opts.on_step(target, u_new)
        return True, its, ""

    def stopped(exc: SolveStopped) -> SolveStopped:
        load = state["load"]
        msg = f"{exc}; last converged load factor {load:.4g}"
        return SolveStopped(msg, state=problem.state(state["u"]), load_factor=load)

    try:
        with deadline.watch():
            path = LoadStepping(opts.load_steps, opts.max_cutbacks).run(try_step)
    except SolveStopped as exc:
        raise stopped(exc) from None
    except KeyboardInterrupt:
        raise stopped(deadline.stopped(interrupted=True)) from None
    finally:
        if opts.verbose:
            _log(opts, "phases:\n" + times.table())
    report.cutbacks = path.cutbacks
    if not path.converged:
        raise SolverError(
            f"Newton failed at load step {len(report.steps) + 1}, load factor {path.load:.4g} "
            f"-> {path.failed_at:.4g}: {path.reason}; gave up after {path.cutbacks} cut-backs "
            "of the load increment",
            state=problem.state(state["u"]),
            load_factor=path.load,
        )
    report.converged = True
    return state["u"], report
