"""ONE Newton iteration with a backtracking line search (:func:`newton`), run by both models
through a small problem protocol (:class:`NewtonProblem`), and the one rule of adaptive
load stepping (:class:`LoadStepping`).

Newton: the problem gives the residual ``R`` (the gradient of the energy when there is
one) with its relative norm, the Newton correction ``d = -K^-1 R`` with a way to re-solve
with the same tangent, the trial state ``state + alpha d``, the energy (or ``None``), and
whether the prescribed values are reached. A state the problem cannot accept (inverted
elements) is signalled by raising :class:`RejectedState` from ``residual``: a rejected
trial is backtracked, a rejected start fails the step. The spring model's adapter is in
:mod:`.static`, the FEM's in ``reference_fem.newton``.

Load stepping: the load fraction goes from 0 to 1 in ``load_steps`` nominal increments. A
step that fails (no convergence, divergence, a failed line search or linear solve, inverted
elements) is retried with half the increment; after a step that converges in at most
``easy_iterations`` iterations the increment doubles again, never beyond the nominal one
(so ``load_steps`` is honoured as the largest increment). The solve gives up after
``max_cutbacks`` halvings in a row, or when the increment has shrunk below
``nominal * cut**max_cutbacks`` (creeping towards a limit load). Halving (bisection) keeps
the largest increment not yet known to fail; the FEM's former ×0.25 threw away more
progress for no measured gain on the bundled scenes (same answers, same iteration counts).

Examples
--------
A scalar problem ``E(u) = u^4/4 - u`` (root ``u = 1``), its state a 1-vector:

>>> import numpy as np
>>> class Quartic:
...     def residual(self, u): R = u**3 - 1.0; return R, float(abs(R[0]))
...     def correction(self, u, R):
...         resolve = lambda b: -b / (3.0 * u**2)
...         return resolve(R), resolve
...     def trial(self, u, alpha, d): return u + alpha * d
...     def energy(self, u): return float(u[0] ** 4 / 4 - u[0])
...     def constrained(self, u): return True
...     def locate(self, R): return ""
>>> out = newton(Quartic(), np.array([2.0]), NewtonSettings(tol=1e-14, max_iter=20))
>>> out.converged, out.iterations, round(float(out.state[0]), 14)
(True, 6, 1.0)
>>> all(b <= a * a for a, b in zip(out.history[2:], out.history[3:]))  # quadratic
True
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from springfem.errors import SolverError

#: Load fractions within this of 1 count as the full load.
FULL_LOAD_TOL = 1e-12
#: Armijo constant: a step of length ``alpha`` must realise this fraction of the decrease
#: the linearisation predicts (of the energy, or of the residual norm).
ARMIJO = 1e-4
#: Energy changes below this times ``|E| + |slope|`` are roundoff: the residual decides.
ENERGY_ROUNDOFF = 1e-12
#: A residual within this factor of the tolerance is at the roundoff floor: a failed line
#: search or a stalled residual there counts as converged (with a note).
ROUNDOFF_FLOOR = 1e3
#: A residual above this times ``max(first residual, tol)`` is divergence.
DIVERGENCE = 1e8
#: Stagnation: after this many iterations, a residual and a correction both above
#: ``STAGNATION_RATIO`` times their values this many iterations ago fail the step.
STAGNATION_WINDOW = 8
#: See :data:`STAGNATION_WINDOW`.
STAGNATION_RATIO = 0.9
#: A residual above this fraction of the previous one at the roundoff floor has stalled.
STALL_RATIO = 0.5


class RejectedState(Exception):
    """Raised by :meth:`NewtonProblem.residual` for a state the problem cannot accept.

    A rejected trial state is backtracked by the line search; a rejected start fails the
    Newton solve (and load stepping cuts the step back).

    Parameters
    ----------
    message
        Why the state is rejected (e.g. which elements are inverted).
    """


class NewtonProblem(Protocol):
    """What :func:`newton` needs of a problem. ``state`` is whatever the problem iterates on.

    Attributes
    ----------
    residual, correction, trial, energy, constrained, locate
        The methods below: residual and its norm, the Newton correction with a re-solve
        for the same tangent, a trial state, the energy, whether the prescribed values are
        met, and where the largest residual is.
    """

    def residual(self, state: Any) -> tuple[np.ndarray, float]:
        """Residual ``R`` (energy-gradient sign) and its relative norm; may raise
        :class:`RejectedState`."""
        ...

    def correction(
        self, state: Any, R: np.ndarray
    ) -> tuple[np.ndarray, Callable[[np.ndarray], np.ndarray]]:
        """Newton correction ``d`` at ``state`` (reaching the prescribed values) and
        ``resolve(R') = -K^-1 R'`` with the same tangent; may raise :class:`SolverError`."""
        ...

    def trial(self, state: Any, alpha: float, d: np.ndarray) -> Any:
        """The state ``state + alpha d``."""
        ...

    def energy(self, state: Any) -> float | None:
        """Potential energy, or ``None`` when the forces have none."""
        ...

    def constrained(self, state: Any) -> bool:
        """Whether the prescribed values are reached."""
        ...

    def locate(self, R: np.ndarray) -> str:
        """Where the largest (or first non-finite) residual is, for messages (or ``""``)."""
        ...

    # optional, for modified Newton (NewtonSettings.reuse):
    # reused_correction(state, R) -> (d, resolve) with the last tangent kept, or None


@dataclass
class NewtonSettings:
    """Settings of :func:`newton`.

    Parameters
    ----------
    tol
        Relative residual tolerance.
    max_iter
        Newton iterations (linear solves) at most.
    max_backtracks
        Halvings of the step length in the line search.
    reuse
        Modified Newton: while an iteration lowers the residual to at most this fraction
        of the previous one, the next reuses the last tangent's factorisation (a problem
        with ``reused_correction``; 0: a fresh tangent every iteration).
    """

    tol: float = 1e-8
    max_iter: int = 200
    max_backtracks: int = 12
    reuse: float = 0.0


@dataclass
class NewtonOutcome:
    """Result of :func:`newton`.

    Attributes
    ----------
    converged
        The residual reached the tolerance (or its roundoff floor, see ``reason``).
    state
        The last accepted state.
    iterations
        Newton iterations done.
    history
        Relative residuals of the accepted states, the start first.
    reason
        Why it stopped: empty on plain convergence, a note at the roundoff floor, the
        failure otherwise.
    """

    converged: bool
    state: Any
    iterations: int
    history: list[float]
    reason: str = ""


def newton(
    problem: NewtonProblem,
    state: Any,
    settings: NewtonSettings,
    monitor: Callable[[int, Any, float, float], None] | None = None,
) -> NewtonOutcome:
    """Newton iterations with a backtracking line search from ``state``.

    Parameters
    ----------
    problem
        The :class:`NewtonProblem`.
    state
        Start state.
    settings
        Tolerance, iterations and backtracks.
    monitor
        ``monitor(iteration, state, residual, alpha)`` at the start (iteration 0, alpha 0)
        and after every accepted step, or ``None``.

    Returns
    -------
    NewtonOutcome
        Convergence, last state, iterations, residual history and reason.

    Notes
    -----
    Line search (backtracking by halving from ``alpha = 1``): a trial whose residual is
    not finite or that the problem rejects is halved. While the prescribed values are not
    yet reached, any other trial is accepted. Otherwise a step is accepted when any of
    these holds: the residual norm decreases (Armijo); with an energy and a descent
    direction, the energy decreases (Armijo; when it is flat to roundoff, the residual
    decreases at all); Deuflhard's natural monotonicity test,
    ``|K^-1 R(x + a d)| <= (1 - a/2) |d|`` (the simplified Newton correction, one more
    solve with the same tangent). Requiring the energy alone cut back the full step of
    the P2 neo-Hookean cantilever, whose residual falls while the energy test fails; the
    monotonicity test is affine invariant: on slender structures the residual norm of a
    good Newton step often grows (large axial forces from small rotations) while the
    correction shrinks.
    """
    tol, max_iter = settings.tol, settings.max_iter
    try:
        R, r = problem.residual(state)
    except RejectedState as exc:
        return NewtonOutcome(False, state, 0, [], str(exc))
    hist = [r]
    corrections: list[float] = []
    met = problem.constrained(state)
    r0 = r if met else None
    if monitor is not None:
        monitor(0, state, r, 0.0)

    def done(ok: bool, its: int, reason: str = "") -> NewtonOutcome:
        return NewtonOutcome(ok, state, its, hist, reason)

    reuse = settings.reuse > 0 and hasattr(problem, "reused_correction")
    stale = reuse  # the next correction may use the last tangent (of an earlier step too)
    for it in range(1, max_iter + 1):
        if not np.isfinite(r):
            return done(False, it - 1, f"non-finite residual{problem.locate(R)}")
        if r <= tol and met:
            return done(True, it - 1)
        while True:
            try:
                reused = getattr(problem, "reused_correction", None) if stale else None
                old = reused(state, R) if reused is not None else None
                d, resolve = old if old is not None else problem.correction(state, R)
            except SolverError as err:
                return done(False, it, f"singular tangent at iteration {it} ({err})")
            except RejectedState as exc:
                return done(False, it - 1, str(exc))
            stale = old is not None
            accepted, alpha, trial, R_try, r_try, d_norm = _line_search(
                problem, state, d, resolve, R, r, met, settings.max_backtracks
            )
            if accepted or not stale:
                break
            stale = False  # an old tangent's direction failed: a fresh one, same iteration
        fresh = not stale
        corrections.append(d_norm)
        if not accepted:
            if met and r <= ROUNDOFF_FLOOR * tol:
                return done(True, it, f"residual stagnated at roundoff level {r:.3g}")
            return done(False, it, f"line search failed at iteration {it} (residual {r:.3g})")
        r_old, met_old = r, met
        state, R, r = trial, R_try, r_try
        stale = reuse and alpha == 1.0 and r <= settings.reuse * r_old
        met = problem.constrained(state)
        hist.append(r)
        if monitor is not None:
            monitor(it, state, r, alpha)
        if met:
            floor = r_old <= ROUNDOFF_FLOOR * tol
            stalled = fresh and met_old and r > STALL_RATIO * r_old and floor
            if tol < r and stalled:
                return done(True, it, f"residual stagnated at roundoff level {r:.3g}")
            if r0 is None:
                r0 = r
            elif r > DIVERGENCE * max(r0, tol):
                return done(False, it, f"diverging (residual {r:.3g})")
        w = STAGNATION_WINDOW
        if (
            it >= w
            and r > STAGNATION_RATIO * hist[-w]
            and d_norm > STAGNATION_RATIO * corrections[-w]
        ):
            return done(False, it, f"stagnating at residual {r:.3g}")
    if np.isfinite(r) and r <= tol and met:
        return done(True, max_iter)
    where = problem.locate(R)
    return done(
        False, max_iter, f"no convergence in {max_iter} iterations (residual {r:.3g}{where})"
    )


def _line_search(problem, state, d, resolve, R, r, met, max_backtracks):
    """Backtracking by halving from ``alpha = 1`` (the Notes of :func:`newton`).

    Returns ``(accepted, alpha, trial, R_try, r_try, |d|)``.
    """
    d_norm = float(np.linalg.norm(d))
    slope = float(R @ d)  # dE/dalpha at alpha = 0 (R = grad E)
    e0 = problem.energy(state) if met and slope < 0 else None
    alpha, accepted, trial, R_try, r_try = 1.0, False, state, R, np.inf
    for _ in range(max_backtracks):
        trial = problem.trial(state, alpha, d)
        try:
            R_try, r_try = problem.residual(trial)
        except RejectedState:
            r_try = np.inf
        if np.isfinite(r_try):
            accepted = _acceptable(
                problem, trial, alpha, met, e0, slope, r, r_try, R_try, resolve, d_norm
            )
        if accepted:
            break
        alpha *= 0.5
    return accepted, alpha, trial, R_try, r_try, d_norm


def _acceptable(problem, trial, alpha, met, e0, slope, r, r_try, R_try, resolve, d_norm) -> bool:
    """The line-search test of :func:`newton` for a finite trial (see its Notes)."""
    if not met:
        return True  # the prescribed values are being reached: take the step
    if r_try <= (1.0 - ARMIJO * alpha) * r:
        return True
    if e0 is not None:
        de = problem.energy(trial) - e0
        if de <= ARMIJO * alpha * slope:
            return True
        if abs(de) <= ENERGY_ROUNDOFF * (abs(e0) + abs(slope)) and r_try < r:
            return True  # energy flat to roundoff and the residual decreases
    try:
        bar = float(np.linalg.norm(resolve(R_try)))
    except SolverError:
        return False
    return bar <= (1.0 - 0.5 * alpha) * d_norm  # natural monotonicity


@dataclass
class LoadPath:
    """Outcome of :meth:`LoadStepping.run`.

    Attributes
    ----------
    converged
        The full load was reached.
    load
        Last converged load fraction.
    steps
        Converged load fractions, in order.
    cutbacks
        Failed steps (each halved the increment).
    reason
        Why the last failed step failed.
    failed_at
        Load fraction of the last failed step (``nan`` when none failed).
    """

    converged: bool = False
    load: float = 0.0
    steps: list[float] = field(default_factory=list)
    cutbacks: int = 0
    reason: str = ""
    failed_at: float = float("nan")


@dataclass
class LoadStepping:
    """The adaptive load-stepping rule (see the module docstring).

    Parameters
    ----------
    load_steps
        Nominal number of equal increments.
    max_cutbacks
        Halvings in a row before giving up.
    easy_iterations
        A step converged in at most this many iterations lets the increment grow.
    cut, grow
        Factors of the increment after a failed and after an easy step.
    """

    load_steps: int = 1
    max_cutbacks: int = 8
    easy_iterations: int = 4
    cut: float = 0.5
    grow: float = 2.0

    def run(self, try_step: Callable[[float, float], tuple[bool, int, str]]) -> LoadPath:
        """Step the load fraction from 0 to 1.

        Parameters
        ----------
        try_step
            ``try_step(from, to) -> (ok, iterations, reason)``: solve at load fraction ``to``
            from the state converged at ``from``, keep the new state when ``ok``.

        Returns
        -------
        LoadPath
            Converged fractions, cut-backs, and the reason of the last failure.
        """
        path = LoadPath()
        nominal = 1.0 / max(1, int(self.load_steps))
        dlam, in_a_row = nominal, 0
        while path.load < 1.0 - FULL_LOAD_TOL or not path.steps:
            lam = path.load
            to = 1.0 if lam + dlam >= 1.0 - FULL_LOAD_TOL else lam + dlam
            ok, its, reason = try_step(lam, to)
            if ok:
                path.load = to
                path.steps.append(to)
                in_a_row = 0
                if its <= self.easy_iterations:
                    dlam = min(self.grow * dlam, nominal)
                continue
            path.cutbacks += 1
            path.reason, path.failed_at = reason, to
            in_a_row += 1
            dlam *= self.cut
            if in_a_row > self.max_cutbacks or dlam < nominal * self.cut**self.max_cutbacks:
                break
        path.converged = bool(path.steps) and path.load >= 1.0 - FULL_LOAD_TOL
        return path
