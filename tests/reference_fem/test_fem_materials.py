"""Material matrices and neo-Hookean laws against independent references.

References: closed-form compliance entries and the off-axis modulus formula (textbook
transverse isotropy), finite differences of the energy and of the stress, frame
indifference, and the isotropic linear tensor (tangent at F = I).
"""

import numpy as np
import pytest

from reference_fem.materials import material_matrix
from springfem.axes import rotation_matrix, uniform_frames
from springfem.materials import (
    isotropic_matrix,
    rotate_tensor,
    tensor_to_voigt,
    transverse_compliance,
    voigt_to_tensor,
)
from springfem.materials.laws.neo_hookean import NeoHookean
from springfem.scene import Material

TRANSVERSE = dict(E_fiber=3.0e4, E_cross=1.0e4, nu_fiber_cross=0.3, nu_cross=0.4, G_fiber=5.0e3)
VARIANTS = [
    ("coupled", "log"),
    ("uncoupled", "log"),
    ("uncoupled", "quadratic"),
    ("uncoupled", "simo-taylor"),
]


def transverse_material(**kw):
    params = dict(TRANSVERSE, **kw)
    return Material("transverse-linear", params["E_cross"], params["nu_cross"], **params)


def random_rotations(n, seed=0):
    rng = np.random.default_rng(seed)
    q, r = np.linalg.qr(rng.standard_normal((n, 3, 3)))
    q = q * np.sign(np.diagonal(r, axis1=1, axis2=2))[:, None, :]
    q[np.linalg.det(q) < 0, :, 2] *= -1
    return q


def test_voigt_tensor_round_trip_and_symmetries():
    D = material_matrix(transverse_material(), random_rotations(4))
    C = voigt_to_tensor(D)
    np.testing.assert_array_equal(tensor_to_voigt(C), D)
    # minor and major symmetries of the tensor
    np.testing.assert_allclose(C, C.transpose(0, 2, 1, 3, 4), atol=0)
    np.testing.assert_allclose(C, C.transpose(0, 1, 2, 4, 3), atol=0)
    np.testing.assert_allclose(C, C.transpose(0, 3, 4, 1, 2), rtol=1e-13, atol=1e-9)
    assert (np.linalg.eigvalsh(D) > 0).all()


def test_isotropic_matrix_is_rotation_invariant():
    C = voigt_to_tensor(isotropic_matrix(2.0, 0.27))
    Cr = rotate_tensor(C, random_rotations(5))
    np.testing.assert_allclose(Cr, np.broadcast_to(C, Cr.shape), atol=1e-14)


def test_transverse_reduces_to_isotropic():
    E, nu = 7.0, 0.31
    mat = transverse_material(
        E_fiber=E, E_cross=E, nu_fiber_cross=nu, nu_cross=nu, G_fiber=E / (2 * (1 + nu))
    )
    D = material_matrix(mat, random_rotations(3))
    np.testing.assert_allclose(D, np.broadcast_to(isotropic_matrix(E, nu), D.shape), atol=1e-12)


def test_transverse_compliance_entries_in_fiber_frame():
    mat = transverse_material()
    S = np.linalg.inv(material_matrix(mat, uniform_frames(1, [0, 0, 1], [1, 0, 0]))[0])
    # fiber along z, sheet along x, normal along y
    p = TRANSVERSE
    assert S[2, 2] == pytest.approx(1 / p["E_fiber"], rel=1e-12)
    assert S[0, 0] == pytest.approx(1 / p["E_cross"], rel=1e-12)
    assert S[1, 1] == pytest.approx(1 / p["E_cross"], rel=1e-12)
    assert S[0, 2] == pytest.approx(-p["nu_fiber_cross"] / p["E_fiber"], rel=1e-12)
    assert S[0, 1] == pytest.approx(-p["nu_cross"] / p["E_cross"], rel=1e-12)
    assert S[3, 3] == pytest.approx(1 / p["G_fiber"], rel=1e-12)  # yz: fiber-normal
    assert S[4, 4] == pytest.approx(1 / p["G_fiber"], rel=1e-12)  # xz: fiber-sheet
    assert S[5, 5] == pytest.approx(2 * (1 + p["nu_cross"]) / p["E_cross"], rel=1e-12)
    assert transverse_compliance(*TRANSVERSE.values())[0, 0] == pytest.approx(1 / 3e4)


@pytest.mark.parametrize("deg", [0, 30, 45, 60, 90])
def test_off_axis_modulus_of_rotated_matrix(deg):
    th = np.radians(deg)
    c, s = np.cos(th), np.sin(th)
    frames = uniform_frames(1, [c, s, 0], [-s, c, 0])
    S = np.linalg.inv(material_matrix(transverse_material(), frames)[0])
    p = TRANSVERSE
    inv_E = (
        c**4 / p["E_fiber"]
        + s**4 / p["E_cross"]
        + (1 / p["G_fiber"] - 2 * p["nu_fiber_cross"] / p["E_fiber"]) * s**2 * c**2
    )
    assert S[0, 0] == pytest.approx(inv_E, rel=1e-12)


def test_uniform_frames_give_one_group_per_frame():
    frames = np.concatenate([uniform_frames(3, [1, 0, 0], [0, 1, 0]), random_rotations(2)])
    D = material_matrix(transverse_material(), frames)
    np.testing.assert_array_equal(D[0], D[2])
    assert not np.allclose(D[3], D[4])


# --------------------------------------------------------------------------- neo-Hookean


@pytest.mark.parametrize("form,vol", VARIANTS)
def test_neo_hookean_stress_and_tangent_are_derivatives(form, vol):
    law = NeoHookean(mu=1.3, lam=2.1, formulation=form, volumetric=vol)
    rng = np.random.default_rng(1)
    F = np.eye(3) + 0.3 * rng.standard_normal((6, 3, 3))
    assert (np.linalg.det(F) > 0).all()
    P, A = law.stress_tangent(F)
    np.testing.assert_array_equal(law.stress(F), P)
    h = 1e-6
    P_fd = np.zeros_like(P)
    A_fd = np.zeros_like(A)
    for k in range(3):
        for l in range(3):
            dF = np.zeros((3, 3))
            dF[k, l] = h
            P_fd[..., k, l] = (law.energy(F + dF) - law.energy(F - dF)) / (2 * h)
            A_fd[..., k, l] = (law.stress(F + dF) - law.stress(F - dF)) / (2 * h)
    # central differences: error ~ h^2 |psi'''| ~ 1e-11, round-off ~ 1e-16 / h ~ 1e-10
    np.testing.assert_allclose(P, P_fd, atol=1e-8)
    np.testing.assert_allclose(A, A_fd, atol=1e-8)


@pytest.mark.parametrize("form,vol", VARIANTS)
def test_neo_hookean_tangent_at_identity_is_linear_elasticity(form, vol):
    E, nu = 5.0e3, 0.45
    mat = Material("neo-hookean", E, nu, formulation=form, volumetric=vol)
    law = NeoHookean.from_material(mat)
    P, A = law.stress_tangent(np.eye(3))
    assert np.abs(P).max() == 0.0
    assert law.energy(np.eye(3)) == 0.0
    np.testing.assert_allclose(A, voigt_to_tensor(isotropic_matrix(E, nu)), rtol=1e-13, atol=1e-9)


@pytest.mark.parametrize("form,vol", VARIANTS)
def test_neo_hookean_is_frame_indifferent(form, vol):
    law = NeoHookean(mu=1.0, lam=3.0, formulation=form, volumetric=vol)
    F = np.eye(3) + 0.2 * np.random.default_rng(2).standard_normal((4, 3, 3))
    Q = rotation_matrix([1.0, 2.0, -0.5], 0.7)
    np.testing.assert_allclose(law.energy(Q @ F), law.energy(F), rtol=1e-12)
    np.testing.assert_allclose(law.stress(Q @ F), Q @ law.stress(F), atol=1e-12)
    # Cauchy stress is symmetric
    s = law.cauchy(F)
    np.testing.assert_allclose(s, np.swapaxes(s, -1, -2), atol=1e-12)


def test_neo_hookean_marks_inverted_elements():
    law = NeoHookean(mu=1.0, lam=1.0)
    F = np.stack([np.eye(3), np.diag([1.0, 1.0, -0.5])])
    P, A = law.stress_tangent(F)
    assert np.isfinite(P[0]).all() and np.isnan(P[1]).all()
    assert np.isnan(law.stress(F)[1]).all()
