"""The FEM's Newton iteration (displacement form, prescribed values reached by the
update) under the shared load-stepping rule :class:`springfem.mechanics.newton.LoadStepping`.

The load factor ``lambda`` scales every load and every prescribed displacement. A load step
that fails (too many iterations, a growing or non-finite residual, an inverted element, a
failed linear solve) is retried with a smaller increment (the shared rule); when it gives
up, the solve stops with :class:`~springfem.errors.SolverError` carrying the last converged
displacement.

Convergence: ``|R_free| <= tol * max(|f_int|, |f_ext|)`` with the prescribed values reached.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from springfem.errors import SolverError
from springfem.mechanics.newton import LoadStepping


class InvertedElements(Exception):
    """Raised by a problem's residual when elements have ``J <= 0``."""

    def __init__(self, elements: np.ndarray, where: str = ""):
        msg = f"{len(elements)} inverted element(s) (J <= 0): {elements[:5].tolist()}"
        super().__init__(msg + (f" {where}" if where else ""))
        self.elements = elements


class NonlinearProblem(Protocol):
    n_dofs: int
    free: np.ndarray
    fixed_dofs: np.ndarray
    fixed_values: np.ndarray

    def residual(self, u: np.ndarray, scale: float) -> tuple[np.ndarray, float]: ...

    def energy(self, u: np.ndarray, scale: float) -> float | None: ...

    def residual_tangent(self, u: np.ndarray, scale: float): ...

    def solve_linear(self, K, b: np.ndarray, symmetric: bool, where: str) -> np.ndarray: ...

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
        Print the residual history to stderr.
    """

    tol: float = 1e-10
    max_iter: int = 25
    load_steps: int = 1
    max_cutbacks: int = 8
    max_backtracks: int = 8
    verbose: bool = False


@dataclass
class NewtonReport:
    """Outcome: total iterations and, per accepted step, its load factor and residuals."""

    converged: bool = False
    iterations: int = 0
    steps: list[dict] = field(default_factory=list)
    cutbacks: int = 0


class _StepFailed(Exception):
    pass


def _log(opts: NewtonOptions, msg: str) -> None:
    if opts.verbose:
        print(msg, file=sys.stderr, flush=True)


def newton_step(
    problem: NonlinearProblem, u: np.ndarray, scale: float, opts: NewtonOptions, label: str
) -> tuple[np.ndarray, list[float], int]:
    """Iterate to equilibrium at load factor ``scale`` starting from ``u``.

    Returns the solution, the relative residual history and the iteration count; raises
    ``_StepFailed`` with a reason.
    """
    free = problem.free
    target = scale * problem.fixed_values
    history: list[float] = []
    u = u.copy()
    r0 = None
    for it in range(opts.max_iter + 1):
        try:
            R, K, symmetric, ref = problem.residual_tangent(u, scale)
        except InvertedElements as exc:
            raise _StepFailed(str(exc)) from None
        res = np.linalg.norm(R[free])
        rel = res / max(ref, 1e-300)
        history.append(float(rel))
        gap = np.abs(u[problem.fixed_dofs] - target).max(initial=0.0)
        _log(opts, f"  {label} iteration {it:2d}  |R|/|f| = {rel:.3e}")
        if not np.isfinite(rel):
            bad = np.flatnonzero(~np.isfinite(R[free]))
            where = f" at FE node {int(free[bad[0]]) // 3}" if bad.size else ""
            raise _StepFailed(f"non-finite residual{where}")
        if rel <= opts.tol and gap == 0.0:
            return u, history, it
        if it == opts.max_iter:
            worst = int(free[np.argmax(np.abs(R[free]))])
            raise _StepFailed(
                f"no convergence in {opts.max_iter} iterations (|R|/|f| = {rel:.2e}; largest "
                f"residual at FE node {worst // 3}, component {'xyz'[worst % 3]})"
            )
        if r0 is None:
            # divergence is judged against the first residual with the prescribed values
            # reached: before that (a prescribed displacement from rest) it can be 0
            r0 = rel if gap == 0.0 else None
        elif rel > 1e6 * max(r0, opts.tol):
            raise _StepFailed(f"residual grew to {rel:.2e}")
        du = np.zeros_like(u)
        du[problem.fixed_dofs] = target - u[problem.fixed_dofs]
        b = -R - (K @ du if gap > 0 else 0.0)
        try:
            du += problem.solve_linear(K, b, symmetric, f"{label} iteration {it}: ")
        except SolverError as exc:
            raise _StepFailed(str(exc)) from None
        # Backtracking line search: accept a step that decreases the potential energy
        # (Armijo, when the loads have one) or the residual norm; full steps while the
        # prescribed values move.
        slope = float(R @ du)
        e0 = problem.energy(u, scale) if gap == 0 and slope < 0 else None
        alpha = 1.0
        for _ in range(opts.max_backtracks):
            trial = u + alpha * du
            if alpha == 1.0:
                trial[problem.fixed_dofs] = target
            try:
                Rt, ref_t = problem.residual(trial, scale)
                rel_t = np.linalg.norm(Rt[free]) / max(ref_t, 1e-300)
            except InvertedElements:
                rel_t = np.inf
            if np.isfinite(rel_t):
                if gap > 0 or rel_t <= (1 - 1e-4 * alpha) * rel:
                    break
                if e0 is not None and problem.energy(trial, scale) <= e0 + 1e-4 * alpha * slope:
                    break
            alpha *= 0.5
        else:
            if rel <= 1e3 * opts.tol and gap == 0.0:
                return u, history, it  # at the round-off floor
            raise _StepFailed(f"line search failed at |R|/|f| = {rel:.2e}")
        if alpha < 1.0:
            _log(opts, f"  {label} line search alpha = {alpha:g}")
        u = trial
    raise AssertionError("unreachable")


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
        displacements.
    """
    report = NewtonReport()
    state = {"u": np.zeros(problem.n_dofs) if u0 is None else u0.copy(), "prev": None}

    def try_step(lam: float, target: float) -> tuple[bool, int, str]:
        label = f"step {len(report.steps) + 1} (load {target:.4g})"
        start = _predict(problem, state["u"], lam, target, state["prev"])
        try:
            u_new, hist, its = newton_step(problem, start, target, opts, label)
        except _StepFailed as exc:
            _log(opts, f"  {label} failed: {exc}; load increment cut")
            return False, 0, str(exc)
        report.iterations += its
        report.steps.append({"load": target, "iterations": its, "residuals": hist})
        _log(opts, f"step {len(report.steps)}: load {target:.4g} converged in {its} iterations")
        state["prev"] = (lam, state["u"])  # last converged (load, displacement)
        state["u"] = u_new
        return True, its, ""

    path = LoadStepping(opts.load_steps, opts.max_cutbacks).run(try_step)
    report.cutbacks = path.cutbacks
    if not path.converged:
        raise SolverError(
            f"Newton failed at load step {len(report.steps) + 1}, load factor {path.load:.4g} "
            f"-> {path.failed_at:.4g}: {path.reason}; gave up after {path.cutbacks} cut-backs "
            "of the load increment",
            state=problem.state(state["u"]),
        )
    report.converged = True
    return state["u"], report
