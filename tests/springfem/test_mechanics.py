"""Solvers and coloured finite-difference Jacobians on independent test systems.

The systems here are springs on the edges of a tet mesh (exact energy, analytic tangent),
written in this file so the solver tests do not depend on the spring-model forces. Every
test compares with something independent: closed-form oscillators, dense eigenvalues,
direct sparse solves, invariants (energy), or convergence rates fitted with ``polyfit``.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from springfem.errors import SolverError
from springfem.mechanics import (
    SolveInfo,
    Trajectory,
    explicit,
    explicit_static,
    implicit,
    stable_time_step,
    static,
)
from springfem.mechanics.fd_jacobian import ColoredJacobian, distance2_coloring, fd_jacobian
from springfem.mechanics.system import MechanicalSystem, node_adjacency
from springfem.mesh import box_mesh
from springmodel.options import SpringOptions
from springmodel.solve import solve_with_options

EDGES = np.array([(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)])


class EdgeSprings:
    """Linear-law springs on mesh edges, geometrically exact (or linearised at rest).

    Spring ``(i, j)``: ``f_i = k (l - L0) d / l`` with ``d = x_j - x_i``, ``f_j = -f_i``;
    energy ``k/2 (l - L0)^2``. Optional relative damping along the spring
    ``c ((v_j - v_i) . e) e``, a dead load ``f_ext * scale``, prescribed displacements
    ``u_presc * scale`` and a circulatory (non-gradient) load ``q * scale * e_z x (x - c)``.
    """

    def __init__(
        self,
        points: np.ndarray,
        tets: np.ndarray,
        fixed_dofs: np.ndarray,
        k: np.ndarray | float = 1.0,
        masses: np.ndarray | None = None,
        f_ext: np.ndarray | None = None,
        u_presc: np.ndarray | None = None,
        edges: np.ndarray | None = None,
        linear: bool = False,
        analytic: bool = True,
        damping: float = 0.0,
        circulation: float = 0.0,
    ):
        self.x0 = np.asarray(points, dtype=float)
        n = self.x0.shape[0]
        self.tets = np.asarray(tets, dtype=np.int64)
        if edges is None:
            e = np.sort(self.tets[:, EDGES].reshape(-1, 2), axis=1)
            edges = np.unique(e, axis=0)
            edges = edges[edges[:, 0] != edges[:, 1]]
        self.i, self.j = edges[:, 0], edges[:, 1]
        self.L0 = np.linalg.norm(self.x0[self.j] - self.x0[self.i], axis=1)
        self.k = np.broadcast_to(np.asarray(k, dtype=float), self.L0.shape).copy()
        self.masses = np.ones(n) if masses is None else np.asarray(masses, dtype=float)
        self.fixed_dofs = np.asarray(fixed_dofs, dtype=np.int64)
        self.f_ext = np.zeros((n, 3)) if f_ext is None else np.asarray(f_ext, dtype=float)
        self.u_presc = np.zeros(self.fixed_dofs.size) if u_presc is None else u_presc
        self.linear = linear
        self.analytic = analytic
        self.damping = damping
        self.circulation = circulation
        self.centre = self.x0.mean(axis=0)
        self.K0 = self._assemble(self.x0)

    def _assemble(self, x: np.ndarray) -> sp.csr_matrix:
        d = x[self.j] - x[self.i]
        l = np.linalg.norm(d, axis=1)
        e = d / l[:, None]
        ee = e[:, :, None] * e[:, None, :]
        ke = self.k[:, None, None] * (ee + (1 - self.L0 / l)[:, None, None] * (np.eye(3) - ee))
        n3 = 3 * self.x0.shape[0]
        r = np.arange(3)
        rows, cols, vals = [], [], []
        for a, b, sgn in ((self.i, self.i, 1), (self.j, self.j, 1), (self.i, self.j, -1),
                          (self.j, self.i, -1)):  # fmt: skip
            shape = (a.size, 3, 3)
            rows.append(np.broadcast_to(3 * a[:, None, None] + r[None, :, None], shape))
            cols.append(np.broadcast_to(3 * b[:, None, None] + r[None, None, :], shape))
            vals.append(sgn * ke)
        return sp.csr_matrix(
            (np.concatenate([v.ravel() for v in vals]),
             (np.concatenate([v.ravel() for v in rows]),
              np.concatenate([v.ravel() for v in cols]))),
            shape=(n3, n3),
        )  # fmt: skip

    def prescribed(self, scale: float) -> np.ndarray:
        return self.x0.reshape(-1)[self.fixed_dofs] + scale * self.u_presc

    def forces(self, x, v=None, scale=1.0):
        x = np.asarray(x, dtype=float).reshape(-1, 3)
        if self.linear:
            f = -(self.K0 @ (x - self.x0).reshape(-1)).reshape(-1, 3)
            e = self.x0[self.j] - self.x0[self.i]
            e = e / np.linalg.norm(e, axis=1)[:, None]
        else:
            d = x[self.j] - x[self.i]
            l = np.linalg.norm(d, axis=1)
            e = d / l[:, None]
            g = (self.k * (l - self.L0))[:, None] * e
            f = np.zeros_like(x)
            np.add.at(f, self.i, g)
            np.add.at(f, self.j, -g)
        if v is not None and self.damping:
            v = np.asarray(v).reshape(-1, 3)
            g = self.damping * np.einsum("ij,ij->i", v[self.j] - v[self.i], e)[:, None] * e
            np.add.at(f, self.i, g)
            np.add.at(f, self.j, -g)
        f += scale * self.f_ext
        if self.circulation:
            r = x - self.centre
            f += scale * self.circulation * np.column_stack([-r[:, 1], r[:, 0], 0 * r[:, 0]])
        return f

    def energy(self, x, scale=1.0):
        if self.circulation:
            return None
        x = np.asarray(x, dtype=float).reshape(-1, 3)
        u = (x - self.x0).reshape(-1)
        work = scale * float(self.f_ext.reshape(-1) @ u)
        if self.linear:
            return 0.5 * float(u @ (self.K0 @ u)) - work
        l = np.linalg.norm(x[self.j] - x[self.i], axis=1)
        return 0.5 * float(np.sum(self.k * (l - self.L0) ** 2)) - work

    def stiffness(self, x, scale=1.0):
        if not self.analytic or self.circulation:
            return None
        return self.K0.copy() if self.linear else self._assemble(np.asarray(x).reshape(-1, 3))

    def element_nodes(self):
        return self.tets

    def post_step(self, x, dt):
        pass


def beam(
    divisions=(6, 2, 2),
    size=(3.0, 1.0, 1.0),
    seed=0,
    load=(0.0, 0.0, 0.0),
    stiff_edges_near=None,
    **kw,
) -> EdgeSprings:
    """An irregular box of edge springs, clamped at x = 0, dead load on the x = max face."""
    rng = np.random.default_rng(seed)
    mesh = box_mesh(size, divisions, split="six")
    h = min(s / d for s, d in zip(size, divisions))
    pts = mesh.points + rng.uniform(-0.15, 0.15, mesh.points.shape) * h  # keeps orientation
    n = pts.shape[0]
    clamp = np.flatnonzero(mesh.points[:, 0] < 1e-9)
    tip = np.flatnonzero(mesh.points[:, 0] > size[0] - 1e-9)
    fixed = (3 * clamp[:, None] + np.arange(3)).ravel()
    f_ext = np.zeros((n, 3))
    f_ext[tip] = np.asarray(load) / tip.size
    vol = np.abs(np.linalg.det(pts[mesh.tets[:, 1:]] - pts[mesh.tets[:, :1]])) / 6
    masses = np.zeros(n)
    np.add.at(masses, mesh.tets, vol[:, None] / 4)
    sys = EdgeSprings(pts, mesh.tets, fixed, masses=masses, f_ext=f_ext, **kw)
    sys.k = (1.0 + 0.3 * rng.uniform(-1, 1, sys.k.size)) / sys.L0
    if stiff_edges_near is not None:  # a weak spot for explicit stability: one stiff tet
        t = mesh.tets[stiff_edges_near]
        on = np.isin(sys.i, t) & np.isin(sys.j, t)
        sys.k[on] *= 30.0
    sys.K0 = sys._assemble(sys.x0)
    return sys


def chain(k1=3.0, k2=2.0, m1=1.5, m2=0.5, masses_only_x=True, **kw) -> EdgeSprings:
    """Node 0 fixed, springs 0-1 and 1-2 along x; only the x motion of nodes 1, 2 is free."""
    pts = np.array([[0.0, 0, 0], [1.0, 0, 0], [2.0, 0, 0]])
    tets = np.array([[0, 1, 1, 1], [1, 2, 2, 2]])  # degenerate "elements": the coupling pattern
    fixed = np.array([0, 1, 2, 4, 5, 7, 8])
    return EdgeSprings(
        pts, tets, fixed, k=np.array([k1, k2]), masses=np.array([1.0, m1, m2]),
        edges=np.array([[0, 1], [1, 2]]), **kw,
    )  # fmt: skip


def oscillator(k=4.0, m=0.25, **kw) -> EdgeSprings:
    """One free DOF: mass m on a spring k (omega = sqrt(k / m))."""
    pts = np.array([[0.0, 0, 0], [1.0, 0, 0]])
    return EdgeSprings(
        pts, np.array([[0, 1, 1, 1]]), np.array([0, 1, 2, 4, 5]), k=k,
        masses=np.array([1.0, m]), edges=np.array([[0, 1]]), **kw,
    )  # fmt: skip


def free_block(sys: EdgeSprings, K: sp.spmatrix) -> tuple[np.ndarray, sp.csr_matrix]:
    free = np.setdiff1d(np.arange(3 * sys.x0.shape[0]), sys.fixed_dofs)
    return free, sp.csr_matrix(K)[free][:, free]


def random_displacement(sys: EdgeSprings, amp: float, seed: int = 1) -> np.ndarray:
    x = sys.x0 + amp * np.random.default_rng(seed).standard_normal(sys.x0.shape)
    x.reshape(-1)[sys.fixed_dofs] = sys.prescribed(1.0)
    return x


def test_test_system_is_consistent():
    """The test system itself: analytic K = -df/dx (central differences) and f = -dE/dx."""
    sys = beam(load=(0, 0, -0.1))
    assert isinstance(sys, MechanicalSystem)
    x = random_displacement(sys, 0.05)
    K = sys.stiffness(x).toarray()
    h = 1e-6
    for dof in (40, 77, 101):
        xp, xm = x.copy(), x.copy()
        xp.reshape(-1)[dof] += h
        xm.reshape(-1)[dof] -= h
        col = -(sys.forces(xp) - sys.forces(xm)).reshape(-1) / (2 * h)
        assert np.allclose(K[:, dof], col, atol=1e-7 * np.abs(K).max())
        dE = (sys.energy(xp) - sys.energy(xm)) / (2 * h)
        assert dE == pytest.approx(-sys.forces(x).reshape(-1)[dof], abs=1e-7)


# ------------------------------------------------------------------------------ colouring


def test_distance2_coloring_separates_nodes_within_two_elements():
    mesh = box_mesh((1.0, 1.0, 1.0), (4, 3, 3), split="six")
    n = mesh.n_points
    colors = distance2_coloring(mesh.tets, n)
    A = node_adjacency(mesh.tets, n).astype(np.int64)
    A2 = (A @ A).toarray() > 0  # distance <= 2 (A has its diagonal)
    i, j = np.nonzero(np.triu(A2, 1))
    assert np.all(colors[i] != colors[j])
    assert colors.max() + 1 < n / 2  # far fewer colours than nodes


def test_fd_jacobian_equals_analytic_stiffness_with_few_evaluations():
    sys = beam(divisions=(8, 3, 3), load=(0, 0, -0.1))
    n = sys.x0.shape[0]
    x = random_displacement(sys, 0.05)  # a deformed, non-trivial state
    K = sys.stiffness(x)
    calls = []

    def f(y):
        calls.append(1)
        return sys.forces(y)

    Kfd = fd_jacobian(f, x, sys.tets)
    cj = ColoredJacobian(sys.tets, n)
    # central differences with h = u^(1/3) L: ~1e-10 relative; 1e-6 is the brief's bound
    assert spla.norm(Kfd - K) / spla.norm(K) < 1e-6
    assert len(calls) == 6 * cj.n_colors == cj.n_evaluations("central")
    assert len(calls) < 0.5 * 3 * n  # central differences over every column would be 6n
    assert Kfd.nnz == 9 * node_adjacency(sys.tets, n).nnz  # pattern: adjacency (x) 3x3
    # forward differences: first order, ~sqrt(u) relative
    calls.clear()
    Kfw = fd_jacobian(f, x, sys.tets, scheme="forward")
    assert spla.norm(Kfw - K) / spla.norm(K) < 1e-5
    assert len(calls) == 3 * cj.n_colors + 1


# ------------------------------------------------------------------------- critical step


def test_stable_time_step_two_mass_chain_closed_form():
    k1, k2, m1, m2 = 3.0, 2.0, 1.5, 0.5
    sys = chain(k1, k2, m1, m2)
    a = (k1 + k2) / m1 + k2 / m2
    b = k1 * k2 / (m1 * m2)
    omega = np.sqrt((a + np.sqrt(a * a - 4 * b)) / 2)
    dt_crit, om = stable_time_step(sys)
    assert om == pytest.approx(omega, rel=1e-12)
    assert dt_crit == pytest.approx(2 / omega, rel=1e-12)
    sys.analytic = False  # coloured FD tangent instead
    assert stable_time_step(sys)[1] == pytest.approx(omega, rel=1e-8)


@pytest.mark.parametrize("divisions", [(4, 2, 2), (13, 3, 3)])  # dense; Lanczos (624 DOFs)
def test_stable_time_step_matches_dense_generalised_eigenvalues(divisions):
    sys = beam(divisions=divisions)
    x = random_displacement(sys, 0.03)
    free, Kff = free_block(sys, sys.stiffness(x))
    d = 1 / np.sqrt(np.repeat(sys.masses, 3)[free])
    A = d[:, None] * Kff.toarray() * d[None, :]  # K phi = w^2 M phi with diagonal M
    lam = scipy.linalg.eigvalsh(A, subset_by_index=[A.shape[0] - 1] * 2)[0]
    assert stable_time_step(sys, x)[1] == pytest.approx(np.sqrt(lam), rel=1e-8)
    sys.analytic = False
    assert stable_time_step(sys, x)[1] == pytest.approx(np.sqrt(lam), rel=1e-7)


# ------------------------------------------------------------------------------ explicit


@pytest.mark.parametrize("integrator", ["symplectic-euler", "verlet"])
def test_explicit_conserves_energy(integrator):
    """Nonlinear springs, no damping, 1e4 steps: |E - E0| / E0 < 1e-3, no drift."""
    sys = beam(divisions=(4, 2, 2))
    x = sys.x0.copy()
    s = sys.x0[:, 0] / sys.x0[:, 0].max()
    x[:, 2] += 0.15 * s**2  # a smooth bend (large enough to be nonlinear)
    dt_crit, _ = stable_time_step(sys, x)
    traj = explicit(sys, dt=0.05 * dt_crit, steps=10_000, integrator=integrator, x_init=x,
                    record_every=10)  # fmt: skip
    E = traj.total_energy
    assert isinstance(traj, Trajectory) and traj.steps == 10_000 and len(E) == 1001
    assert traj.potential[0] > 0 and np.abs(E - E[0]).max() / E[0] < 1e-3
    # no secular drift: mean error in the last tenth no larger than in the first tenth (x2)
    err = np.abs(E - E[0])
    assert err[-100:].mean() <= 2 * err[1:101].mean() + 1e-12 * E[0]


def _oscillator_error(integrator, n_per_period, alpha=0.0):
    k, m, A = 4.0, 0.25, 0.01
    sys = oscillator(k, m, linear=True)
    omega = np.sqrt(k / m)
    T = 2 * np.pi / omega
    x = sys.x0.copy()
    x[1, 0] += A
    # t = 2.25 T: at whole periods Verlet's O(dt^2) phase error cancels in x to O(dt^4)
    steps = 9 * n_per_period // 4
    traj = explicit(sys, dt=T / n_per_period, steps=steps, integrator=integrator,
                    x_init=x, mass_damping=alpha)  # fmt: skip
    t = steps * T / n_per_period
    wd = np.sqrt(omega**2 - alpha**2 / 4)
    exact = A * np.exp(-alpha * t / 2) * (np.cos(wd * t) + alpha / (2 * wd) * np.sin(wd * t))
    return abs(traj.x[1, 0] - 1.0 - exact) / A


def test_verlet_is_second_order_and_symplectic_euler_first():
    ns = np.array([40, 80, 160, 320])
    h = 1.0 / ns
    for integrator, order in (("verlet", 2.0), ("symplectic-euler", 1.0)):
        err = [_oscillator_error(integrator, n) for n in ns]
        rate = np.polyfit(np.log(h), np.log(err), 1)[0]
        assert rate == pytest.approx(order, abs=0.15), (integrator, err)


def test_mass_damping_matches_damped_oscillator():
    """Verlet with exact mass-damping splitting: second order towards the damped solution."""
    errs = [_oscillator_error("verlet", n, alpha=0.8) for n in (100, 200)]
    assert errs[1] < 1e-3
    assert errs[0] / errs[1] == pytest.approx(4.0, rel=0.15)


@pytest.mark.parametrize("integrator", ["symplectic-euler", "verlet"])
def test_critical_time_step_is_sharp(integrator):
    sys = beam(divisions=(4, 2, 2), linear=True)
    x = random_displacement(sys, 0.01)  # excites the highest modes
    dt_crit, _ = stable_time_step(sys)
    traj = explicit(sys, dt=0.95 * dt_crit, steps=3000, integrator=integrator, x_init=x)
    E = traj.total_energy
    assert np.all(np.isfinite(E)) and E.max() < 50 * E[0]  # bounded (no growth)
    with pytest.raises(SolverError, match=r"explicit integration blew up at step \d+ \(t = ") as e:
        explicit(sys, dt=1.1 * dt_crit, steps=3000, integrator=integrator, x_init=x)
    msg = str(e.value)
    assert "in element" in msg and "dt / dt_crit = 1.1" in msg  # dt given: ratio at rest
    assert float(msg.split("omega dt = ")[1].split()[0]) > 2.0  # the unstable mode's omega dt
    state = e.value.state
    assert state.shape == sys.x0.shape and np.all(np.isfinite(state))


def test_load_switched_on_after_a_quiet_start_is_not_a_blow_up():
    """Kinetic energy jumps by ~1e20 when the load comes on after roundoff-level motion:
    physical growth, not instability (the velocity is not on the unstable time scale)."""
    sys = beam(divisions=(4, 2, 2), load=(0.0, 0.0, -0.05), linear=True)
    dt_crit, _ = stable_time_step(sys)
    dt = 0.9 * dt_crit
    v0 = 1e-12 * np.random.default_rng(3).standard_normal(sys.x0.shape)
    traj = explicit(sys, dt=dt, steps=600, v_init=v0, scale=lambda t: float(t > 200 * dt))
    assert traj.steps == 600 and traj.kinetic[-1] > 1e15 * traj.kinetic[0]
    with pytest.raises(SolverError, match="blew up"):  # the same start at 1.05 dt_crit
        explicit(sys, dt=1.05 * dt_crit, steps=600, v_init=v0, scale=lambda t: float(t > 0.3))


def test_blow_up_names_the_element_where_it_starts():
    """A stiff element is the weak spot: the top mode (and the blow-up) lives there."""
    weak = 17
    sys = beam(divisions=(4, 2, 2), linear=True, stiff_edges_near=weak)
    dt_crit, _ = stable_time_step(sys)
    x = random_displacement(sys, 1e-3)
    with pytest.raises(SolverError) as e:
        explicit(sys, dt=1.05 * dt_crit, steps=5000, x_init=x)
    msg = str(e.value)
    node = int(msg.split(" at node ")[1].split()[0])
    elem = int(msg.split(" in element ")[1].split()[0])
    assert node in sys.tets[weak]
    # the named element shares the stiff edges: it is the weak tet or a neighbour of it
    assert np.intersect1d(sys.tets[elem], sys.tets[weak]).size >= 2


def test_explicit_ramped_prescribed_displacement_follows_scale():
    sys = beam(divisions=(4, 2, 2))
    sys.u_presc = np.tile([0.0, 0.0, 0.05], sys.fixed_dofs.size // 3)
    dt_crit, _ = stable_time_step(sys)
    steps = 400
    traj = explicit(sys, dt=0.5 * dt_crit, steps=steps, scale=lambda t: min(1.0, t / 0.01))
    assert np.allclose(traj.x.reshape(-1)[sys.fixed_dofs], sys.prescribed(1.0), atol=1e-15)
    assert traj.steps == steps and np.all(np.isfinite(traj.x))


def test_progress_bar_runs(capsys):
    sys = oscillator()
    traj = explicit(sys, dt=0.01, steps=500, progress=True)
    assert traj.steps == 500
    assert "explicit" in capsys.readouterr().err


# ------------------------------------------------------------------------------- static


def _linear_reference(sys: EdgeSprings) -> np.ndarray:
    """Direct sparse solve K_ff u_f = f_f - K_fc u_c of the linearised system."""
    free, Kff = free_block(sys, sys.K0)
    K = sp.csr_matrix(sys.K0)
    u = np.zeros(3 * sys.x0.shape[0])
    u[sys.fixed_dofs] = sys.u_presc
    rhs = sys.f_ext.reshape(-1)[free] - K[free][:, sys.fixed_dofs] @ sys.u_presc
    u[free] = spla.spsolve(Kff.tocsc(), rhs)
    return u


def _prescribe_tip(sys: EdgeSprings, value) -> None:
    """Clamp plus a prescribed displacement of the x = max face."""
    tip = np.flatnonzero(sys.x0[:, 0] > sys.x0[:, 0].max() - 0.6)
    tip = tip[np.abs(sys.x0[tip, 0] - sys.x0[tip, 0].max()) < 0.3]
    extra = (3 * tip[:, None] + np.arange(3)).ravel()
    sys.fixed_dofs = np.concatenate([sys.fixed_dofs, extra])
    sys.u_presc = np.concatenate([np.zeros(sys.fixed_dofs.size - extra.size),
                                  np.tile(value, tip.size)])  # fmt: skip


@pytest.mark.parametrize("linear_solver", ["auto", "amg"])
def test_static_linear_equals_direct_solve(linear_solver):
    sys = beam(load=(0.0, 0.02, -0.05), linear=True)
    u_ref = _linear_reference(sys)
    info = static(sys, tol=1e-13, linear_solver=linear_solver)
    u = (info.x - sys.x0).reshape(-1)
    assert isinstance(info, SolveInfo) and info.converged
    # direct: Newton is exact in one step to roundoff; AMG-CG to its rtol 1e-10
    tol = 1e-10 if linear_solver == "auto" else 1e-8
    assert np.linalg.norm(u - u_ref) / np.linalg.norm(u_ref) < tol
    assert info.iterations <= 3  # 1 (exact) + roundoff stagnation; AMG: +1 for its rtol
    assert info.linear_solver == ("direct" if linear_solver == "auto" else "cg+amg")


def test_static_linear_with_prescribed_displacement():
    sys = beam(linear=True)
    _prescribe_tip(sys, [0.0, 0.0, -0.1])
    u_ref = _linear_reference(sys)
    info = static(sys, tol=1e-13, load_steps=3)
    u = (info.x - sys.x0).reshape(-1)
    assert np.linalg.norm(u - u_ref) / np.linalg.norm(u_ref) < 1e-10
    assert info.load_steps == pytest.approx([1 / 3, 2 / 3, 1.0])


def test_newton_converges_quadratically_on_nonlinear_springs():
    load = (0.0, 0.0, -0.15)
    sys = beam(load=load)
    iterates = []
    info = static(sys, tol=1e-13, callback=lambda it, s, x, r: iterates.append(x.copy()))
    u_lin = _linear_reference(beam(load=load, linear=True))
    u = (info.x - sys.x0).reshape(-1)
    assert np.linalg.norm(u - u_lin) > 0.1 * np.linalg.norm(u_lin)  # really nonlinear
    assert info.converged and info.residual <= 2e-13 and info.load_steps == [1.0]
    # quadratic: e_{k+1} <= C e_k^2 with C of order one once e_k is small (a linearly
    # convergent iteration with ratio rho has e_{k+1} / e_k^2 = rho / e_k -> infinity);
    # pairs whose e_{k+1} is at roundoff (< 1e-12, lengths ~ 1) say nothing.
    e = np.array([np.abs(x - info.x).max() for x in iterates])
    pairs = [(a, b) for a, b in zip(e[:-1], e[1:]) if a < 1e-2 and b > 1e-12]
    assert len(pairs) >= 2, e
    assert all(b <= 100 * a * a for a, b in pairs), e
    # equilibrium checked independently: the net force on the free DOFs vanishes
    f = sys.forces(info.x).reshape(-1)
    free = np.setdiff1d(np.arange(f.size), sys.fixed_dofs)
    assert np.linalg.norm(f[free]) <= 2e-13 * info.reference_force


def test_static_with_fd_jacobian_matches_analytic():
    sys = beam(load=(0.0, 0.0, -0.15))
    ref = static(sys, tol=1e-12)
    sys.analytic = False
    info = static(sys, tol=1e-12)
    assert info.converged and info.jacobian == "fd" and ref.jacobian == "analytic"
    assert np.abs(info.x - ref.x).max() < 1e-9
    assert info.iterations <= ref.iterations + 2  # FD tangent accurate to ~1e-10


@pytest.mark.parametrize("linear_solver", ["direct", "amg"])
def test_static_non_gradient_forces_converge(linear_solver):
    """A circulatory load: no energy, non-symmetric FD Jacobian, spsolve or GMRES."""
    sys = beam(load=(0.0, 0.0, -0.1), circulation=1e-3)  # ~1/5 of K's smallest eigenvalue
    info = static(sys, tol=1e-10, linear_solver=linear_solver)
    assert info.converged and info.jacobian == "fd"
    assert info.linear_solver == ("direct" if linear_solver == "direct" else "gmres+amg")
    f = sys.forces(info.x).reshape(-1)
    free = np.setdiff1d(np.arange(f.size), sys.fixed_dofs)
    assert np.linalg.norm(f[free]) <= 1e-10 * info.reference_force * 1.0001
    K = fd_jacobian(lambda y: sys.forces(y), info.x, sys.tets)
    assert spla.norm(K - K.T) > 1e-5 * spla.norm(K)  # non-symmetric (FD noise is ~1e-10)


def test_static_cuts_back_and_falls_back_to_dynamic_relaxation():
    sys = beam(load=(0.0, 0.0, -0.15))
    ref = static(sys, tol=1e-10)
    cut = static(sys, tol=1e-10, max_iter=3)
    assert cut.converged and cut.cutbacks > 0 and len(cut.load_steps) > 1
    assert np.abs(cut.x - ref.x).max() < 1e-8
    dr = static(sys, tol=1e-7, max_iter=1, max_cutbacks=1)
    assert dr.converged and dr.method == "newton+dynamic-relaxation" and dr.steps > 0
    assert np.abs(dr.x - ref.x).max() < 1e-4 * np.abs(ref.x - sys.x0).max()
    with pytest.raises(SolverError, match="static solve did not converge") as e:
        static(sys, tol=1e-10, max_iter=1, max_cutbacks=1, fallback=False)
    assert e.value.state.shape == sys.x0.shape


@pytest.mark.parametrize("fixed", [np.array([], dtype=int), np.array([0, 1, 2])])
def test_singular_system_raises(fixed):
    sys = beam(load=(0.0, 0.0, -0.1))
    sys.fixed_dofs = fixed
    sys.u_presc = np.zeros(fixed.size)
    with pytest.raises(
        SolverError,
        match="singular stiffness: the scene has no boundary condition that stops rigid motion",
    ):
        static(sys)


@pytest.mark.parametrize("damping", ["kinetic", "mass"])
def test_explicit_static_reaches_newton_solution(damping):
    sys = beam(divisions=(4, 2, 2), load=(0.0, 0.0, -0.05))
    ref = static(sys, tol=1e-12)
    alpha = 0.0
    if damping == "mass":  # about critical for the lowest mode
        free, Kff = free_block(sys, sys.stiffness(ref.x))
        w = scipy.linalg.eigh(Kff.toarray(), np.diag(np.repeat(sys.masses, 3)[free]),
                              eigvals_only=True)  # fmt: skip
        alpha = 2 * np.sqrt(w[0])
    info = explicit_static(sys, tol=1e-8, damping=damping, mass_damping=alpha)
    assert info.converged and info.steps > 0 and info.residual <= 1e-8
    u_ref = ref.x - sys.x0
    assert np.abs(info.x - ref.x).max() < 1e-5 * np.abs(u_ref).max()


# ------------------------------------------------------------------------------ implicit


def test_implicit_is_stable_beyond_the_critical_step():
    sys = beam(divisions=(4, 2, 2), linear=True)
    x = random_displacement(sys, 0.01)
    dt_crit, _ = stable_time_step(sys)
    traj = implicit(sys, dt=10 * dt_crit, steps=100, x_init=x, record_every=1)
    E = traj.total_energy
    assert np.all(np.isfinite(traj.x)) and traj.iterations == 100  # linear: one Newton step
    # backward Euler dissipates: energy never grows (to roundoff)
    assert np.all(np.diff(E) <= 1e-12 * E[0]) and E[-1] < E[0]
    with pytest.raises(SolverError, match="blew up"):
        explicit(sys, dt=10 * dt_crit, steps=100, x_init=x)


def test_implicit_converges_to_explicit_trajectory_at_first_order():
    """Lowest mode of a linear system: x(t) = x0 + A phi cos(omega_1 t) exactly."""
    sys = beam(divisions=(4, 2, 2), linear=True)
    free, Kff = free_block(sys, sys.K0)
    M = np.repeat(sys.masses, 3)[free]
    w2, phi = scipy.linalg.eigh(Kff.toarray(), np.diag(M))
    omega = np.sqrt(w2[0])
    T = 2 * np.pi / omega
    x = sys.x0.copy()
    x.reshape(-1)[free] += 0.05 * phi[:, 0] / np.abs(phi[:, 0]).max()
    amp = np.abs(x - sys.x0).max()
    dt_crit, _ = stable_time_step(sys)
    n_e = int(np.ceil(T / (0.5 * dt_crit)))
    xe = explicit(sys, dt=T / n_e, steps=n_e, integrator="verlet", x_init=x).x
    assert np.abs(xe - x).max() < 1e-3 * amp  # explicit Verlet: O(dt^2), back after a period
    ns = np.array([50, 100, 200, 400])
    errs, diffs = [], []
    for n in ns:
        xi = implicit(sys, dt=T / n, steps=n, x_init=x).x
        errs.append(np.abs(xi - x).max() / amp)  # exact solution after one period: x
        diffs.append(np.abs(xi - xe).max() / amp)
    rate = np.polyfit(np.log(1.0 / ns), np.log(errs), 1)[0]
    assert rate == pytest.approx(1.0, abs=0.15)  # backward Euler: first order
    # amplitude decays like exp(-omega^2 dt T / 2): error ~ pi omega dt = 2 pi^2 / n
    assert errs[-1] == pytest.approx(1 - np.exp(-2 * np.pi**2 / ns[-1]), rel=0.1)
    assert diffs[-1] < 0.06 and np.all(np.diff(diffs) < 0)  # approaches explicit


def test_implicit_uses_the_damping_jacobian():
    """Linear springs with linear dashpots: Newton is exact, one iteration per step."""
    sys = beam(divisions=(4, 2, 2), linear=True, damping=0.05)
    x = random_displacement(sys, 0.01)
    dt_crit, _ = stable_time_step(sys)
    traj = implicit(sys, dt=5 * dt_crit, steps=20, x_init=x, tol=1e-12)
    assert traj.iterations == 20
    assert traj.residual_history[-1] <= 1e-12


def test_implicit_nonlinear_large_steps_reach_equilibrium():
    sys = beam(divisions=(4, 2, 2), load=(0.0, 0.0, -0.05))
    ref = static(sys, tol=1e-12)
    dt_crit, _ = stable_time_step(sys)
    traj = implicit(sys, dt=200 * dt_crit, steps=500, equilibrium_tol=1e-9)
    assert traj.converged and traj.steps < 500
    assert np.abs(traj.x - ref.x).max() < 1e-6 * np.abs(ref.x - sys.x0).max()


def test_solve_with_options_dispatch():
    sys = beam(divisions=(4, 2, 2), load=(0.0, 0.0, -0.1))
    ref = static(sys, tol=1e-10).x
    info = solve_with_options(sys, SpringOptions(solver="static", tol=1e-10))
    assert isinstance(info, SolveInfo) and np.abs(info.x - ref).max() < 1e-12
    traj = solve_with_options(sys, SpringOptions(solver="explicit", steps=50))
    assert isinstance(traj, Trajectory) and traj.steps == 50
    assert traj.dt == pytest.approx(0.5 * stable_time_step(sys)[0])
    dr = solve_with_options(sys, SpringOptions(solver="explicit", tol=1e-6))
    assert isinstance(dr, SolveInfo) and dr.converged
    be = solve_with_options(sys, SpringOptions(solver="implicit", tol=1e-8))
    assert isinstance(be, Trajectory) and be.converged


# ------------------------------------------------------------ with the spring model itself

SCENES = Path(__file__).resolve().parents[2] / "studies" / "scenes"


@pytest.fixture(scope="module")
def stretch_model():
    """The bundled stretch-fiber scene with the energy-consistent torsion (conservative)."""
    from springfem.scene import load_scene
    from springmodel.model import SpringModel

    scene = load_scene(SCENES / "stretch-fiber.toml")
    return SpringModel(scene, replace(SpringOptions.of(scene), torsion="energy"), parallel=False)


def test_spring_model_fd_jacobian_matches_its_hessian(stretch_model):
    m = stretch_model
    x = random_displacement(m, 2e-4)  # mesh size 1.7 mm: ~10 % strains
    K = m.stiffness(x)
    assert K is not None
    cj = ColoredJacobian(m.element_nodes(), m.x0.shape[0])
    Kfd = cj(lambda y: m.forces(y, None), x)
    assert spla.norm(Kfd - K) / spla.norm(K) < 1e-6  # central differences: ~1e-10
    assert cj.n_evaluations() < 0.2 * 3 * m.x0.shape[0]


def test_spring_model_static_fd_and_dynamic_relaxation_agree(stretch_model):
    m = stretch_model
    ref = static(m, tol=1e-11)
    fd = static(m, tol=1e-11, jacobian="fd")
    assert ref.jacobian == "analytic" and fd.jacobian == "fd"
    u = ref.x - m.x0
    assert np.abs(fd.x - ref.x).max() < 1e-8 * np.abs(u).max()
    dr = explicit_static(m, tol=1e-8)
    assert dr.converged and np.abs(dr.x - ref.x).max() < 1e-5 * np.abs(u).max()


def test_spring_model_explicit_conserves_energy(stretch_model):
    """Release the static stretch (scale 0): total energy stays at the stored elastic energy."""
    m = stretch_model
    x = static(m, tol=1e-10).x
    dt_crit, _ = stable_time_step(m, x)
    traj = explicit(
        m, dt=0.1 * dt_crit, steps=2000, integrator="verlet", scale=0.0, x_init=x, record_every=10
    )
    E = traj.total_energy
    assert E[0] > 0 and np.abs(E - E[0]).max() < 1e-3 * E[0]
    assert traj.kinetic.max() > 0.1 * E[0]  # the energy really moved


def test_spring_model_non_gradient_torsion_newton_on_the_cantilever():
    """Cosine torsion (eq. 2.44-2.45): no energy, non-symmetric FD tangent. The slender
    cantilever's first Newton step raises the residual norm tenfold; the natural
    monotonicity test accepts it and Newton converges in a few iterations."""
    from springfem.scene import load_scene
    from springmodel.model import SpringModel

    scene = load_scene(SCENES / "cantilever.toml")
    m = SpringModel(scene, replace(SpringOptions.of(scene), torsion="cosine"), parallel=False)
    assert m.energy(m.x0) is None
    info = static(m, tol=1e-8)  # this scene's roundoff floor is ~3e-9 of its tiny load
    assert info.converged and info.jacobian == "fd" and info.iterations <= 6
    assert max(info.residual_history) > 2.0  # the residual norm did grow on the way
    f = m.forces(info.x, None).reshape(-1)
    free = np.setdiff1d(np.arange(f.size), m.fixed_dofs)
    assert np.linalg.norm(f[free]) <= 1e-8 * info.reference_force
    K = fd_jacobian(lambda y: m.forces(y, None), info.x, m.element_nodes())
    assert spla.norm(K - K.T) > 1e-6 * spla.norm(K)  # FD noise alone is ~1e-10
