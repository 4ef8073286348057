"""Solvers for a :class:`~springfem.mechanics.system.MechanicalSystem`: critical time step,
explicit (symplectic Euler, velocity Verlet), explicit to equilibrium (dynamic
relaxation), implicit backward Euler and static Newton with line search and load stepping.

The solvers see only masses, constraints, forces, energy, tangent and connectivity, never
springs. When the system has no analytic tangent, a coloured finite-difference Jacobian
(:mod:`springfem.mechanics.coloring`) takes its place.

Every solver detects failure and raises :class:`~springfem.errors.SolverError` naming
what failed, when (step, time, load factor) and where (node and element), with the last
good positions as ``state``.

Examples
--------
A fixed-free chain of two masses (``tests/test_solvers.py`` has the full test systems)::

    dt_crit, omega = stable_time_step(system)
    traj = explicit(system, dt=0.5 * dt_crit, steps=1000, integrator="verlet")
    info = static(system, tol=1e-10)
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import scipy.linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from springfem.errors import SolverError

from .coloring import ColoredJacobian, characteristic_length
from .system import (
    SINGULAR_MESSAGE,
    MechanicalSystem,
    check_constrained,
    constrained_positions,
    free_dofs,
    rigid_body_modes,
)

Integrator = Literal["symplectic-euler", "verlet"]
LinearSolverKind = Literal["auto", "direct", "amg"]
JacobianKind = Literal["auto", "analytic", "fd"]
Damping = Literal["auto", "kinetic", "mass"]
Scale = float | Callable[[float], float]

#: Above this many free DOFs, ``linear_solver="auto"`` uses CG/GMRES + smoothed-aggregation AMG.
AMG_THRESHOLD = 12_000
#: Up to this many free DOFs, the critical time step uses a dense eigensolver.
DENSE_EIG_THRESHOLD = 600
#: Relative asymmetry ``|K - K^T| / |K|`` below which a tangent is treated as symmetric
#: (the central-difference Jacobian of a gradient field is symmetric to ~1e-10).
SYMMETRY_TOL = 1e-6

_TET_EDGES = np.array([(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)])


# ------------------------------------------------------------------------------ results


@dataclass
class Trajectory:
    """A time integration: recorded energies, final state and cost.

    Attributes
    ----------
    times, kinetic, potential
        Recorded every ``record_every`` steps (and at the end). ``potential`` is NaN when
        the system has no energy (non-gradient forces). Symplectic Euler is leapfrog with
        the stored velocity half a step behind the positions; its kinetic energy is recorded
        with the synchronised velocity ``v + dt/2 M^-1 f`` (as velocity Verlet's), so the
        recorded total energy of both integrators oscillates by ``O((omega dt)^2)`` without
        drifting.
    x, v
        Final positions and velocities ``(n, 3)``.
    steps, dt, dt_crit
        Steps taken, time step, critical time step (``None`` when not computed).
    converged
        ``True`` when the run completed (or, for equilibrium runs, reached the tolerance).
    iterations
        Total Newton iterations (implicit), 0 for explicit runs.
    residual_history
        Implicit: final relative Newton residual of every step. Equilibrium runs: relative
        static residual at every check.
    """

    times: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    x: np.ndarray
    v: np.ndarray
    steps: int
    dt: float
    dt_crit: float | None
    integrator: str
    converged: bool = True
    wall_time: float = 0.0
    iterations: int = 0
    residual_history: list[float] = field(default_factory=list)
    force_evaluations: int = 0
    message: str = ""

    @property
    def energies(self) -> np.ndarray:
        """``(r, 2)``: kinetic and potential energy at the recorded times."""
        return np.column_stack([self.kinetic, self.potential])

    @property
    def total_energy(self) -> np.ndarray:
        """Kinetic plus potential energy at the recorded times."""
        return self.kinetic + self.potential


@dataclass
class SolveInfo:
    """A static (equilibrium) solve.

    Attributes
    ----------
    x
        Equilibrium positions ``(n, 3)``.
    converged
        Relative residual reached ``tol``.
    iterations
        Newton iterations summed over load steps (explicit steps for dynamic relaxation).
    residual_history
        ``|f_free| / reference_force`` after every iteration (or check).
    load_steps
        The converged load factors, in order.
    method
        ``newton``, ``dynamic-relaxation`` or ``newton+dynamic-relaxation``.
    jacobian
        ``analytic``, ``fd`` (coloured finite differences) or ``none``.
    linear_solver
        Linear solvers used (``direct``, ``cg+amg``, ``gmres+amg``), comma separated.
    reference_force
        ``|f_free|`` at the rest positions with prescribed DOFs: the load being balanced.
    cutbacks
        Load-step cut-backs after a failed Newton solve.
    """

    x: np.ndarray
    converged: bool
    iterations: int
    residual_history: list[float]
    load_steps: list[float]
    method: str
    jacobian: str
    linear_solver: str
    wall_time: float
    reference_force: float
    cutbacks: int = 0
    steps: int = 0
    dt: float | None = None
    force_evaluations: int = 0
    message: str = ""

    @property
    def residual(self) -> float:
        """Final relative residual."""
        return self.residual_history[-1] if self.residual_history else float("nan")


# ------------------------------------------------------------------------------ context


class _Context:
    """Per-solve view of a system: DOF sets, masses, Jacobians, force-evaluation count."""

    def __init__(self, system: MechanicalSystem):
        self.system = system
        self.x0 = np.asarray(system.x0, dtype=float).reshape(-1, 3)
        self.n = self.x0.shape[0]
        self.fixed = np.asarray(system.fixed_dofs, dtype=np.int64).ravel()
        self.free = free_dofs(system)
        self.m = np.asarray(system.masses, dtype=float).ravel()
        if self.m.shape != (self.n,) or not np.all(self.m > 0):
            raise ValueError("masses must be (n,) and positive")
        self.m_dof = np.repeat(self.m, 3)
        self.tets = np.asarray(system.element_nodes(), dtype=np.int64)
        self.n_evals = 0
        self._cj: ColoredJacobian | None = None
        self._node_tets: tuple[np.ndarray, np.ndarray] | None = None
        self.jacobian_kind = "none"
        self.solvers_used: list[str] = []

    # forces / energies
    def forces(self, x: np.ndarray, v: np.ndarray | None, s: float) -> np.ndarray:
        self.n_evals += 1
        return np.asarray(self.system.forces(x, v, s), dtype=float).reshape(self.n, 3)

    def free_force(self, x: np.ndarray, s: float) -> np.ndarray:
        return self.forces(x, None, s).reshape(-1)[self.free]

    def potential(self, x: np.ndarray, s: float) -> float:
        e = self.system.energy(x, s)
        return float("nan") if e is None else float(e)

    def kinetic(self, v: np.ndarray) -> float:
        return 0.5 * float(np.einsum("i,ij,ij->", self.m, v, v))

    # Jacobians
    @property
    def coloring(self) -> ColoredJacobian:
        if self._cj is None:
            self._cj = ColoredJacobian(self.tets, self.n)
        return self._cj

    def stiffness(self, x: np.ndarray, s: float, jacobian: JacobianKind = "auto") -> sp.csr_matrix:
        """``K = -d f / dx`` (static part), analytic when available."""
        K = None
        if jacobian in ("auto", "analytic"):
            K = self.system.stiffness(x, s)
            if K is None and jacobian == "analytic":
                raise ValueError("jacobian='analytic' but the system has no analytic stiffness")
        if K is None:
            self.jacobian_kind = "fd"
            return self.coloring(lambda y: self.forces(y, None, s), x)
        self.jacobian_kind = "analytic"
        return sp.csr_matrix(K)

    def damping_matrix(self, x: np.ndarray, s: float, v_scale: float) -> sp.csr_matrix:
        """``C = -d f / dv`` by forward differences (damping forces are linear in ``v``)."""
        zero = np.zeros_like(x)
        return self.coloring(
            lambda w: self.forces(x, w, s), zero, eps=1e-3 * v_scale, scheme="forward"
        )

    def has_damping(self, x: np.ndarray, s: float, v_scale: float) -> bool:
        """Whether the forces depend on the velocity (probe with a random velocity)."""
        rng = np.random.default_rng(0)
        w = rng.standard_normal(x.shape) * v_scale
        f1 = self.forces(x, w, s)
        f0 = self.forces(x, np.zeros_like(x), s)
        scale = max(np.abs(f0).max(), np.abs(f1).max(), 1e-300)
        return bool(np.abs(f1 - f0).max() > 1e-13 * scale)

    def ff(self, K: sp.spmatrix) -> sp.csr_matrix:
        K = sp.csr_matrix(K)
        return K[self.free][:, self.free]

    # location of a failure
    def node_tets(self, node: int) -> np.ndarray:
        if self._node_tets is None:
            flat = self.tets.ravel()
            order = np.argsort(flat, kind="stable")
            start = np.searchsorted(flat[order], np.arange(self.n + 1))
            self._node_tets = (order // max(self.tets.shape[1], 1), start)
        order, start = self._node_tets
        return np.unique(order[start[node] : start[node + 1]])

    def edge_strain(self, x: np.ndarray, elems: np.ndarray) -> np.ndarray:
        """Largest ``| |e| / |e0| - 1 |`` over the six edges of each element."""
        t = self.tets[elems]
        if t.shape[1] < 4:
            return np.zeros(len(elems))
        e = x[t[:, _TET_EDGES[:, 1]]] - x[t[:, _TET_EDGES[:, 0]]]
        e0 = self.x0[t[:, _TET_EDGES[:, 1]]] - self.x0[t[:, _TET_EDGES[:, 0]]]
        l0 = np.linalg.norm(e0, axis=-1)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            strain = np.abs(np.linalg.norm(e, axis=-1) / np.where(l0 > 0, l0, 1.0) - 1.0)
        strain = np.where(l0 > 0, strain, 0.0)  # repeated nodes (degenerate elements)
        return np.nan_to_num(strain, nan=np.inf).max(axis=1)

    def shortest_edge(self, node: int) -> float:
        elems = self.node_tets(node)
        if elems.size == 0:
            return float("nan")
        t = self.tets[elems]
        d = np.linalg.norm(self.x0[t] - self.x0[node], axis=-1)
        d = d[d > 0]
        return float(d.min()) if d.size else float("nan")

    def locate(self, x_prev: np.ndarray, x: np.ndarray) -> str:
        """Describe where a blow-up started: node and element."""
        bad = ~np.isfinite(x).all(axis=1)
        if self.tets.size == 0:
            node = int(np.flatnonzero(bad)[0]) if bad.any() else 0
            return f"at node {node}"
        if bad.any():
            elems = np.flatnonzero(bad[self.tets].any(axis=1))
            if elems.size == 0:
                node = int(np.flatnonzero(bad)[0])
                return f"first non-finite value at node {node} (in no element)"
            strain = self.edge_strain(x_prev, elems)
            e = int(elems[np.argmax(strain)])
            in_e = [int(i) for i in self.tets[e] if bad[i]]
            node = in_e[0] if in_e else int(np.flatnonzero(bad)[0])
            return (
                f"first non-finite value at node {node} in element {e} "
                f"(largest edge strain there {strain.max():.3g} the step before)"
            )
        jump = np.linalg.norm(x - x_prev, axis=1)
        node = int(np.argmax(jump))
        elems = self.node_tets(node)
        if elems.size == 0:
            return f"largest displacement jump {jump[node]:.3g} m at node {node} (in no element)"
        strain = self.edge_strain(x, elems)
        e = int(elems[np.argmax(strain)])
        h = self.shortest_edge(node)
        return (
            f"largest displacement jump {jump[node]:.3g} m ({jump[node] / h:.3g} x its "
            f"shortest edge) at node {node} in element {e} (largest edge strain {strain.max():.3g})"
        )


def _scale_fn(scale: Scale) -> Callable[[float], float]:
    if callable(scale):
        return scale
    s = float(scale)
    return lambda t: s


def _n_steps(dt: float, steps: int | None, t_end: float | None) -> int:
    if steps is not None:
        return int(steps)
    if t_end is not None:
        return max(1, int(np.ceil(t_end / dt - 1e-9)))
    raise ValueError("give steps or t_end")


# --------------------------------------------------------------------------- linear solve


def _is_symmetric(A: sp.spmatrix) -> bool:
    nrm = spla.norm(A)
    return bool(nrm == 0 or spla.norm(A - A.T) <= SYMMETRY_TOL * nrm)


class LinearSolver:
    """A factorised (free-DOF) tangent: solve ``A x = b`` for several right-hand sides.

    ``direct`` is SuperLU; ``amg`` is CG (symmetric ``A``) or GMRES (non-symmetric, e.g. the
    Jacobian of the non-gradient torsion springs) preconditioned by pyamg smoothed
    aggregation with ``near_nullspace`` (the rigid-body modes) as candidates. ``auto`` is
    direct up to :data:`AMG_THRESHOLD` unknowns; a failed direct solve falls back to AMG.
    A tangent whose asymmetry is below :data:`SYMMETRY_TOL` (finite-difference noise) is
    symmetrised for CG.

    Attributes
    ----------
    name
        The solver that produced the last solution (``direct``, ``cg+amg``, ``gmres+amg``).
    """

    def __init__(
        self,
        A: sp.spmatrix,
        method: LinearSolverKind = "auto",
        near_nullspace: np.ndarray | None = None,
        rtol: float = 1e-10,
    ):
        self.A = sp.csr_matrix(A)
        n = self.A.shape[0]
        if method == "auto":
            method = "direct" if n <= AMG_THRESHOLD else "amg"
        if method not in ("direct", "amg"):
            raise ValueError(f"unknown linear solver {method!r}; valid: 'auto', 'direct', 'amg'")
        self.method = method
        self.B = near_nullspace
        self.rtol = rtol
        self.name = "none"
        self._lu = None
        self._ml = None
        if method == "direct":
            try:
                self._lu = spla.splu(self.A.tocsc())
            except RuntimeError:  # exactly singular factor: try AMG
                self._lu = None

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Solve ``A x = b``.

        Raises
        ------
        SolverError
            When no solver produces a finite solution with a small residual (singular ``A``).
        """
        b = np.asarray(b, dtype=float)
        bnorm = float(np.linalg.norm(b))
        if bnorm == 0:
            return np.zeros(self.A.shape[0])
        if self._lu is not None:
            x = self._lu.solve(b)
            if np.all(np.isfinite(x)) and np.linalg.norm(self.A @ x - b) <= 1e-6 * bnorm:
                self.name = "direct"
                return x
        x, A_used = self._solve_amg(b)
        if (
            not np.all(np.isfinite(x))
            or np.linalg.norm(A_used @ x - b) > max(1e-6, 10 * self.rtol) * bnorm
        ):
            raise SolverError(
                "singular stiffness: the tangent has a zero-energy mode (a mechanism of the "
                "spring network, a limit point, or a missing boundary condition)"
            )
        return x

    def _solve_amg(self, b: np.ndarray) -> tuple[np.ndarray, sp.csr_matrix]:
        if self._ml is None:
            import pyamg

            self._sym = _is_symmetric(self.A)
            self._As = ((self.A + self.A.T) * 0.5).tocsr() if self._sym else self.A
            B = self.B
            kw = {"B": B} if B is not None and B.shape[0] == self.A.shape[0] else {}
            self._ml = pyamg.smoothed_aggregation_solver(
                self._As, symmetry="hermitian" if self._sym else "nonsymmetric", **kw
            )
        M = self._ml.aspreconditioner(cycle="V")
        maxiter = max(200, self.A.shape[0] // 10)
        if self._sym:
            x, _ = spla.cg(self._As, b, rtol=self.rtol, atol=0.0, maxiter=maxiter, M=M)
            self.name = "cg+amg"
            return x, self._As
        x, _ = spla.gmres(self.A, b, rtol=self.rtol, atol=0.0, restart=60, maxiter=maxiter, M=M)
        self.name = "gmres+amg"
        return x, self.A


def solve_linear(
    A: sp.spmatrix,
    b: np.ndarray,
    method: LinearSolverKind = "auto",
    near_nullspace: np.ndarray | None = None,
    rtol: float = 1e-10,
) -> tuple[np.ndarray, str]:
    """Solve ``A x = b`` once with a :class:`LinearSolver`; returns ``(x, solver name)``."""
    solver = LinearSolver(A, method, near_nullspace, rtol)
    x = solver.solve(b)
    return x, solver.name


# ------------------------------------------------------------------------ critical step


def stable_time_step(
    system: MechanicalSystem,
    x: np.ndarray | None = None,
    scale: float = 1.0,
    jacobian: JacobianKind = "auto",
) -> tuple[float, float]:
    """Critical time step ``2 / omega_max`` of explicit integration at a state.

    ``omega_max^2`` is the largest eigenvalue of ``M^-1 K`` on the free DOFs, computed as
    the largest eigenvalue of the symmetric ``M^-1/2 K M^-1/2`` (dense below
    :data:`DENSE_EIG_THRESHOLD` free DOFs, Lanczos ``eigsh`` above). For a non-symmetric
    tangent (non-gradient forces) ``omega_max^2`` is the largest ``|lambda|`` of ``M^-1 K``.
    Symplectic Euler and velocity Verlet are stable for linear systems iff
    ``omega_max dt < 2``.

    Parameters
    ----------
    system
        The system.
    x
        State ``(n, 3)``; default the rest positions (fixed DOFs are set to
        ``prescribed(scale)`` in either case).
    scale
        Load factor.
    jacobian
        ``auto`` (analytic if available, else coloured finite differences), ``analytic``
        or ``fd``.

    Returns
    -------
    dt_crit, omega_max
        ``(inf, 0)`` when the tangent has no positive eigenvalue.
    """
    ctx = _Context(system)
    x = constrained_positions(system, scale, x)
    Kff = ctx.ff(ctx.stiffness(x, scale, jacobian))
    d = sp.diags(1.0 / np.sqrt(ctx.m_dof[ctx.free]))
    A = (d @ Kff @ d).tocsr()
    n = A.shape[0]
    if n == 0:
        return float("inf"), 0.0
    sym = _is_symmetric(A)
    if sym:
        A = ((A + A.T) * 0.5).tocsr()
    if n <= DENSE_EIG_THRESHOLD:
        if sym:
            lam = float(scipy.linalg.eigvalsh(A.toarray())[-1])
        else:
            lam = float(np.abs(np.linalg.eigvals(A.toarray())).max())
    else:
        lam = _largest_eigenvalue(A, sym)
    if not lam > 0:
        return float("inf"), 0.0
    omega = float(np.sqrt(lam))
    return 2.0 / omega, omega


def _largest_eigenvalue(A: sp.csr_matrix, sym: bool) -> float:
    rng = np.random.default_rng(1)
    v0 = rng.standard_normal(A.shape[0])
    ncv = min(A.shape[0], 40)
    try:
        if sym:
            return float(spla.eigsh(A, k=1, which="LA", tol=1e-8, ncv=ncv, v0=v0)[0][0])
        return float(np.abs(spla.eigs(A, k=1, which="LM", tol=1e-8, ncv=ncv, v0=v0)[0][0]))
    except spla.ArpackNoConvergence:
        # Gershgorin: an upper bound on the spectral radius (a safe, smaller dt).
        return float(np.abs(A).sum(axis=1).max())


# --------------------------------------------------------------------------- explicit


def _blowup_error(
    ctx: _Context,
    kind: str,
    k: int,
    t: float,
    reason: str,
    x_prev: np.ndarray,
    x: np.ndarray,
    dt: float,
    dt_crit: float | None,
    state: np.ndarray,
) -> SolverError:
    where = ctx.locate(x_prev, x)
    if dt_crit is None:
        try:
            dt_crit = stable_time_step(ctx.system)[0]
        except Exception:  # noqa: BLE001 - the report must not fail while reporting
            dt_crit = None
    crit = (
        f" (critical dt {dt_crit:.3g} s at rest: dt / dt_crit = {dt / dt_crit:.3g})"
        if dt_crit and np.isfinite(dt_crit)
        else ""
    )
    msg = f"{kind} integration blew up at step {k} (t = {t:.3g} s): {reason}; {where}; "
    msg += f"dt = {dt:.3g} s{crit}"
    return SolverError(msg, state=state)


class _BlowupMonitor:
    """Detects an explicit blow-up from the kinetic energy history.

    A step is a blow-up when the velocity is not finite, or when both

    1. the kinetic energy exceeds ``factor`` times its largest value in the first half of
       the current window (a stable run grows polynomially, by ``~2^p`` over such a window;
       an unstable one exponentially), and
    2. the velocity field oscillates on the unstable time scale: its Rayleigh quotient
       ``omega_eff^2 = v.K v / v.M v`` (one central difference of the forces along ``v``)
       gives ``omega_eff dt >= 1.5``. Linear explicit integration is unstable only for
       modes with ``omega dt > 2`` and ``omega_eff <= omega_max``, so a stable step
       (``dt <~ 0.75 dt_crit``) never passes this test.

    Growth that fails the second test is physical (e.g. a load switched on after a quiet
    start): the window restarts at that step.
    """

    def __init__(self, ctx: _Context, n_steps: int, dt: float, factor: float, ke0: float):
        self.ctx = ctx
        self.dt = dt
        self.factor = factor
        self.ke = np.empty(n_steps + 1)
        self.ke[0] = ke0
        self.start = 0  # window start
        self.ref_idx = 0
        self.ref = ke0
        self._length: float | None = None

    def check(self, k: int, ke: float, x: np.ndarray, v: np.ndarray, s: float) -> str | None:
        self.ke[k] = ke
        if not np.isfinite(ke):
            return "non-finite velocity"
        j = self.start + (k - self.start) // 2
        while self.ref_idx < j:
            self.ref_idx += 1
            self.ref = max(self.ref, self.ke[self.ref_idx])
        if not (self.ref > 0 and ke > self.factor * self.ref):
            return None
        w_dt = self.omega_dt(x, v, s)
        if w_dt >= 1.5:
            return (
                f"kinetic energy grew by a factor {ke / self.ref:.3g} between steps {j} and {k} "
                f"while the velocity oscillates at omega dt = {w_dt:.3g} (unstable above 2)"
            )
        self.start, self.ref_idx, self.ref = k, k, ke  # physical growth: new window
        return None

    def omega_dt(self, x: np.ndarray, v: np.ndarray, s: float) -> float:
        """``dt sqrt(v.K v / v.M v)`` on the free DOFs (K by a central difference)."""
        ctx = self.ctx
        w = np.zeros(3 * ctx.n)
        w[ctx.free] = v.reshape(-1)[ctx.free]
        wmax = np.abs(w).max()
        if not wmax > 0:
            return 0.0
        w = (w / wmax).reshape(-1, 3)
        if self._length is None:
            self._length = characteristic_length(ctx.x0, ctx.tets)
        h = 1e-6 * self._length
        df = ctx.forces(x + h * w, None, s) - ctx.forces(x - h * w, None, s)
        wKw = -float(np.sum(w * df)) / (2 * h)
        wMw = float(np.einsum("i,ij,ij->", ctx.m, w, w))
        return self.dt * float(np.sqrt(max(wKw, 0.0) / wMw))


def _explicit_loop(
    ctx: _Context,
    *,
    dt: float,
    n_steps: int,
    integrator: Integrator,
    alpha: float,
    scale: Scale,
    x: np.ndarray,
    v: np.ndarray,
    record_every: int,
    callback: Callable | None,
    progress: bool,
    kinetic_damping: bool,
    stop_fn: Callable[[int, float, np.ndarray], tuple[bool, float]] | None,
    check_every: int,
    blowup_factor: float,
    dt_crit: float | None,
) -> tuple[Trajectory, bool]:
    """Integrate in place; returns the trajectory and whether ``stop_fn`` stopped it."""
    if integrator not in ("symplectic-euler", "verlet"):
        raise ValueError(f"unknown integrator {integrator!r}; valid: 'symplectic-euler', 'verlet'")
    system = ctx.system
    fixed = ctx.fixed
    has_fixed = fixed.size > 0
    inv_m = 1.0 / ctx.m[:, None]
    s_of = _scale_fn(scale)
    const = not callable(scale)
    xf, vf = x.reshape(-1), v.reshape(-1)
    t0 = 0.0
    s = s_of(t0)
    p_new = system.prescribed(s) if has_fixed else None
    if has_fixed:
        xf[fixed] = p_new
        vf[fixed] = 0.0 if const else (system.prescribed(s_of(t0 + dt)) - p_new) / dt
    verlet = integrator == "verlet"
    decay = np.exp(-alpha * dt * (0.5 if verlet else 1.0)) if alpha else 1.0
    # a = M^-1 f(x_n, v_n), cached: each step needs one force evaluation
    a = ctx.forces(x, v, s) * inv_m
    if has_fixed:
        a.reshape(-1)[fixed] = 0.0

    def kinetic_now() -> float:
        # Symplectic Euler is leapfrog with the stored velocity half a step behind the
        # positions; v + dt/2 a is the velocity at the positions' time (as in Verlet).
        return ctx.kinetic(v if verlet else v + 0.5 * dt * a)

    ke = ctx.kinetic(v)
    monitor = _BlowupMonitor(ctx, n_steps, dt, blowup_factor, ke)
    times, kin, pot = [t0], [kinetic_now()], [ctx.potential(x, s)]
    snapshots: deque = deque([x.copy()], maxlen=3)
    x_prev = x.copy()
    residuals: list[float] = []
    kin_last = ke
    restart = False
    stopped = False
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=n_steps, desc=f"explicit {integrator}", unit="step", mininterval=0.5)
    chunk = max(1, n_steps // 200)
    k = 0
    t = t0
    for k in range(1, n_steps + 1):
        t = t0 + k * dt
        if not const:
            s = s_of(t)
        if has_fixed:
            p_old = xf[fixed].copy()
            p_new = system.prescribed(s) if not const else p_new
            v_fixed = (p_new - p_old) / dt
        x_prev[...] = x
        a_prev = a
        if not verlet:
            # symplectic Euler: kick with f(x_n, v_n), then drift; after a kinetic-damping
            # restart from rest the first kick is a half kick (leapfrog start)
            v += (0.5 * dt if restart else dt) * a
            restart = False
            if alpha:
                v *= decay  # exact solution of dv/dt = -alpha v over dt
            if has_fixed:
                vf[fixed] = v_fixed
            x += dt * v
            if has_fixed:
                xf[fixed] = p_new
            a = ctx.forces(x, v, s) * inv_m
            if has_fixed:
                a.reshape(-1)[fixed] = 0.0
        else:
            if alpha:
                v *= decay  # Strang splitting of the mass damping around the Verlet step
            v += 0.5 * dt * a
            if has_fixed:
                vf[fixed] = v_fixed
            x += dt * v
            if has_fixed:
                xf[fixed] = p_new
            a = ctx.forces(x, v, s) * inv_m
            if has_fixed:
                a.reshape(-1)[fixed] = 0.0
            v += 0.5 * dt * a
            if alpha:
                v *= decay
        ke = ctx.kinetic(v)
        reason = monitor.check(k, ke, x, v, s)
        if reason is not None:
            if bar is not None:
                bar.close()
            err = _blowup_error(ctx, "explicit", k, t, reason, x_prev, x, dt, dt_crit, snapshots[0])
            raise err
        if kinetic_damping and ke < kin_last:
            # Kinetic damping: the kinetic energy peaked about the previous positions (for
            # symplectic Euler the stored velocity is half a step behind): go back there,
            # stop, and restart from rest.
            x[...] = x_prev
            a = a_prev
            v[...] = 0.0
            if has_fixed:
                vf[fixed] = v_fixed
            restart = True
            ke = ctx.kinetic(v)
        kin_last = ke
        system.post_step(x, dt)
        if k % record_every == 0 or k == n_steps:
            times.append(t)
            kin.append(kinetic_now())
            pot.append(ctx.potential(x, s))
            snapshots.append(x.copy())
        if bar is not None and k % chunk == 0:
            bar.update(chunk)
        if callback is not None and callback(k, t, x, v):
            stopped = True
            break
        if stop_fn is not None and k % check_every == 0:
            done = stop_fn(k, t, x)
            residuals.append(done[1])
            if done[0]:
                stopped = True
                break
    if bar is not None:
        bar.close()
    if stopped and times[-1] != t:
        times.append(t)
        kin.append(kinetic_now())
        pot.append(ctx.potential(x, s))
    traj = Trajectory(
        times=np.asarray(times),
        kinetic=np.asarray(kin),
        potential=np.asarray(pot),
        x=x,
        v=v,
        steps=k,
        dt=dt,
        dt_crit=dt_crit,
        integrator=integrator,
        residual_history=residuals,
    )
    return traj, stopped


def _time_step(
    system: MechanicalSystem, dt: float | None, dt_safety: float, scale: Scale
) -> tuple[float, float | None]:
    if dt is not None:
        if not dt > 0:
            raise ValueError(f"dt must be positive, got {dt}")
        return float(dt), None
    s0 = scale(0.0) if callable(scale) else float(scale)
    dt_crit, _ = stable_time_step(system, scale=s0)
    if not np.isfinite(dt_crit):
        raise SolverError(
            "cannot choose a time step: the stiffness has no positive eigenvalue; give dt"
        )
    return dt_safety * dt_crit, dt_crit


def explicit(
    system: MechanicalSystem,
    dt: float | None = None,
    steps: int | None = None,
    t_end: float | None = None,
    integrator: Integrator = "symplectic-euler",
    mass_damping: float = 0.0,
    scale: Scale = 1.0,
    record_every: int | None = None,
    callback: Callable[[int, float, np.ndarray, np.ndarray], bool | None] | None = None,
    progress: bool = False,
    *,
    x_init: np.ndarray | None = None,
    v_init: np.ndarray | None = None,
    dt_safety: float = 0.5,
    blowup_factor: float = 1e4,
) -> Trajectory:
    """Explicit time integration.

    ``symplectic-euler`` (semi-implicit Euler): ``v += dt M^-1 f(x, v); x += dt v``.
    ``verlet`` (velocity Verlet): half kick, drift, force, half kick; velocity-dependent
    forces see the half-step velocity. Mass-proportional damping ``-alpha m v`` is applied
    exactly (``v *= exp(-alpha dt)``, split symmetrically around the Verlet step). The fixed
    DOFs follow ``prescribed(scale(t))``.

    Parameters
    ----------
    system
        The system.
    dt
        Time step; default ``dt_safety * 2 / omega_max`` at the initial state.
    steps, t_end
        Number of steps, or end time (``steps = ceil(t_end / dt)``).
    integrator
        ``symplectic-euler`` or ``verlet``.
    mass_damping
        ``alpha`` (1/s).
    scale
        Load factor, or a function of time (e.g. a ramp).
    record_every
        Record energies every this many steps (default: about 1000 records).
    callback
        ``callback(step, t, x, v)``, called after every step; return ``True`` to stop.
    progress
        Show a tqdm progress bar.
    x_init, v_init
        Initial positions and velocities (default: rest, zero).
    dt_safety
        Fraction of the critical time step used when ``dt`` is ``None``.
    blowup_factor
        A step is a blow-up when its kinetic energy exceeds this factor times the largest
        kinetic energy of the first half of the run so far (a stable run from rest grows
        polynomially, by ``2^p``; an unstable one exponentially) and the velocity field
        oscillates on the unstable time scale (``omega_eff dt >= 1.5``, see
        ``_BlowupMonitor``). Non-finite values are always a blow-up.

    Raises
    ------
    SolverError
        On blow-up: names the step, time, node and element, ``dt`` against the critical
        step; ``state`` holds the positions recorded before the blow-up.
    """
    t_start = time.perf_counter()
    ctx = _Context(system)
    dt, dt_crit = _time_step(system, dt, dt_safety, scale)
    n_steps = _n_steps(dt, steps, t_end)
    x = np.array(ctx.x0 if x_init is None else x_init, dtype=float).reshape(ctx.n, 3)
    v = np.zeros_like(x) if v_init is None else np.array(v_init, dtype=float).reshape(ctx.n, 3)
    record_every = int(record_every) if record_every else max(1, n_steps // 1000)
    traj, _ = _explicit_loop(
        ctx,
        dt=dt,
        n_steps=n_steps,
        integrator=integrator,
        alpha=float(mass_damping),
        scale=scale,
        x=x,
        v=v,
        record_every=record_every,
        callback=callback,
        progress=progress,
        kinetic_damping=False,
        stop_fn=None,
        check_every=1,
        blowup_factor=blowup_factor,
        dt_crit=dt_crit,
    )
    traj.wall_time = time.perf_counter() - t_start
    traj.force_evaluations = ctx.n_evals
    return traj


def explicit_static(
    system: MechanicalSystem,
    tol: float = 1e-8,
    max_steps: int = 200_000,
    dt: float | None = None,
    integrator: Integrator = "symplectic-euler",
    mass_damping: float = 0.0,
    damping: Damping = "auto",
    scale: float = 1.0,
    check_every: int = 10,
    progress: bool = False,
    *,
    x_init: np.ndarray | None = None,
    dt_safety: float = 0.5,
    raise_on_failure: bool = True,
) -> SolveInfo:
    """Equilibrium by damped explicit integration (dynamic relaxation).

    Runs :func:`explicit` with mass damping ``alpha = mass_damping`` or kinetic damping
    (velocities zeroed at every kinetic-energy peak; the default when ``mass_damping`` is
    0) until ``|f_free(x)| < tol * reference_force``, checked every ``check_every`` steps.

    Raises
    ------
    SolverError
        On blow-up, or (``raise_on_failure``) when ``max_steps`` pass without convergence.
    """
    t_start = time.perf_counter()
    ctx = _Context(system)
    s = float(scale)
    if damping == "auto":
        damping = "mass" if mass_damping > 0 else "kinetic"
    if damping not in ("kinetic", "mass"):
        raise ValueError(f"unknown damping {damping!r}; valid: 'auto', 'kinetic', 'mass'")
    if damping == "mass" and not mass_damping > 0:
        raise ValueError("damping='mass' needs mass_damping > 0")
    dt, dt_crit = _time_step(system, dt, dt_safety, s)
    x = constrained_positions(system, s, x_init)
    f_ref = _reference(ctx, s)
    r0 = float(np.linalg.norm(ctx.free_force(x, s))) / f_ref
    if r0 <= tol:
        return SolveInfo(
            x=x, converged=True, iterations=0, residual_history=[r0], load_steps=[s],
            method="dynamic-relaxation", jacobian="none", linear_solver="none",
            wall_time=time.perf_counter() - t_start, reference_force=f_ref, dt=dt,
            force_evaluations=ctx.n_evals,
        )  # fmt: skip

    def stop(k: int, t: float, x: np.ndarray) -> tuple[bool, float]:
        r = float(np.linalg.norm(ctx.free_force(x, s))) / f_ref
        return r <= tol, r

    v = np.zeros_like(x)
    traj, done = _explicit_loop(
        ctx,
        dt=dt,
        n_steps=int(max_steps),
        integrator=integrator,
        alpha=float(mass_damping) if damping == "mass" else 0.0,
        scale=s,
        x=x,
        v=v,
        record_every=max(1, int(max_steps) // 1000),
        callback=None,
        progress=progress,
        kinetic_damping=damping == "kinetic",
        stop_fn=stop,
        check_every=max(1, int(check_every)),
        blowup_factor=1e4,
        dt_crit=dt_crit,
    )
    hist = [r0, *traj.residual_history]
    info = SolveInfo(
        x=traj.x,
        converged=bool(done),
        iterations=traj.steps,
        residual_history=hist,
        load_steps=[s] if done else [],
        method="dynamic-relaxation",
        jacobian="none",
        linear_solver="none",
        wall_time=time.perf_counter() - t_start,
        reference_force=f_ref,
        steps=traj.steps,
        dt=dt,
        force_evaluations=ctx.n_evals,
    )
    if not done:
        info.message = (
            f"dynamic relaxation ({damping} damping) did not reach the tolerance {tol:.3g} in "
            f"{traj.steps} steps: relative residual {hist[-1]:.3g}"
        )
        if raise_on_failure:
            raise SolverError(info.message, state=traj.x)
    return info


def _reference(ctx: _Context, s: float) -> float:
    """Reference force norm (see :func:`springfem.mechanics.system.reference_force`), never 0."""
    x = constrained_positions(ctx.system, s)
    f_ref = float(np.linalg.norm(ctx.free_force(x, s)))
    if f_ref > 0:
        return f_ref
    return 1.0  # unloaded: the rest state is the solution; any scale will do


# --------------------------------------------------------------------------- implicit


def implicit(
    system: MechanicalSystem,
    dt: float | None = None,
    steps: int | None = None,
    t_end: float | None = None,
    mass_damping: float = 0.0,
    scale: Scale = 1.0,
    tol: float = 1e-8,
    max_iter: int = 25,
    record_every: int | None = None,
    callback: Callable[[int, float, np.ndarray, np.ndarray], bool | None] | None = None,
    progress: bool = False,
    *,
    x_init: np.ndarray | None = None,
    v_init: np.ndarray | None = None,
    dt_safety: float = 0.5,
    jacobian: JacobianKind = "auto",
    linear_solver: LinearSolverKind = "auto",
    equilibrium_tol: float | None = None,
    max_substeps: int = 4,
) -> Trajectory:
    """Implicit (backward) Euler.

    Each step solves ``M (v1 - v0) / dt = f(x0 + dt v1, v1) - alpha M v1`` for ``v1`` by
    Newton with the Jacobian ``M (1 + alpha dt) + dt C + dt^2 K`` (``K`` analytic when the
    system has it, else coloured finite differences; ``C = -df/dv`` by finite differences
    when the forces depend on ``v``). Unconditionally stable for linear systems, first order
    and dissipative. A step whose Newton iteration fails is split in halves (up to
    ``max_substeps`` times).

    Parameters
    ----------
    tol
        Newton tolerance on ``|residual| / (|M v0| + dt |f(x0, v0)| + dt reference_force)``.
    equilibrium_tol
        If given, stop early when the static residual ``|f_free(x)| / reference_force``
        falls below it (pseudo-time stepping to equilibrium).

    Other parameters are as in :func:`explicit`.
    """
    t_start = time.perf_counter()
    ctx = _Context(system)
    dt, dt_crit = _time_step(system, dt, dt_safety, scale)
    n_steps = _n_steps(dt, steps, t_end)
    s_of = _scale_fn(scale)
    alpha = float(mass_damping)
    fixed = ctx.fixed
    x = np.array(ctx.x0 if x_init is None else x_init, dtype=float).reshape(ctx.n, 3)
    v = np.zeros_like(x) if v_init is None else np.array(v_init, dtype=float).reshape(ctx.n, 3)
    s = s_of(0.0)
    if fixed.size:
        x.reshape(-1)[fixed] = system.prescribed(s)
        v.reshape(-1)[fixed] = 0.0
    f_ref = _reference(ctx, s_of(n_steps * dt))
    length = characteristic_length(ctx.x0, ctx.tets)
    damped = ctx.has_damping(x, s, length / dt)
    record_every = int(record_every) if record_every else max(1, n_steps // 1000)
    times, kin, pot = [0.0], [ctx.kinetic(v)], [ctx.potential(x, s)]
    hist: list[float] = []
    total_iters = 0
    snapshots: deque = deque([x.copy()], maxlen=3)

    def step(x0: np.ndarray, v0: np.ndarray, t0: float, h: float, depth: int):
        """One backward-Euler step of size h, split on failure; returns x1, v1, its, r."""
        x1, v1, its, r, ok = _backward_euler_step(
            ctx, x0, v0, h, s_of(t0 + h), alpha, tol, max_iter, damped, length,
            f_ref, jacobian, linear_solver,
        )  # fmt: skip
        if ok or depth >= max_substeps:
            return x1, v1, its, r, ok
        xa, va, ia, _, oka = step(x0, v0, t0, 0.5 * h, depth + 1)
        if not oka:
            return xa, va, its + ia, r, False
        xb, vb, ib, rb, okb = step(xa, va, t0 + 0.5 * h, 0.5 * h, depth + 1)
        return xb, vb, its + ia + ib, rb, okb

    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=n_steps, desc="implicit Euler", unit="step", mininterval=0.5)
    k, t = 0, 0.0
    converged = True
    message = ""
    for k in range(1, n_steps + 1):
        t0, t = t, k * dt
        x_new, v_new, its, r, ok = step(x, v, t0, dt, 0)
        total_iters += its
        hist.append(r)
        if not ok:
            if bar is not None:
                bar.close()
            finite = np.isfinite(x_new).all() and np.isfinite(v_new).all()
            reason = (
                f"Newton did not converge (relative residual {r:.3g} after {max_iter} "
                f"iterations, {max_substeps} step halvings)"
                if finite
                else "non-finite state"
            )
            raise _blowup_error(ctx, "implicit", k, t, reason, x, x_new, dt, dt_crit, snapshots[0])
        x, v = x_new, v_new
        s = s_of(t)
        system.post_step(x, dt)
        if k % record_every == 0 or k == n_steps:
            times.append(t)
            kin.append(ctx.kinetic(v))
            pot.append(ctx.potential(x, s))
            snapshots.append(x.copy())
        if bar is not None:
            bar.update(1)
        if callback is not None and callback(k, t, x, v):
            break
        if equilibrium_tol is not None:
            r_static = float(np.linalg.norm(ctx.free_force(x, s))) / f_ref
            if r_static <= equilibrium_tol:
                message = f"equilibrium reached at step {k}: relative residual {r_static:.3g}"
                break
    if bar is not None:
        bar.close()
    if times[-1] != t:
        times.append(t)
        kin.append(ctx.kinetic(v))
        pot.append(ctx.potential(x, s))
    if equilibrium_tol is not None and not message:
        converged = False
        message = f"equilibrium not reached in {k} steps"
    return Trajectory(
        times=np.asarray(times),
        kinetic=np.asarray(kin),
        potential=np.asarray(pot),
        x=x,
        v=v,
        steps=k,
        dt=dt,
        dt_crit=dt_crit,
        integrator="backward-euler",
        converged=converged,
        wall_time=time.perf_counter() - t_start,
        iterations=total_iters,
        residual_history=hist,
        force_evaluations=ctx.n_evals,
        message=message,
    )


def _backward_euler_step(
    ctx: _Context,
    x0: np.ndarray,
    v0: np.ndarray,
    dt: float,
    s: float,
    alpha: float,
    tol: float,
    max_iter: int,
    damped: bool,
    length: float,
    f_ref: float,
    jacobian: JacobianKind,
    linear_solver: LinearSolverKind,
):
    system = ctx.system
    fixed, free = ctx.fixed, ctx.free
    Mf = ctx.m_dof[free]
    x1, v1 = x0.copy(), v0.copy()
    x1f, v1f, x0f, v0f = x1.reshape(-1), v1.reshape(-1), x0.reshape(-1), v0.reshape(-1)
    if fixed.size:
        p = system.prescribed(s)
        v1f[fixed] = (p - x0f[fixed]) / dt
        x1f[fixed] = p
    x1f[free] = x0f[free] + dt * v1f[free]

    def residual() -> np.ndarray:
        f = ctx.forces(x1, v1, s).reshape(-1)[free]
        return Mf * ((1.0 + dt * alpha) * v1f[free] - v0f[free]) - dt * f

    g = residual()
    f0 = ctx.forces(x0, v0, s).reshape(-1)[free]
    g_ref = float(np.linalg.norm(Mf * v0f[free]) + dt * np.linalg.norm(f0) + dt * f_ref)
    g_ref = g_ref if g_ref > 0 else 1.0
    r = float(np.linalg.norm(g)) / g_ref
    solver = None
    analytic = True
    ratio = 1.0
    its = 0
    B = rigid_body_modes(ctx.x0)[free]
    for its in range(1, max_iter + 1):  # noqa: B007 - its is reported
        if not np.isfinite(r):
            return x1, v1, its, r, False
        if r <= tol:
            return x1, v1, its - 1, r, True
        # Full Newton with an analytic tangent; with finite differences the factorised
        # Jacobian is reused while it contracts well (r drops at least twofold).
        if solver is None or analytic or ratio > 0.5:
            K = ctx.stiffness(x1, s, jacobian)
            analytic = ctx.jacobian_kind == "analytic"
            J = sp.diags(Mf * (1.0 + dt * alpha)) + dt * dt * ctx.ff(K)
            if damped:
                J = J + dt * ctx.ff(ctx.damping_matrix(x1, s, length / dt))
            solver = LinearSolver(J, linear_solver, B)
        try:
            dv = solver.solve(-g)
        except SolverError:
            return x1, v1, its, r, False
        _note(ctx, solver.name)
        v1f[free] += dv
        x1f[free] = x0f[free] + dt * v1f[free]
        g_new = residual()
        r_new = float(np.linalg.norm(g_new)) / g_ref
        ratio = r_new / r if r > 0 else 0.0
        g, r = g_new, r_new
    return x1, v1, max_iter, r, bool(np.isfinite(r) and r <= tol)


def _note(ctx: _Context, name: str) -> None:
    if name != "none" and name not in ctx.solvers_used:
        ctx.solvers_used.append(name)


# ----------------------------------------------------------------------------- static


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
    line_search: bool = True,
    predictor: bool = True,
    max_cutbacks: int = 8,
    fallback: bool = True,
    dr_max_steps: int = 200_000,
    raise_on_failure: bool = True,
    callback: Callable[[int, float, np.ndarray, float], None] | None = None,
) -> SolveInfo:
    """Static equilibrium ``f_free(x) = 0`` by Newton's method with load stepping.

    Each load step solves ``K dx = f`` on the free DOFs (``K`` analytic if the system has it,
    else coloured finite differences, non-symmetric for non-gradient forces) with
    :func:`solve_linear` and a backtracking line search: Armijo on the energy when the
    system has one and the step descends it, else on the residual norm. A step that does
    not converge in ``max_iter`` iterations is cut in half and retried (up to
    ``max_cutbacks`` times in a row); the increment grows back after easy steps. When
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
    callback
        ``callback(iteration, load_factor, x, relative_residual)`` after every iteration.

    Raises
    ------
    SolverError
        Rigid-body modes not stopped by the constraints ("singular stiffness: ..."), a
        singular tangent at rest, or no convergence (``raise_on_failure``); ``state`` holds
        the last converged positions.
    """
    t_start = time.perf_counter()
    ctx = _Context(system)
    check_constrained(system)
    target = float(scale)
    f_ref = _reference(ctx, target)
    B = rigid_body_modes(ctx.x0)[ctx.free]
    x_conv = np.array(ctx.x0 if x_init is None else x_init, dtype=float).reshape(ctx.n, 3)
    # load fractions lam in [0, 1]; the load factor is lam * target
    lam_conv = 0.0
    nominal = 1.0 / max(1, int(load_steps))
    dlam = nominal
    hist: list[float] = []
    steps_done: list[float] = []
    total_its = 0
    cutbacks = 0
    in_a_row = 0
    last_reason = ""
    K_conv: sp.csr_matrix | None = None
    method = "newton"
    notes: list[str] = []

    while lam_conv < 1.0 - 1e-12 or not steps_done:
        lam_new = min(1.0, lam_conv + dlam)
        s_new = lam_new * target
        x = x_conv.copy()
        xf = x.reshape(-1)
        if ctx.fixed.size:
            dp = system.prescribed(s_new) - xf[ctx.fixed]
            xf[ctx.fixed] += dp
            if predictor and np.any(dp != 0):
                # tangent predictor: move the free DOFs with the prescribed ones
                try:
                    K = sp.csr_matrix(
                        K_conv
                        if K_conv is not None
                        else ctx.stiffness(x_conv, lam_conv * target, jacobian)
                    )
                    rhs = -(K[ctx.free][:, ctx.fixed] @ dp)
                    dxf, name = solve_linear(ctx.ff(K), rhs, linear_solver, B)
                    _note(ctx, name)
                    xf[ctx.free] += dxf
                except SolverError:
                    if not steps_done:
                        raise SolverError(
                            f"{SINGULAR_MESSAGE} or the springs leave a mechanism: the "
                            "tangent stiffness at rest is singular",
                            state=x_conv,
                        ) from None
        ok, x, its, h, reason, K_last = _newton(
            ctx, x, s_new, f_ref, tol, max_iter, line_search, jacobian, linear_solver, B,
            callback, total_its,
        )  # fmt: skip
        total_its += its
        hist.extend(h)
        if ok:
            if reason:
                notes.append(f"load factor {s_new:.4g}: {reason}")
            x_conv, lam_conv, K_conv = x, lam_new, K_last
            steps_done.append(s_new)
            in_a_row = 0
            if its <= 4:
                dlam = min(2 * dlam, nominal)  # easy step: grow back
            continue
        last_reason = reason
        if (
            reason.startswith("singular tangent at iteration 1 ")
            and not steps_done
            and (in_a_row == 0)
        ):
            raise SolverError(
                f"{SINGULAR_MESSAGE} or the springs leave a mechanism: {reason}", state=x_conv
            )
        cutbacks += 1
        in_a_row += 1
        dlam *= 0.5
        # give up after max_cutbacks halvings in a row, or when the increment has shrunk
        # below nominal / 2^max_cutbacks (creeping towards a limit load)
        if in_a_row > max_cutbacks or dlam < nominal * 0.5**max_cutbacks:
            break
    converged = bool(steps_done) and lam_conv >= 1.0 - 1e-12
    s_conv = lam_conv * target
    x_final = x_conv
    steps = 0
    dt = None
    message = "; ".join(notes)
    if not converged:
        message = (
            f"{message + '; ' if message else ''}Newton failed at load factor "
            f"{min(1.0, lam_conv + 2 * dlam) * target:.4g} after {cutbacks} cut-backs "
            f"({last_reason}); last converged load factor {s_conv:.4g}"
        )
        if fallback:
            try:
                dr = explicit_static(
                    system, tol=tol, max_steps=dr_max_steps, scale=target, x_init=x_conv,
                    raise_on_failure=False,
                )  # fmt: skip
            except SolverError as err:
                dr = None
                message += f"; dynamic relaxation blew up: {err}"
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
                    message += f"; {dr.message}"
        if not converged and raise_on_failure:
            raise SolverError(f"static solve did not converge: {message}", state=x_conv)
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


def _newton(
    ctx: _Context,
    x: np.ndarray,
    s: float,
    f_ref: float,
    tol: float,
    max_iter: int,
    line_search: bool,
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
            solver = LinearSolver(ctx.ff(K), linear_solver, B)
            dx = solver.solve(R)
        except SolverError as err:
            return False, x, it, hist, f"singular tangent at iteration {it} ({err})", K
        _note(ctx, solver.name)
        dx_norm = float(np.linalg.norm(dx))
        corrections.append(dx_norm)
        e0 = system.energy(x, s) if line_search else None
        slope = float(R @ dx)  # -dPi/dalpha at alpha = 0 (f = -grad Pi)
        use_energy = e0 is not None and slope > 0
        alpha = 1.0
        accepted = False
        for _ in range(12 if line_search else 1):
            x_try = x.copy()
            x_try.reshape(-1)[free] = xf[free] + alpha * dx
            R_try = ctx.free_force(x_try, s)
            r_try = float(np.linalg.norm(R_try)) / f_ref
            if not line_search:
                accepted = bool(np.isfinite(r_try))
            elif np.isfinite(r_try):
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
