"""Backward Euler: stability beyond the critical step, first-order convergence to the
explicit trajectory, the damping Jacobian; the spring solver dispatch."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the shared test systems
from mechanics_systems import (  # noqa: E402
    beam,
    free_block,
    random_displacement,
)

from springfem.errors import SolverError
from springfem.mechanics import (
    SolveInfo,
    Trajectory,
    explicit,
    implicit,
    stable_time_step,
    static,
)
from springmodel.options import SpringOptions
from springmodel.solve import solve_with_options


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


@pytest.mark.slow
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
