"""Tests of the anisotropy study: the off-axis formula, its boundary conditions, and the
spring model's anisotropy ratio on a 2³×6-tet cube."""

import numpy as np
import pytest

from studies.study_anisotropy import (
    affine_fit,
    fiber_scene,
    modulus_case,
    off_axis_modulus,
    off_axis_strain,
)

N = 2


@pytest.fixture(scope="module")
def material():
    return fiber_scene(0.0, N).material


def _case(angle: float, model: str) -> dict:
    c = {"angle": angle, "n": N, "model": model}
    c.update({"calibration": "analytic"} if model == "spring" else {"order": 1})
    return modulus_case(c)


@pytest.mark.parametrize("angle", [0.0, 10.0, 33.0, 45.0, 72.0, 90.0])
def test_rotated_compliance_gives_the_off_axis_formula(material, angle):
    # Two independent routes: the closed-form 1/E(θ) against rotating the 4th-order
    # compliance tensor; and no shear coupling along or across the fibers.
    eps = off_axis_strain(material, angle, 1.0)
    assert 1.0 / eps[0, 0] == pytest.approx(off_axis_modulus(material, angle), rel=1e-12)
    if angle in (0.0, 90.0):
        assert abs(eps[0, 1]) < 1e-15


def test_affine_fit_recovers_a_homogeneous_strain():
    rng = np.random.default_rng(1)
    X = rng.random((20, 3))
    A = 1e-3 * rng.standard_normal((3, 3))
    eps = affine_fit(X, X @ A.T + [1.0, 2.0, 3.0])
    np.testing.assert_allclose(eps, 0.5 * (A + A.T), atol=1e-14)


@pytest.mark.parametrize("angle, key", [(0.0, "E_fiber"), (90.0, "E_cross")])
def test_fem_modulus_along_and_across_fibers(material, angle, key):
    # P1 represents the homogeneous uniaxial-stress field exactly (patch test): E_f and E_c
    # up to the linear solver's round-off (observed ~1e-14; 1e-9 leaves room for
    # conditioning).
    r = _case(angle, "fem")
    assert r["status"] == "ok"
    assert r["E_eff"] == pytest.approx(getattr(material, key), rel=1e-9)


def test_boundary_conditions_leave_the_off_axis_shear_free(material):
    # At 45° uniaxial stress couples shear; the scene's supports only remove rigid motion,
    # so FEM reproduces both the off-axis modulus and the shear coupling of the rotated
    # compliance (1e-6: exact up to the linear solver).
    r = _case(45.0, "fem")
    eps = off_axis_strain(material, 45.0, 1.0)
    assert r["E_eff"] == pytest.approx(off_axis_modulus(material, 45.0), rel=1e-6)
    assert r["gamma_xy"] / r["eps_xx"] == pytest.approx(2 * eps[0, 1] / eps[0, 0], rel=1e-6)


def test_spring_anisotropy_ratio_near_analytic(material):
    # Measured: E(0)/E(90) = 3.047 on 2³ and 3³ meshes against E_f/E_c = 3 (+1.6 %, the
    # calibration mismatch of the six-tet split); tolerance 5 %. Along the fibers the
    # axial springs alone carry the load: E(0) within 1 % of E_f.
    e0, e90 = _case(0.0, "spring"), _case(90.0, "spring")
    ratio = e0["E_eff"] / e90["E_eff"]
    assert ratio == pytest.approx(material.E_fiber / material.E_cross, rel=0.05)
    assert e0["E_eff"] == pytest.approx(material.E_fiber, rel=0.01)


def test_spring_off_axis_modulus_within_stated_error(material):
    # Measured -4.8 % at 45° on this mesh (-5.1 % on 4³); the study reports it. Bound 8 %,
    # and the spring model must be softer off-axis than along the fibers (monotone trend).
    r = _case(45.0, "spring")
    assert r["E_eff"] == pytest.approx(off_axis_modulus(material, 45.0), rel=0.08)
    assert r["E_eff"] < _case(0.0, "spring")["E_eff"]
