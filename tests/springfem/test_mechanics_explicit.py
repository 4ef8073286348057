"""Critical time step and explicit integrators against closed-form oscillators, dense
eigenvalues and energy conservation; the blow-up monitor."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the shared test systems
from mechanics_systems import (  # noqa: E402
    beam,
    chain,
    free_block,
    oscillator,
    random_displacement,
)

from springfem.errors import SolverError
from springfem.mechanics import (
    Trajectory,
    explicit,
    stable_time_step,
    static,
)


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
