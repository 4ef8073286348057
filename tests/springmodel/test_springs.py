"""Spring forces (springmodel.springs): gradients, invariants, volume springs, LMS, energy.

Every check compares against something independent of the force code: central finite
differences of the energy, the energy ``W_k(F)`` computed from the deformation gradient
alone (springmodel.calibration), momentum invariants, rigid motions, and energy
conservation of a symplectic integrator.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from springfem.mesh import box_mesh
from springmodel import springs
from springmodel.element_energy import element_energy_from_F
from springmodel.elements import build_spring_elements
from springmodel.options import LMSOptions, SpringOptions

MATERIAL = {"law": "linear", "E": 1.0e3, "nu": 0.3}
TORSION_LAWS = ("angle", "cosine", "cubic", "energy")
AXIAL_LAWS = ("linear", "quadratic", "cubic", "stress-scaled")


# --------------------------------------------------------------------------- helpers


def tet_soup(m: int, seed: int = 0, noise: float = 0.35):
    """``m`` disconnected irregular tets (4 own nodes each), positively oriented."""
    rng = np.random.default_rng(seed)
    ref = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    X = ref[None] + noise * rng.standard_normal((m, 4, 3)) + 3.0 * rng.standard_normal((m, 1, 3))
    det = np.linalg.det(X[:, 1:] - X[:, :1])
    X[det < 0] = X[det < 0][:, [0, 2, 1, 3]]
    return X.reshape(-1, 3), np.arange(4 * m).reshape(m, 4)


def random_elements(points, tets, seed: int = 1, options: SpringOptions | None = None):
    """Elements with random frames and random positive constants (catches index mix-ups)."""
    rng = np.random.default_rng(seed)
    m = tets.shape[0]
    frames = Rotation.random(m, random_state=seed).as_matrix()
    el = build_spring_elements(points, tets, frames, options or SpringOptions(), MATERIAL)
    el.k_axial = rng.uniform(0.5, 2.0, (m, 3)) * el.k_axial
    el.k_torsion = rng.uniform(0.5, 2.0, (m, 3)) * el.k_torsion
    el.k_volume = rng.uniform(0.5, 2.0, m) * el.k_volume
    el.k_volume0 = el.k_volume.copy()
    return el


def only(el, part: str):
    """A copy of ``el`` with the constants of every other part set to zero."""
    zero = {
        "axial": {"k_torsion": 0 * el.k_torsion, "k_volume": 0 * el.k_volume},
        "torsion": {"k_axial": 0 * el.k_axial, "k_volume": 0 * el.k_volume},
        "volume": {"k_axial": 0 * el.k_axial, "k_torsion": 0 * el.k_torsion},
    }[part]
    return dataclasses.replace(el, **zero)


def all_variants():
    """Every (axial, torsion, volume_form) combination, damping on."""
    for a in AXIAL_LAWS:
        for t in ("off", *TORSION_LAWS):
            for vf in ("gradient", "spec"):
                yield SpringOptions(
                    axial=a,
                    axial_coefficients=(0.7, 0.4),
                    torsion=t,
                    torsion_cubic=1.5,
                    volume_form=vf,
                    volume_damping=0.2,
                    axial_damping=0.3,
                )


def fd_gradient(energy, x, h):
    """Central differences of a scalar function of ``x`` (n, 3)."""
    g = np.zeros_like(x)
    for i in range(x.shape[0]):
        for c in range(3):
            xp, xm = x.copy(), x.copy()
            xp[i, c] += h
            xm[i, c] -= h
            g[i, c] = (energy(xp) - energy(xm)) / (2 * h)
    return g


def torque(x, f):
    return np.cross(x, f).sum(axis=0)


def rel(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


# --------------------------------------------------------------------------- gradients

ENERGY_CASES = [
    ("axial", SpringOptions(axial="linear", torsion="off", volume=False)),
    ("axial", SpringOptions(axial="quadratic", axial_coefficients=(0.8, 0.0), torsion="off")),
    ("axial", SpringOptions(axial="cubic", axial_coefficients=(0.8, 0.6), torsion="off")),
    ("torsion", SpringOptions(torsion="energy", volume=False)),
    ("volume", SpringOptions(torsion="off", volume=True, volume_form="gradient")),
    ("all", SpringOptions(axial="cubic", axial_coefficients=(0.3, 0.2), torsion="energy")),
]


@pytest.mark.parametrize(("part", "options"), ENERGY_CASES)
def test_energy_forms_are_exact_gradients(part, options):
    # large random deformation of irregular tets; tolerance 1e-6: central differences with
    # h = 1e-6 have O(h^2) truncation and ~1e-10 round-off relative to these forces
    points, tets = tet_soup(5, seed=3)
    el = random_elements(points, tets)
    el = el if part == "all" else only(el, part)
    x = points + 0.25 * np.random.default_rng(4).standard_normal(points.shape)
    f = springs.internal_forces(x, None, el, options)
    g = fd_gradient(lambda y: springs.spring_energy(y, el, options)[1], x, 1e-6)
    assert np.abs(f).max() > 0
    assert rel(f, -g) < 1e-6


@pytest.mark.parametrize("law", ["cosine", "angle", "cubic"])
def test_spec_torsion_laws_are_not_gradients(law):
    # the counterpart of the test above: the spec's torsion forces differ from -dU/dx of the
    # energy they are derived from by far more than finite-difference error
    points, tets = tet_soup(3, seed=5)
    el = only(random_elements(points, tets), "torsion")
    x = points + 0.2 * np.random.default_rng(6).standard_normal(points.shape)
    options = SpringOptions(torsion=law, torsion_cubic=1.0, volume=False)
    f = springs.internal_forces(x, None, el, options)
    g = fd_gradient(lambda y: springs.spring_energy(y, el, options)[1], x, 1e-6)
    assert rel(f, -g) > 1e-2


def test_volume_spec_form_is_not_the_gradient():
    points, tets = tet_soup(3, seed=7)
    el = only(random_elements(points, tets), "volume")
    x = points + 0.2 * np.random.default_rng(8).standard_normal(points.shape)
    options = SpringOptions(torsion="off", volume_form="spec")
    f = springs.internal_forces(x, None, el, options)
    g = fd_gradient(lambda y: springs.spring_energy(y, el, options)[1], x, 1e-6)
    assert rel(f, -g) > 1e-2


# --------------------------------------------------------------------------- energy = W_k(F)


@pytest.mark.parametrize("axial", ["linear", "quadratic", "cubic"])
def test_element_energy_equals_W_of_F(axial):
    # x = F X per element with large random F: the energy through the intersection points
    # must equal W_k(F) built from F zeta0 and F xi0 alone, to round-off (1e-12)
    points, tets = tet_soup(20, seed=9)
    el = random_elements(points, tets)
    rng = np.random.default_rng(10)
    F = np.eye(3) + 0.4 * rng.standard_normal((20, 3, 3))
    F[np.linalg.det(F) < 0] *= -1  # keep the tets positively oriented
    X = points[tets]
    x = (np.einsum("kcd,kid->kic", F, X) + rng.standard_normal((20, 1, 3))).reshape(-1, 3)
    options = SpringOptions(axial=axial, axial_coefficients=(0.5, 0.3), torsion="energy")
    W, total = springs.spring_energy(x, el, options)
    b2, b3 = options.axial_coefficients
    coefficients = (0.0, 0.0) if axial == "linear" else (b2, b3 if axial == "cubic" else 0.0)
    W_F = element_energy_from_F(F, el, el.k_axial, el.k_torsion, el.k_volume, coefficients)
    assert np.all(W_F > 0)
    np.testing.assert_allclose(W, W_F, rtol=1e-12)
    assert total == pytest.approx(W_F.sum(), rel=1e-12)


# --------------------------------------------------------------------------- invariants


@pytest.mark.parametrize(
    "options", list(all_variants()), ids=lambda o: f"{o.axial}-{o.torsion}-{o.volume_form}"
)
def test_net_force_zero_and_rigid_motion(options):
    points, tets = tet_soup(4, seed=11)
    el = random_elements(points, tets)
    rng = np.random.default_rng(12)
    x = points + 0.2 * rng.standard_normal(points.shape)
    v = rng.standard_normal(points.shape)
    f = springs.internal_forces(x, v, el, options)
    scale = np.abs(f).max()
    # net force: every part pairs its forces, except the spec volume form (next test);
    # check per element (disconnected tets) to 1e-12 relative (round-off)
    net = f.reshape(-1, 4, 3).sum(axis=1)
    if options.volume_form == "spec":
        f_ok = f - springs.volume_forces(x, v, el, options)  # everything but the volume part
        net = f_ok.reshape(-1, 4, 3).sum(axis=1)
        scale = np.abs(f_ok).max()
    assert np.abs(net).max() < 1e-12 * scale
    # a rigid rotation + translation of the rest state gives no force (no velocity)
    R = Rotation.random(random_state=13).as_matrix()
    x_rigid = points @ R.T + np.array([0.3, -2.0, 1.0])
    f_rigid = springs.internal_forces(x_rigid, None, el, options)
    assert np.abs(f_rigid).max() < 1e-11 * scale


def test_volume_spec_form_net_force_nonzero_on_irregular_tets():
    # -k dL sum_j xh_j: zero on a regular tet (the xh_j sum to zero), not on irregular ones
    options = SpringOptions(torsion="off", volume_form="spec")
    points, tets = tet_soup(1, seed=14)
    el = only(random_elements(points, tets), "volume")
    x = 1.2 * points
    f = springs.internal_forces(x, None, el, options)
    assert np.linalg.norm(f.sum(axis=0)) > 0.05 * np.abs(f).max()
    f_grad = springs.internal_forces(
        x, None, el, dataclasses.replace(options, volume_form="gradient")
    )
    assert np.linalg.norm(f_grad.sum(axis=0)) < 1e-12 * np.abs(f_grad).max()
    regular = np.array([[1.0, 1, 1], [-1, 1, -1], [1, -1, -1], [-1, -1, 1]])
    assert np.linalg.det(regular[1:] - regular[0]) > 0
    el_r = only(random_elements(regular, np.array([[0, 1, 2, 3]])), "volume")
    f_r = springs.internal_forces(1.2 * regular, None, el_r, options)
    assert np.linalg.norm(f_r.sum(axis=0)) < 1e-12 * np.abs(f_r).max()


@pytest.mark.parametrize("axial", AXIAL_LAWS)
def test_net_torque_zero_for_pair_and_energy_forms(axial):
    # axial forces are +-pairs along the axis; torsion "energy" and the volume gradient are
    # gradients of rotation-invariant energies; 1e-12 relative: round-off
    points, tets = tet_soup(4, seed=15)
    el = random_elements(points, tets)
    x = points + 0.2 * np.random.default_rng(16).standard_normal(points.shape)
    options = SpringOptions(axial=axial, axial_coefficients=(0.5, 0.5), torsion="energy")
    f = springs.internal_forces(x, None, el, options)
    for k in range(4):
        sl = slice(4 * k, 4 * k + 4)
        assert np.linalg.norm(torque(x[sl], f[sl])) < 1e-12 * np.abs(f[sl]).max() * np.abs(x).max()


@pytest.mark.parametrize("law", ["cosine", "angle", "cubic"])
def test_spec_torsion_net_torque_nonzero(law):
    # the spec's laws put s zh_m on the ends of axis l and s zh_l on the ends of axis m; the
    # net torque is sum_pairs s (|zeta_l| - |zeta_m|) zh_l x zh_m, nonzero when the axis
    # segments differ. Compare with that formula (independent: from the current axes).
    points, tets = tet_soup(1, seed=17)
    el = only(random_elements(points, tets), "torsion")
    assert np.ptp(el.l0) > 0.05  # unequal axis segments
    x = points + 0.15 * np.random.default_rng(18).standard_normal(points.shape)
    options = SpringOptions(torsion=law, torsion_cubic=1.2, volume=False)
    f = springs.internal_forces(x, None, el, options)
    zeta = np.einsum("il,ic->lc", el.G[0], x)
    L = np.linalg.norm(zeta, axis=1)
    u = zeta / L[:, None]
    expected = np.zeros(3)
    for p, (l, m) in enumerate([(0, 1), (0, 2), (1, 2)]):
        c = u[l] @ u[m]
        dc, k = c - el.c0[0, p], el.k_torsion_force[0, p]
        s = {
            "cosine": -k * dc,
            "cubic": -k * (dc + 1.2 * dc**3),
            "angle": k * (np.arccos(c) - el.alpha0[0, p]),
        }[law]
        expected += s * (L[l] - L[m]) * np.cross(u[l], u[m])
    T = torque(x, f)
    assert np.linalg.norm(T) > 1e-3 * np.abs(f).max()
    np.testing.assert_allclose(T, expected, rtol=1e-10, atol=1e-13 * np.abs(f).max())


def test_damping_of_rigid_velocity():
    # a rigid velocity field: axial damping sees no stretching rate (zero force), the spec's
    # volume damping -c (v_j - v_b) does damp a rigid rotation (documented behaviour)
    points, tets = tet_soup(2, seed=19)
    el = random_elements(points, tets)
    omega, vel = np.array([0.3, -1.0, 0.5]), np.array([1.0, 2.0, 3.0])
    v = np.cross(omega, points) + vel
    ax = SpringOptions(torsion="off", volume=False, axial_damping=2.0)
    f_ax = springs.internal_forces(points, v, el, ax)
    assert np.abs(f_ax).max() < 1e-12
    vol = SpringOptions(torsion="off", volume_damping=2.0)
    f_vol = springs.internal_forces(points, v, el, vol)
    assert np.abs(f_vol).max() > 0.1
    f_trans = springs.internal_forces(points, np.broadcast_to(vel, points.shape), el, vol)
    assert np.abs(f_trans).max() < 1e-12


# --------------------------------------------------------------------------- torsion laws


def test_angle_law_is_restoring_and_close_to_cosine():
    # near right angles alpha - alpha0 ~ -(c - c0): the angle law (with the sign that makes
    # it restoring) must agree with the cosine law to first order, and do negative work on a
    # small shear from rest. The spec's literal sign -k (alpha - alpha0) would be the
    # opposite force, i.e. anti-restoring.
    points, tets = tet_soup(3, seed=20)
    el = only(random_elements(points, tets), "torsion")
    du = 1e-4 * np.random.default_rng(21).standard_normal(points.shape)
    x = points + du
    f_angle = springs.torsion_forces(x, el, SpringOptions(torsion="angle"))
    f_cos = springs.torsion_forces(x, el, SpringOptions(torsion="cosine"))
    assert rel(f_angle, f_cos) < 1e-3  # O(|du|) relative difference
    assert np.sum(f_angle * du) < 0
    assert np.sum(f_cos * du) < 0


def test_stress_scaled_axial_is_linear_at_small_strain():
    # stress-scaled: E (d/l0) (V/|zeta|) with E = k l0^2/V0 -> -k d at rest; difference O(d^2)
    points, tets = tet_soup(3, seed=22)
    el = only(random_elements(points, tets), "axial")
    x = points + 1e-6 * np.random.default_rng(23).standard_normal(points.shape)
    lin = springs.axial_forces(x, None, el, SpringOptions(axial="linear"))
    ss = springs.axial_forces(x, None, el, SpringOptions(axial="stress-scaled"))
    assert rel(ss, lin) < 1e-5
    x = 1.3 * points  # large stretch: the current cross-section shrinks the force
    lin = springs.axial_forces(x, None, el, SpringOptions(axial="linear"))
    ss = springs.axial_forces(x, None, el, SpringOptions(axial="stress-scaled"))
    assert rel(ss, lin) > 0.1


# --------------------------------------------------------------------------- volume, LMS


@pytest.mark.parametrize("form", ["gradient", "spec"])
@pytest.mark.parametrize("factor", [1.15, 0.85])
def test_volume_spring_restores(form, factor):
    # scale each tet about its barycenter: expanded (factor > 1) must be pulled in,
    # compressed pushed out: sum_j f_j . (x_j - x_b) opposite to the volume change
    points, tets = tet_soup(6, seed=24)
    el = only(random_elements(points, tets), "volume")
    X = points[tets]
    xb = X.mean(axis=1, keepdims=True)
    x = (xb + factor * (X - xb)).reshape(-1, 3)
    f = springs.volume_forces(x, None, el, SpringOptions(), volume_form=form)
    radial = np.einsum("kjc,kjc->k", f.reshape(-1, 4, 3), (x.reshape(-1, 4, 3) - xb))
    assert np.all(np.sign(radial) == -np.sign(factor - 1.0))


def test_lms_rules_and_clamp():
    rng = np.random.default_rng(25)
    m = 50
    k0 = rng.uniform(1.0, 5.0, m)
    V0 = rng.uniform(0.5, 1.0, m)
    L0 = rng.uniform(1.0, 2.0, m)
    for rule in ("spec", "abs"):
        opts = LMSOptions(mu=2.0, k_min=0.2, k_max=5.0, rule=rule)
        for factor, sign in ((0.8, -1), (1.25, +1)):  # compressed, expanded
            k = k0.copy()
            history = []
            for _ in range(200):
                k_new = springs.lms_update(k, k0, factor * V0, V0, factor ** (1 / 3) * L0, L0, opts)
                history.append(k_new / k0)
                k = k_new
            history = np.array(history)
            assert np.all(history >= opts.k_min - 1e-15)
            assert np.all(history <= opts.k_max + 1e-15)
            first = history[0]
            if rule == "abs" or sign > 0:
                assert np.all(first > 1.0)  # stiffens
                np.testing.assert_allclose(history[-1], opts.k_max)
            else:  # the spec's rule softens a compressed element down to the clamp
                assert np.all(first < 1.0)
                np.testing.assert_allclose(history[-1], opts.k_min)


# --------------------------------------------------------------------------- dynamics


def run_symplectic_euler(options: SpringOptions, steps: int):
    """Free small box (48 tets) from a random 4% displacement at rest, kick-drift steps.

    Returns the energies and angular momenta every 20 steps and the scale
    ``max sum_i m_i |x_i| |v_i|`` of the angular momentum.
    """
    mesh = box_mesh((1.0, 1.0, 1.0), (2, 2, 2), split="six")
    el = random_elements(mesh.points, mesh.tets, seed=26, options=options)
    mass = np.bincount(mesh.tets.ravel(), np.repeat(1000.0 * el.V0 / 4, 4), mesh.n_points)
    # highest frequency from the symmetric part of the rest stiffness (finite differences)
    n3 = 3 * mesh.n_points
    K = np.zeros((n3, n3))
    h = 1e-7
    for j in range(n3):
        dx = np.zeros(n3)
        dx[j] = h
        fp = springs.internal_forces(mesh.points + dx.reshape(-1, 3), None, el, options)
        fm = springs.internal_forces(mesh.points - dx.reshape(-1, 3), None, el, options)
        K[:, j] = -(fp - fm).ravel() / (2 * h)
    minv = 1.0 / np.sqrt(np.repeat(mass, 3))
    omega_max = np.sqrt(np.linalg.eigvalsh(0.5 * (K + K.T) * minv[:, None] * minv[None]).max())
    dt = 0.05 / omega_max

    x = mesh.points + 0.04 * np.random.default_rng(27).standard_normal(mesh.points.shape)
    v = np.zeros_like(x)
    energies, momenta, scale = [], [], 0.0
    for step in range(steps):
        v_new = v + dt * springs.internal_forces(x, None, el, options) / mass[:, None]
        if step % 20 == 0:
            v_mid = 0.5 * (v + v_new)
            kinetic = 0.5 * np.sum(mass[:, None] * v_mid**2)
            energies.append(kinetic + springs.spring_energy(x, el, options)[1])
            # sum x_n x m v_{n+1} changes by exactly dt * torque(x_n) per step
            momenta.append(np.cross(x, mass[:, None] * v_new).sum(axis=0))
            scale = max(
                scale, np.sum(mass * np.linalg.norm(x, axis=1) * np.linalg.norm(v_new, axis=1))
            )
        x = x + dt * v_new
        v = v_new
    return np.array(energies), np.array(momenta), scale


@pytest.mark.parametrize(
    "steps", [2_000, pytest.param(10_000, marks=pytest.mark.slow, id="10000-no-drift")]
)
def test_symplectic_euler_conserves_energy_and_angular_momentum(steps):
    # kick-drift symplectic Euler is leapfrog with staggered velocities; the energy at x_n
    # uses the mean of the velocities on either side, whose error is O((omega dt)^2) and
    # bounded (no drift) for conservative forces: 1e-3 relative at any horizon (2000 steps
    # by default, 1e4 in the slow run to show there is no drift). The energy forms have zero
    # net torque, so angular momentum is conserved to round-off.
    options = SpringOptions(axial="cubic", axial_coefficients=(0.5, 0.5), torsion="energy")
    energies, momenta, scale = run_symplectic_euler(options, steps)
    assert energies[0] > 0
    assert np.abs(energies / energies[0] - 1).max() < 1e-3
    assert np.abs(momenta).max() < 1e-10 * scale


def test_cosine_torsion_breaks_angular_momentum_and_energy():
    # the same run with the spec's default torsion law: its net torque spins the free body
    # up (angular momentum from zero to a sizeable fraction of its scale) and the energy is
    # far from conserved within 2000 steps
    options = SpringOptions(axial="cubic", axial_coefficients=(0.5, 0.5), torsion="cosine")
    energies, momenta, scale = run_symplectic_euler(options, 2_000)
    assert np.linalg.norm(momenta[-1]) > 1e-2 * scale
    assert np.abs(energies / energies[0] - 1).max() > 1e-2
