"""The per-solve view of a :class:`~springfem.mechanics.system.MechanicalSystem` that every
solver works through: free and fixed DOFs, masses, forces with an evaluation count, the
tangent (analytic or coloured finite differences), and the location of a failure (node,
element, edge strain) for the error messages.

Examples
--------
>>> import numpy as np
>>> from springfem.mechanics.toy import Oscillator
>>> ctx = SolveContext(Oscillator())
>>> ctx.free.tolist()
[9]
>>> reference_norm(ctx, 1.0)
1.0
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Literal

import numpy as np
import scipy.sparse as sp

from ..errors import SolverError
from .fd_jacobian import ColoredJacobian
from .limits import LIMITS, SolveStopped, cap_reason
from .system import MechanicalSystem, constrained_positions, free_dofs

JacobianKind = Literal["auto", "analytic", "fd"]
#: Fraction of the prescribed displacement of the central difference in :func:`reference_norm`.
LINEARISATION_STEP = 1e-4
#: The linearised reference is used only above this fraction of the external load's norm.
CANCELLATION_FLOOR = 1e-3
Scale = float | Callable[[float], float]

_TET_EDGES = np.array([(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)])


class SolveContext:
    """Per-solve view of a system: DOF sets, masses, Jacobians, force-evaluation count.

    Parameters
    ----------
    system
        The :class:`~springfem.mechanics.system.MechanicalSystem` being solved.

    Attributes
    ----------
    x0, n, fixed, free, m, m_dof, tets
        Rest positions ``(n, 3)``, node count, fixed and free DOFs, nodal and per-DOF
        masses, element connectivity.
    n_evals
        Force evaluations so far.
    jacobian_kind
        ``analytic``, ``fd`` or ``none``: how the last tangent was computed.
    solvers_used
        Names of the linear solvers used so far, in order of first use.
    """

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
        self.start = time.monotonic()
        max_time = LIMITS["max_time"]
        self.max_time = max_time
        self.why = cap_reason(max_time)
        self.deadline = None if max_time is None else self.start + float(max_time)
        self.max_steps = LIMITS["max_steps"]
        self.step = 0  # time steps taken (set by the time-stepping loops)
        self.f_ref: float | None = None  # set by reference_norm

    # forces / energies
    def forces(self, x: np.ndarray, v: np.ndarray | None, s: float) -> np.ndarray:
        """Nodal forces ``(n, 3)`` at positions ``x``, velocities ``v``, load factor ``s``.

        Raises :class:`SolveStopped` past the deadline or step cap of :func:`solve_limits`.
        """
        self.n_evals += 1
        f = np.asarray(self.system.forces(x, v, s), dtype=float).reshape(self.n, 3)
        if self.n_evals == 1 and self.max_time is not None:
            # the clock starts after the first evaluation, which compiles the kernels once
            self.start = time.monotonic()
            self.deadline = self.start + float(self.max_time)
        elif self.deadline is not None or self.max_steps is not None:
            self.check_limits(x, f)
        return f

    def check_limits(self, x: np.ndarray, f: np.ndarray) -> None:
        """Raise :class:`SolveStopped` when the time or step cap is passed.

        Parameters
        ----------
        x, f
            The positions and the forces just evaluated there (for the message and state).
        """
        now = time.monotonic()
        late = self.deadline is not None and now > self.deadline
        many = self.max_steps is not None and self.step > self.max_steps
        if not (late or many):
            return
        r = float(np.linalg.norm(f.reshape(-1)[self.free]))
        res = f"relative residual {r / self.f_ref:.3g}" if self.f_ref else f"residual {r:.3g} N"
        # the loops set ``step`` before evaluating its forces: ``step - 1`` are complete
        what = f"{self.step - 1} steps" if self.step else f"{self.n_evals} force evaluations"
        cap = self.why if late else f"the cap of {self.max_steps} steps"
        raise SolveStopped(
            f"stopped after {now - self.start:.3g} s / {what} at {res} ({cap})",
            state=np.array(x, dtype=float).reshape(self.n, 3),
        )

    def free_force(self, x: np.ndarray, s: float) -> np.ndarray:
        """Forces on the free DOFs (flat)."""
        return self.forces(x, None, s).reshape(-1)[self.free]

    def potential(self, x: np.ndarray, s: float) -> float:
        """Potential energy, NaN when the system has none."""
        e = self.system.energy(x, s)
        return float("nan") if e is None else float(e)

    def kinetic(self, v: np.ndarray) -> float:
        """Kinetic energy ``1/2 v.M v``."""
        return 0.5 * float(np.einsum("i,ij,ij->", self.m, v, v))

    # Jacobians
    @property
    def coloring(self) -> ColoredJacobian:
        """The coloured finite-difference Jacobian of the mesh (built on first use)."""
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
        """The free-free block of a ``3n x 3n`` matrix."""
        K = sp.csr_matrix(K)
        return K[self.free][:, self.free]

    # location of a failure
    def node_tets(self, node: int) -> np.ndarray:
        """Elements that contain ``node``."""
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
        """Shortest rest edge from ``node`` to another node of its elements."""
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


def scale_function(scale: Scale) -> Callable[[float], float]:
    """The load factor as a function of time.

    Parameters
    ----------
    scale
        A constant load factor, or a function of time.

    Returns
    -------
    callable
        ``t -> scale(t)``.
    """
    if callable(scale):
        return scale
    s = float(scale)
    return lambda t: s


def number_of_steps(dt: float, steps: int | None, t_end: float | None) -> int:
    """Time steps to take: ``steps``, else ``ceil(t_end / dt)``.

    Parameters
    ----------
    dt
        Time step.
    steps, t_end
        Number of steps or end time (one of them).

    Returns
    -------
    int
        The number of steps.
    """
    if steps is not None:
        return int(steps)
    if t_end is not None:
        return max(1, int(np.ceil(t_end / dt - 1e-9)))
    raise ValueError("give steps or t_end")


def reference_norm(ctx: SolveContext, s: float) -> float:
    """The load being balanced: ``|f_free|`` at the rest positions with prescribed DOFs.

    See :func:`springfem.mechanics.system.reference_force`; an unloaded system gives 1
    (the rest state is the solution; any scale will do). With prescribed displacements it
    is the smaller of that force and its linearisation at rest, ``|f_ext + K_fc d|`` (a
    central difference of the forces along the prescribed displacement ``d``): a layer of
    elements at the constrained boundary strained by the whole ``d`` at once can carry a
    far larger force than the solution does in a stiffening law (an exponential spring
    element: ``e^14`` times at 30 % stretch of a 3-element cube, not finite on a finer one),
    which would loosen the tolerance by as much. The linearisation is not used when it is
    below :data:`CANCELLATION_FLOOR` of the external load (a load the prescribed
    displacements' reaction cancels gives no scale).

    Parameters
    ----------
    ctx
        The solve context.
    s
        Load factor.

    Returns
    -------
    float
        The reference force norm, never 0.

    Raises
    ------
    SolverError
        Neither the force nor its linearisation is finite.
    """
    x = constrained_positions(ctx.system, s)
    f_ref = float(np.linalg.norm(ctx.free_force(x, s)))
    x0 = np.asarray(ctx.system.x0, dtype=float).reshape(ctx.n, 3)
    d = x - x0
    if np.any(d != 0.0):
        h = LINEARISATION_STEP
        f_ext = ctx.free_force(x0, s)
        kd = (ctx.free_force(x0 + h * d, s) - ctx.free_force(x0 - h * d, s)) / (2 * h)
        f_lin = float(np.linalg.norm(f_ext + kd))
        # a load cancelled by the prescribed displacements' reaction is no scale: floor
        usable = np.isfinite(f_lin) and f_lin >= CANCELLATION_FLOOR * np.linalg.norm(f_ext)
        if usable and f_lin > 0 and (f_lin < f_ref or not np.isfinite(f_ref)):
            f_ref = f_lin
    if not np.isfinite(f_ref):
        raise SolverError(
            "the load is not finite at the rest positions with the prescribed displacements "
            "(nor its linearisation): no scale for the static tolerance",
            state=x0,
        )
    ctx.f_ref = f_ref if f_ref > 0 else 1.0
    return ctx.f_ref


def note_solver(ctx: SolveContext, name: str) -> None:
    """Record a linear solver's name in ``ctx.solvers_used`` (once).

    Parameters
    ----------
    ctx
        The solve context.
    name
        ``direct``, ``cg+amg``, ``gmres+amg`` (``none`` is ignored).

    Returns
    -------
    None
    """
    if name != "none" and name not in ctx.solvers_used:
        ctx.solvers_used.append(name)


def reference_force(system: MechanicalSystem, scale: float = 1.0) -> float:
    """The load the body must balance, which static tolerances are relative to.

    The norm of the free-DOF force at the rest positions with the fixed DOFs prescribed
    (external forces times ``scale`` plus the internal reaction to the prescribed
    displacements), or its linearisation when that is smaller: see
    :func:`reference_norm`, which the solvers call.

    Parameters
    ----------
    system
        The system.
    scale
        Load factor.

    Returns
    -------
    float
        The norm (1 for an unloaded system).
    """
    return reference_norm(SolveContext(system), scale)
