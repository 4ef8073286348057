"""Tissue laws (Guccione, Holzapfel–Ogden): stress = d energy, tangent = d stress (central
finite differences), frame indifference and material symmetry, and the small-strain tangent
the law table derives (:func:`springfem.materials.laws.small_strain_tangent`) against the
closed forms written out here."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from springfem.materials import rotate_to_global, tensor_to_voigt
from springfem.materials.laws import Guccione, HolzapfelOgden, small_strain_tangent

HO = dict(a=1.0, b=2.0, a_f=2.0, b_f=3.0, a_s=1.5, b_s=2.5, a_fs=0.5, b_fs=1.5)
GU = dict(C=2.0, b_f=8.0, b_t=2.0, b_fs=4.0)
LAWS = [
    Guccione(**GU, kappa=50.0, volumetric="log"),
    Guccione(**GU, kappa=0.0),
    HolzapfelOgden(**HO, kappa=30.0, volumetric="simo-taylor"),
    HolzapfelOgden(**HO, kappa=30.0, volumetric="quadratic"),
    HolzapfelOgden(**HO, kappa=0.0),
]
RNG = np.random.default_rng(11)
# Several deformations with fibres and sheets in tension and in compression.
FS = np.eye(3) + 0.25 * RNG.standard_normal((6, 3, 3))
FRAMES = Rotation.random(6, random_state=3).as_matrix()


def guccione_tangent(C, b_f, b_t, b_fs, kappa=0.0):
    """Closed form: ``W ~ C/2 Q`` at small strain, so ``D = diag(C b_f, C b_t, C b_t,
    C b_t / 2, C b_fs / 2, C b_fs / 2)`` plus ``kappa`` on the normal block."""
    D = np.diag([C * b_f, C * b_t, C * b_t, C * b_t / 2, C * b_fs / 2, C * b_fs / 2])
    D[:3, :3] += kappa
    return D


def holzapfel_ogden_tangent(a, b, a_f, b_f, a_s, b_s, a_fs, b_fs, kappa=0.0, tension=True):
    """Closed form: the isochoric term is a neo-Hookean deviator of shear modulus ``a``;
    the fibre and sheet terms add ``4 a_f``, ``4 a_s`` (``I4 - 1 = 2 E``) in tension, the
    fs term ``a_fs`` to the fs shear (``I8 = 2 E_fs``); ``U''(1) = kappa``."""
    D = np.zeros((6, 6))
    D[:3, :3] = 2.0 * a * (np.eye(3) - 1.0 / 3.0) + kappa
    D[3:, 3:] = a * np.eye(3)
    if tension:
        D[0, 0] += 4.0 * a_f
        D[1, 1] += 4.0 * a_s
    D[5, 5] += a_fs
    return D


@pytest.mark.parametrize("kappa", [0.0, 40.0])
@pytest.mark.parametrize("tension", [True, False])
def test_the_table_small_strain_tangent_is_the_closed_form(kappa, tension):
    D = small_strain_tangent("guccione", GU, kappa=kappa)
    assert np.allclose(D, guccione_tangent(**GU, kappa=kappa), rtol=1e-14, atol=0)
    D = small_strain_tangent("holzapfel-ogden", HO, kappa=kappa, tension=tension)
    closed = holzapfel_ogden_tangent(**HO, kappa=kappa, tension=tension)
    assert np.allclose(D, closed, rtol=1e-14, atol=1e-14 * abs(closed).max())


def test_the_table_lists_each_law_with_its_constants():
    from springfem.materials.laws import TISSUE_LAWS
    from springfem.scene import LAWS

    assert TISSUE_LAWS["guccione"] == tuple(GU)
    assert TISSUE_LAWS["holzapfel-ogden"] == tuple(HO)
    assert {"guccione", "holzapfel-ogden", "linear", "neo-hookean"} <= set(LAWS)


def _fd(fun, F, h=1e-6):
    """Central differences of ``fun`` w.r.t. each ``F_kL``, stacked on the last two axes."""
    out = []
    for k in range(3):
        for L in range(3):
            d = np.zeros((3, 3))
            d[k, L] = h
            out.append((fun(F + d) - fun(F - d)) / (2 * h))
    out = np.array(out)
    return np.moveaxis(out.reshape((3, 3) + out.shape[1:]), (0, 1), (-2, -1))


@pytest.mark.parametrize("law", LAWS, ids=lambda law: law.name)
@pytest.mark.parametrize("i", range(len(FS)))
def test_stress_and_tangent_are_derivatives(law, i):
    F, R = FS[i], FRAMES[i]
    P, A = law.stress_tangent(F, R)
    # h = 1e-6: central differences are accurate to ~h^2 |d3W| + eps |W| / h ~ 1e-9 relative
    assert np.allclose(P, _fd(lambda G: law.energy(G, R), F), rtol=1e-7, atol=1e-7 * abs(P).max())
    A_fd = _fd(lambda G: law.stress(G, R), F)
    assert np.allclose(A, A_fd, rtol=1e-6, atol=1e-7 * abs(A).max())
    # the tangent of a hyperelastic law has the major symmetry A_iJkL = A_kLiJ
    assert np.allclose(A, A.transpose(2, 3, 0, 1), atol=1e-12 * abs(A).max())


@pytest.mark.parametrize("law", LAWS, ids=lambda law: law.name)
def test_frame_indifference_and_material_symmetry(law):
    Q = Rotation.random(random_state=5).as_matrix()
    F, R = FS, FRAMES
    W = law.energy(F, R)
    # a rigid rotation after the deformation: same energy, P rotated
    assert np.allclose(law.energy(Q @ F, R), W, rtol=1e-12)
    assert np.allclose(law.stress(Q @ F, R), Q @ law.stress(F, R), atol=1e-12)
    # body and fibres rotated together: the same material response (F' = Q F Q^T, R' = R Q^T)
    assert np.allclose(law.energy(Q @ F @ Q.T, R @ Q.T), W, rtol=1e-12)


def test_stress_free_reference_and_inversion_is_nan():
    for law in LAWS:
        assert abs(law.stress(np.eye(3))).max() < 1e-14
        assert np.isnan(law.stress(np.diag([1.0, 1.0, -1.0]))).all()


@pytest.mark.parametrize("kappa", [0.0, 40.0])
def test_guccione_small_strain_tangent_is_the_closed_form(kappa):
    law = Guccione(**GU, kappa=kappa)
    R = FRAMES[:2]
    _, A = law.stress_tangent(np.tile(np.eye(3), (2, 1, 1)), R)
    D = rotate_to_global(guccione_tangent(**GU, kappa=kappa), R)
    assert np.allclose(tensor_to_voigt(A), D, atol=1e-12)


def test_holzapfel_ogden_small_strain_tangent_both_sides():
    law = HolzapfelOgden(**HO, kappa=25.0)
    R = FRAMES[:1]
    # exactly at F = I the fibre and sheet terms are off (tension only: I4 > 1)
    _, A = law.stress_tangent(np.eye(3), R)
    D_off = rotate_to_global(holzapfel_ogden_tangent(**HO, kappa=25.0, tension=False), R)
    assert np.allclose(tensor_to_voigt(A), D_off, atol=1e-12)
    # a tiny stretch along fibre and sheet switches them on; the tangent moves by O(delta)
    delta = 1e-7
    F = np.eye(3) + delta * (np.outer(R[0, 0], R[0, 0]) + np.outer(R[0, 1], R[0, 1]))
    _, A = law.stress_tangent(F, R)
    D_on = rotate_to_global(holzapfel_ogden_tangent(**HO, kappa=25.0, tension=True), R)
    assert np.allclose(tensor_to_voigt(A), D_on, atol=1e-4)


def test_holzapfel_ogden_fibres_carry_no_compression():
    soft = HolzapfelOgden(**{**HO, "a_f": 0.0, "a_s": 0.0}, kappa=30.0)
    law = HolzapfelOgden(**HO, kappa=30.0)
    F = np.diag([0.9, 0.95, 1.0 / (0.9 * 0.95)])  # fibre and sheet shortened, I8 = 0
    assert np.allclose(law.stress(F), soft.stress(F), atol=1e-14)
    F = np.diag([1.1, 0.95, 1.0])  # fibre in tension: stiffer along it
    assert law.stress(F)[0, 0] > soft.stress(F)[0, 0] + 0.1


@pytest.mark.parametrize(
    "module",
    [
        "springfem.materials.laws",
        "springfem.materials.laws.guccione",
        "springfem.materials.laws.holzapfel_ogden",
        "springfem.materials.laws.kinematics",
        "springfem.materials.laws.base",
        "springfem.materials.tissue",
    ],
)
def test_doctests(module):
    import doctest
    import importlib

    assert doctest.testmod(importlib.import_module(module)).failed == 0
