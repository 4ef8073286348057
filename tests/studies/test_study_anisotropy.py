"""Tests of the anisotropy study: the off-axis formula and its reference, the blocks'
boundary conditions, the spring model's modulus on a 2³-cell block, and the error split."""

import numpy as np
import pytest

from studies import analytic
from studies.scenes import StudyScene
from studies.study_anisotropy import (
    STUDY,
    VERSION,
    affine_fit,
    fibre_block,
    refusal,
    solve_case,
    split_errors,
    stretch_measures,
)

N = 2
SIGMA = 300.0  # the stretch-fiber traction


@pytest.fixture(scope="module")
def material():
    return fibre_block(0.0, N).build().material


def _solve(angle: float, model: str) -> tuple:
    s = fibre_block(angle, N)
    r = solve_case(s.case(STUDY, VERSION, model=model))
    assert r["status"] == "ok", r.get("message")
    scene = s.build()
    return scene, np.asarray(r["u"]), stretch_measures(scene, np.asarray(r["u"]))


@pytest.mark.parametrize("angle", [0.0, 10.0, 33.0, 45.0, 72.0, 90.0])
def test_rotated_compliance_gives_the_off_axis_formula(material, angle):
    # Two independent routes: the closed-form 1/E(θ) against rotating the 4th-order
    # compliance tensor; and no shear coupling along or across the fibres.
    eps = analytic.off_axis_strain(material, angle, 1.0)
    assert 1.0 / eps[0, 0] == pytest.approx(analytic.off_axis_modulus(material, angle), rel=1e-12)
    if angle in (0.0, 90.0):
        assert abs(eps[0, 1]) < 1e-15


@pytest.mark.parametrize("angle", [0.0, 37.5, 90.0])
def test_off_axis_reference_of_a_rotated_block(material, angle):
    # The hook reads the fibre angle back from the scene's frames and gives the corner's
    # stretch sigma L / E(theta) along x.
    s = fibre_block(angle, N)
    scene = s.build()
    assert analytic.fibre_angle(scene) == pytest.approx(angle, abs=1e-12)
    probe, component, value, _ = analytic.reference(s, scene)
    assert (probe, component) == ("corner", 0)
    assert value == pytest.approx(SIGMA * 0.01 / analytic.off_axis_modulus(material, angle))


def test_affine_fit_recovers_a_homogeneous_strain():
    rng = np.random.default_rng(1)
    X = rng.random((20, 3))
    A = 1e-3 * rng.standard_normal((3, 3))
    eps = affine_fit(X, X @ A.T + [1.0, 2.0, 3.0])
    np.testing.assert_allclose(eps, 0.5 * (A + A.T), atol=1e-14)


@pytest.mark.parametrize("angle, key", [(0.0, "E_fiber"), (90.0, "E_cross")])
def test_fem_modulus_along_and_across_fibres(material, angle, key):
    # P1 represents the homogeneous uniaxial-stress field exactly (patch test): E_f and E_c
    # up to the linear solver's round-off (observed ~1e-14; 1e-9 leaves room for
    # conditioning).
    assert _solve(angle, "P1")[2]["E_eff"] == pytest.approx(getattr(material, key), rel=1e-9)


def test_boundary_conditions_leave_the_off_axis_shear_free(material):
    # At 45° uniaxial stress couples shear; the blocks' supports only remove rigid motion,
    # so FEM reproduces both the off-axis modulus and the shear coupling of the rotated
    # compliance (1e-6: exact up to the linear solver).
    r = _solve(45.0, "P1")[2]
    eps = analytic.off_axis_strain(material, 45.0, 1.0)
    assert r["E_eff"] == pytest.approx(analytic.off_axis_modulus(material, 45.0), rel=1e-6)
    assert r["gamma_xy"] / r["eps_xx"] == pytest.approx(2 * eps[0, 1] / eps[0, 0], rel=1e-6)


@pytest.mark.parametrize("angle", [0.0, 45.0, 90.0])
def test_spring_modulus_is_its_dk_linearisation(angle, dk_reference):
    # The spring model's effective modulus at each fibre angle equals its small-strain
    # answer, the D_k FEM (independent of the force kernel), up to its nonlinear
    # kinematics at the scene's strain: O(strain), tolerance rel = strain (1-3 %;
    # measured 0.14 %, 0.45 %, 1.0 %).
    dk_p1_displacement, _ = dk_reference
    scene = fibre_block(angle, N).build()
    E_dk = stretch_measures(scene, dk_p1_displacement(scene))["E_eff"]
    E = _solve(angle, "spring-analytic")[2]["E_eff"]
    assert E == pytest.approx(E_dk, rel=SIGMA / E_dk)


def test_spring_anisotropy_trend():
    # Monotone trend: the spring model is softer off-axis than along the fibres, and softer
    # still across them (E_f / E_c = 3).
    e0, e45, e90 = (_solve(a, "spring-analytic")[2]["E_eff"] for a in (0.0, 45.0, 90.0))
    assert e0 > e45 > e90


@pytest.mark.parametrize("angle", [0.0, 30.0, 45.0, 72.0, 90.0])
def test_exact_element_with_coupling_follows_the_off_axis_formula(material, angle):
    """The exact element with Poisson coupling equals the transversely isotropic P1 element
    at small strain on any tet, and P1 is exact for this homogeneous field: the spring
    model's effective modulus is the off-axis formula up to its finite-strain kinematics,
    of relative order the applied strain (eps = sigma / E(theta))."""
    E = analytic.off_axis_modulus(material, angle)
    assert _solve(angle, "spring-exact")[2]["E_eff"] == pytest.approx(E, rel=SIGMA / E)


def test_error_split_of_known_errors():
    # Invariants of the split: zero for the reference itself; an error along the fibre at
    # every vertex has no cross part and is its total; the parts add in quadrature.
    scene, u_ref, _ = _solve(30.0, "P1")
    f = scene.frames[0, 0]
    zero = split_errors(scene, u_ref, u_ref)
    assert max(zero.values()) == 0.0
    along = split_errors(scene, u_ref + 1e-6 * f, u_ref)
    assert along["cross"] < 1e-12 * along["fibre"]
    assert along["fibre"] == pytest.approx(1e-6 * np.sqrt(len(u_ref)) / np.linalg.norm(u_ref))
    assert along["strain_fibre"] < 1e-9  # a rigid translation strains nothing
    rng = np.random.default_rng(0)
    any_err = split_errors(scene, u_ref + 1e-6 * rng.standard_normal(u_ref.shape), u_ref)
    assert np.hypot(any_err["fibre"], any_err["cross"]) == pytest.approx(any_err["total"])


def test_refusal_names_what_is_missing():
    iso = StudyScene("ball", {"material": {"law": "linear"}, "axes": {}})
    assert refusal(iso).startswith("scene ball has isotropic material (law linear)")
    bare = StudyScene("t", {"material": {"law": "transverse-linear"}})
    assert refusal(bare).startswith("scene t has no [axes] section")
    assert refusal(fibre_block(30.0, N)) is None
