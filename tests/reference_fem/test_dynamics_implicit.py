"""The dynamic reference (reference_fem.dynamics_implicit) against independent references.

- Its first bending frequency of a cantilever against a modal analysis of the same P2 mesh,
  assembled independently here with scikit-fem's own vector elasticity and mass forms and
  solved by ``eigsh`` in shift-invert mode (Newmark's frequency error is
  ``(omega h)^2 / 12``: 0.008 % at 200 steps a period, far inside the 0.5 % asked for).
- Its probe trajectory against itself at three time steps: second order.
- Energy: the trapezoidal rule conserves the energy of a linear law to round-off;
  with Rayleigh damping the balance closes with the dissipated energy.
"""

import numpy as np
import pytest
import skfem
from scipy.sparse.linalg import eigsh
from skfem.helpers import dot
from skfem.models.elasticity import lame_parameters, linear_elasticity

from reference_fem.dynamics_implicit import Integrator, run
from springfem.scene import scene_from_dict

E, NU, RHO = 1.0e4, 0.3, 1000.0
#: A beam twice as wide as thick: its first mode bends in z, well apart from the y one.
SIZE, TIP = [0.1, 0.02, 0.01], [0.1, 0.01, 0.005]


def beam(divisions, law="linear", traction=-0.01, time=None, nu=NU, **extra):
    load = {"type": "traction", "region": "x_max", "value": [0.0, 0.0, traction]}
    if time is not None:
        load["time"] = time
    return scene_from_dict({
        "mesh": {"generator": "box", "size": SIZE, "divisions": divisions},
        "material": {"law": law, "E": E, "nu": nu, "density": RHO},
        "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
        "load": [load],
        "probe": [{"name": "tip", "point": TIP}],
        **extra,
    })  # fmt: skip


def modal_frequencies(scene, k=3):
    """Angular frequencies of the clamped P2 mesh and each mode's share of z motion:
    scikit-fem's own linear elasticity and vector mass forms (not the reference's)."""
    m = skfem.MeshTet(scene.mesh.points.T.copy(), scene.mesh.tets.T.copy())
    ib = skfem.Basis(m, skfem.ElementVector(skfem.ElementTetP2()), intorder=4)
    K = skfem.asm(linear_elasticity(*lame_parameters(E, NU)), ib)
    M = skfem.asm(skfem.BilinearForm(lambda u, v, w: RHO * dot(u, v)), ib)
    free = ib.complement_dofs(ib.get_dofs(lambda x: np.isclose(x[0], 0.0)).all())
    w2, V = eigsh(K[free][:, free], k=k, M=M[free][:, free], sigma=0.0, which="LM")
    full = np.zeros((K.shape[0], k))
    full[free] = V
    z = ib.split_indices()[2]
    share = np.linalg.norm(full[z], axis=0) / np.linalg.norm(full, axis=0)
    return np.sqrt(w2), share


def upward_crossings(t, z):
    """Times where ``z`` crosses 0 upwards (linear interpolation in the step)."""
    i = np.flatnonzero((z[:-1] < 0) & (z[1:] >= 0))
    return t[i] - z[i] * (t[i + 1] - t[i]) / (z[i + 1] - z[i])


def test_first_bending_frequency_matches_a_modal_analysis():
    scene = beam([10, 2, 1], time={"release": 0.0}, dynamics={"initial": "static"})
    w, z_share = modal_frequencies(scene)
    assert z_share[0] > 0.99  # the first mode is the bending in z the tip load excites
    period = 2 * np.pi / w[0]
    r = run(scene, t_end=4.2 * period, dt=period / 200)
    c = upward_crossings(r.times, r.probes["tip"][:, 2])
    assert len(c) == 4
    measured = (c[-1] - c[0]) / (len(c) - 1)
    # trapezoidal Newmark lengthens the period by (omega h)^2 / 12 = 8e-5 here; the
    # crossings also see the higher modes the release excites (measured: 1.2e-4)
    assert measured / period - 1 == pytest.approx(0.0, abs=1e-3)


SMOOTH = [[0.5 * s, s**3 * (10 - 15 * s + 6 * s * s)] for s in np.linspace(0, 1, 21)]


@pytest.mark.parametrize(
    "integrator", ["trapezoidal", pytest.param("generalized-alpha", marks=pytest.mark.slow)]
)
def test_probe_trajectory_converges_at_second_order_in_time(integrator):
    # neo-Hookean, tip traction raised smoothly from rest (a smooth load excites no mode
    # the steps leave unresolved; the table's kinks fall on every grid)
    scene = beam([6, 2, 1], law="neo-hookean", traction=-1.0, time={"table": SMOOTH})
    q = [run(scene, t_end=0.5, dt=1 / n, integrator=integrator).probes["tip"]
         for n in (40, 80, 160)]  # fmt: skip
    d1 = np.abs(q[0] - q[1][::2]).max()
    d2 = np.abs(q[1][::2] - q[2][::4]).max()
    assert np.log2(d1 / d2) > 1.9  # second order (measured 1.98)


def test_trapezoidal_conserves_the_energy_of_a_linear_law():
    scene = beam([6, 2, 1], time={"release": 0.0}, dynamics={"initial": "static"})
    r = run(scene, t_end=2.0, dt=0.01)
    e0 = r.energies["strain"][0]
    total = r.energies["kinetic"] + r.energies["strain"]
    assert r.energies["external_work"].max() == 0.0  # released at t = 0
    # round-off per step: the step solve's relative accuracy (condition number of the
    # step matrix times machine epsilon; measured 7e-12), and no drift over 200 steps
    assert np.abs(np.diff(total)).max() < 1e-10 * e0
    assert np.abs(total - total[0]).max() < 1e-9 * e0
    assert r.energies["kinetic"].max() > 0.5 * e0  # it does swing


def test_rayleigh_damping_balance_closes_and_matches_its_ratio():
    zeta = 0.02
    w, _ = modal_frequencies(beam([6, 2, 1]), k=1)
    f1 = w[0] / (2 * np.pi)
    scene = beam([6, 2, 1], time={"release": 0.0}, dynamics={
        "initial": "static", "damping": {"ratio": zeta, "frequencies": [f1]}})  # fmt: skip
    period = 1 / f1
    r = run(scene, t_end=3.2 * period, dt=period / 200)
    e = r.energies
    assert e["dissipated"][-1] > 0.3 * e["strain"][0]
    assert np.abs(e["balance"]).max() < 1e-10 * e["strain"][0]
    # the amplitude decays as exp(-zeta omega t): compare minima one period apart, after
    # the first period (the higher modes the release excites are damped more, and faster)
    z = r.probes["tip"][:, 2]
    first, second = z[200:400].min(), z[400:600].min()
    assert np.log(first / second) / (2 * np.pi) == pytest.approx(zeta, rel=0.05)


def test_generalized_alpha_at_rho_one_is_the_trapezoidal_rule_and_below_damps():
    g = Integrator.generalized_alpha(1.0)
    assert (g.beta, g.gamma) == (0.25, 0.5)
    scene = beam([6, 2, 1], time={"release": 0.0}, dynamics={"initial": "static"})
    trap = run(scene, t_end=1.0, dt=0.02)
    alpha1 = run(scene, t_end=1.0, dt=0.02, integrator="generalized-alpha", rho_inf=1.0)
    scale = np.abs(trap.probes["tip"]).max()
    assert np.abs(trap.probes["tip"] - alpha1.probes["tip"]).max() < 1e-9 * scale
    damped = run(scene, t_end=1.0, dt=0.02, integrator="generalized-alpha", rho_inf=0.5)
    total = damped.energies["kinetic"] + damped.energies["strain"]
    assert total[-1] < total[0] and damped.energies["balance"][-1] < 0.0


def mixed_beam(nu):
    return beam([6, 2, 1], law="neo-hookean", time={"release": 0.0}, nu=nu, dynamics={
        "initial": "static"}, fem={"order": 2, "formulation": "mixed"})  # fmt: skip


def condensed_frequency(scene):
    """The first angular frequency of the P2/P1 mesh: the reference's tangent at rest with
    the pressure condensed out, ``S = K_uu - K_up K_pp^-1 K_pu``, and its mass matrix
    (dense ``eigh``; independent of the time integration)."""
    from scipy.linalg import eigh

    from reference_fem.dynamics_terms import mass_matrix
    from reference_fem.solver import make_problem

    p = make_problem(scene, 2)
    K = p.internal_force(np.zeros(p.n_dofs), tangent=True)[1].toarray()
    fu = p.free[: p.nu]
    Kuu, Kup, Kpp = K[: p.nu, : p.nu][fu][:, fu], K[: p.nu, p.nu :][fu], K[p.nu :, p.nu :]
    S = Kuu - Kup @ np.linalg.solve(Kpp, Kup.T)
    M = mass_matrix(p).toarray()[fu][:, fu]
    return float(np.sqrt(eigh(S, M, eigvals_only=True, subset_by_index=[0, 0])[0]))


@pytest.mark.slow
def test_mixed_first_frequency_matches_its_condensed_modal_analysis():
    scene = mixed_beam(0.45)
    period = 2 * np.pi / condensed_frequency(scene)
    r = run(scene, t_end=3.2 * period, dt=period / 200)
    c = upward_crossings(r.times, r.probes["tip"][:, 2])
    assert r.info["formulation"] == "mixed" and len(c) == 3
    # measured 0.035 % (0.19 % at 100 steps a period: the (omega h)^2 of the rule)
    assert (c[-1] - c[0]) / (len(c) - 1) / period - 1 == pytest.approx(0.0, abs=5e-3)


def test_mixed_energy_balance_closes_at_the_rules_order():
    scene = mixed_beam(0.45)
    balance = []
    for n in (25, 50):
        r = run(scene, t_end=0.5, dt=0.5 / n)
        balance.append(np.abs(r.energies["balance"]).max() / r.energies["strain"][0])
    # the pressure carries no energy the balance misses: what is left is the trapezoid's
    # error on a nonlinear law, second order (measured 1e-6 at 100 steps a period)
    assert balance[0] < 1e-4 and 3.0 < balance[0] / balance[1] < 5.0


def test_probes_between_steps_and_frames_at_chosen_times():
    # the tip of a linear beam swinging in its first mode: Hermite interpolation of a
    # dt = 0.02 run at other times against a run with those times on its grid
    scene = beam([6, 2, 1], time={"release": 0.0}, dynamics={"initial": "static"})
    coarse = run(scene, t_end=0.4, dt=0.02, frames=[0.1, 0.25])
    fine = run(scene, t_end=0.4, dt=0.005)
    t = fine.times[1::4]  # between coarse steps: 0.005, 0.025, ...
    between = coarse.probes_at(t)["tip"]
    on_step = run(scene, t_end=0.4, dt=0.02).probes["tip"]
    # interpolation adds little to the rule's own error (the dt = 0.02 run's error at its
    # steps, against the dt = 0.005 run)
    rule = np.abs(on_step - fine.probes["tip"][::4]).max()
    assert np.abs(between - fine.probes["tip"][1::4]).max() < 2.0 * rule
    assert coarse.frame_times == pytest.approx([0.1, 0.26])  # the first step at or after


@pytest.mark.parametrize("formulation", ["displacement", "nodal-strain", "mini"])
def test_every_p1_formulation_keeps_its_own_energy(formulation):
    # released neo-Hookean beam, 50 steps of 0.01 s: the balance measures each
    # formulation's own potential (nodal strain: its blended energy, not int psi(F_e))
    scene = beam([10, 2, 1], law="neo-hookean", time={"release": 0.0},
                 dynamics={"initial": "static"})  # fmt: skip
    r = run(scene, t_end=0.5, dt=0.01, order=1, formulation=formulation)
    e = r.energies
    assert e["kinetic"].max() > 0.5 * e["strain"][0]
    assert np.abs(e["balance"]).max() < 1e-5 * e["strain"][0]  # measured 1e-7 to 7e-7


def test_a_step_whose_newton_fails_is_split_in_two(monkeypatch):
    """A failing step is taken as two half steps; the motion stays that of the run (the
    halves are a finer step of the same integrator) and the run says how many it split."""
    import reference_fem.dynamics_implicit as dyn
    from springfem.errors import SolverError
    from springfem.scene import scene_from_dict

    scene = scene_from_dict({
        "mesh": {"generator": "box", "size": [0.1, 0.01, 0.01], "divisions": [4, 1, 1]},
        "material": {"law": "neo-hookean", "E": 1.0e4, "nu": 0.3, "density": 1000.0},
        "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
        "load": [{"type": "traction", "region": "x_max", "value": [0, 0, -0.5],
                  "time": {"ramp": [0.0, 0.05]}}],
        "probe": [{"name": "tip", "point": [0.1, 0.005, 0.005]}]})  # fmt: skip
    plain = dyn.run(scene, t_end=0.1, dt=0.01)
    step = dyn._Run._step
    failed = []

    def flaky(self, x, v, a, g_n, t1, h, tol, max_iter):
        if abs(t1 - 0.03) < 1e-12 and h > 0.006:
            failed.append(t1)
            raise SolverError("Newton did not converge (test)")
        return step(self, x, v, a, g_n, t1, h, tol, max_iter)

    monkeypatch.setattr(dyn._Run, "_step", flaky)
    split = dyn.run(scene, t_end=0.1, dt=0.01)
    assert failed == [0.03] and split.info["split_steps"] == 1
    assert len(split.times) == len(plain.times)
    tip, ref = split.probes["tip"][:, 2], plain.probes["tip"][:, 2]
    assert np.abs(tip - ref).max() < 0.05 * np.abs(ref).max()
    assert np.abs(tip - ref).max() > 0  # the split step did take two halves
