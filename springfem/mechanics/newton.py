"""Newton's method with a backtracking line search at one load factor.

Examples
--------

>>> import numpy as np, scipy.sparse as sp
>>> class Oscillator:  # one tet, only node 3 moves (along x): mass 1, spring 4, load 1
...     x0 = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
...     masses = np.ones(4)
...     fixed_dofs = np.array([0, 1, 2, 3, 4, 5, 6, 7, 8, 10, 11])
...     def prescribed(self, s): return self.x0.reshape(-1)[self.fixed_dofs]
...     def forces(self, x, v, s=1.0):
...         f = np.zeros((4, 3)); f[3, 0] = -4.0 * x[3, 0] + s; return f
...     def energy(self, x, s=1.0): return 2.0 * x[3, 0] ** 2 - s * x[3, 0]
...     def stiffness(self, x, s=1.0):
...         return sp.csr_matrix(([4.0], ([9], [9])), shape=(12, 12))
...     def element_nodes(self): return np.array([[0, 1, 2, 3]])
...     def post_step(self, x, dt): pass
>>> from springfem.mechanics.context import SolveContext
>>> from springfem.mechanics.system import rigid_body_modes
>>> ctx = SolveContext(Oscillator())
>>> ok, x, its, hist, reason, K = newton(
...     ctx, ctx.x0.copy(), 1.0, 1.0, 1e-12, 10, "auto", "auto",
...     rigid_body_modes(ctx.x0)[ctx.free], None, 0)
>>> ok, its, round(float(x[3, 0]), 12)
(True, 1, 0.25)
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from springfem.errors import SolverError

from .context import JacobianKind, SolveContext, note_solver
from .linsolve import LinearSolver, LinearSolverKind

#: Backtracking steps (halvings of the Newton step) of the line search.
MAX_BACKTRACKS = 12


def newton(
    ctx: SolveContext,
    x: np.ndarray,
    s: float,
    f_ref: float,
    tol: float,
    max_iter: int,
    jacobian: JacobianKind,
    linear_solver: LinearSolverKind,
    B: np.ndarray,
    callback: Callable | None,
    it_offset: int,
):
    """Newton iterations at load factor s. Returns ok, x, iterations, history, reason, K.

    Line search (backtracking by halving): with an energy and a descent direction, Armijo
    on the energy; otherwise a step is accepted when the residual norm decreases (Armijo)
    or when Deuflhard's natural monotonicity test holds, ``|K^-1 f(x + a dx)| <=
    (1 - a/2) |dx|`` (the simplified Newton correction, one more solve with the same
    factorisation). The latter is affine invariant: on slender structures the residual
    norm of a good Newton step often grows (large axial forces from small rotations)
    while the correction shrinks.
    """
    system = ctx.system
    free = ctx.free
    xf = x.reshape(-1)
    R = ctx.free_force(x, s)
    r = float(np.linalg.norm(R)) / f_ref
    hist = [r]
    corrections: list[float] = []
    r0 = r
    K = None
    for it in range(1, max_iter + 1):
        if not np.isfinite(r):
            return False, x, it - 1, hist, "non-finite residual", K
        if r <= tol:
            return True, x, it - 1, hist, "", K
        K = ctx.stiffness(x, s, jacobian)
        try:
            solver = LinearSolver(linear_solver, B).factorize(ctx.ff(K))
            dx = solver.solve(R)
        except SolverError as err:
            return False, x, it, hist, f"singular tangent at iteration {it} ({err})", K
        note_solver(ctx, solver.name)
        dx_norm = float(np.linalg.norm(dx))
        corrections.append(dx_norm)
        e0 = system.energy(x, s)
        slope = float(R @ dx)  # -dPi/dalpha at alpha = 0 (f = -grad Pi)
        use_energy = e0 is not None and slope > 0
        alpha = 1.0
        accepted = False
        for _ in range(MAX_BACKTRACKS):
            x_try = x.copy()
            x_try.reshape(-1)[free] = xf[free] + alpha * dx
            R_try = ctx.free_force(x_try, s)
            r_try = float(np.linalg.norm(R_try)) / f_ref
            if np.isfinite(r_try):
                if use_energy:
                    e_try = system.energy(x_try, s)
                    de = e_try - e0
                    if de <= -1e-4 * alpha * slope:
                        accepted = True
                    elif abs(de) <= 1e-12 * (abs(e0) + abs(slope)) and r_try < r:
                        accepted = True  # energy flat to roundoff: the residual decides
                elif r_try <= (1.0 - 1e-4 * alpha) * r:
                    accepted = True
                else:
                    try:
                        bar = float(np.linalg.norm(solver.solve(R_try)))
                    except SolverError:
                        bar = np.inf
                    accepted = bar <= (1.0 - 0.5 * alpha) * dx_norm  # natural monotonicity
            if accepted:
                break
            alpha *= 0.5
        if not accepted:
            if r <= 1e3 * tol:
                return True, x, it, hist, f"residual stagnated at roundoff level {r:.3g}", K
            return False, x, it, hist, f"line search failed at iteration {it} (residual {r:.3g})", K
        r_old = r
        x, xf, R, r = x_try, x_try.reshape(-1), R_try, r_try
        hist.append(r)
        if callback is not None:
            callback(it_offset + it, s, x, r)
        if r > tol and r > 0.5 * r_old and r_old <= 1e3 * tol:
            return True, x, it, hist, f"residual stagnated at roundoff level {r:.3g}", K
        if r > 1e8 * max(r0, tol):
            return False, x, it, hist, f"diverging (residual {r:.3g})", K
        if it >= 8 and r > 0.9 * hist[-8] and dx_norm > 0.9 * corrections[-8]:
            return False, x, it, hist, f"stagnating at residual {r:.3g}", K
    if np.isfinite(r) and r <= tol:
        return True, x, max_iter, hist, "", K
    reason = f"no convergence in {max_iter} iterations (residual {r:.3g})"
    return False, x, max_iter, hist, reason, K
