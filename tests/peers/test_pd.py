"""Projective Dynamics against independent references: numpy's SVD for the compiled one, the
nearest-point property of its projections, finite differences of its energy, linear P1 FEM
at small strain, the Newton answer of its own energy (the core's Newton with a
finite-difference Jacobian) and reference_fem's P1 neo-Hookean for its quasi-Newton form, on
a jittered large-rotation cantilever."""

from __future__ import annotations

import tomllib
from importlib import resources

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from peers.pd import PD, PDSettings
from peers.pd.energy import PDEnergy, density, projections, signed_svd
from peers.pd.energy import unit_determinant as unit_determinant_ref
from peers.pd.kernels import local_step, signed_svd3, unit_determinant
from peers.xpbd.constraints import deformation_gradients
from springfem.errors import InputError
from springfem.mechanics import static
from springfem.model_api import plugin_models
from springfem.scene import scene_from_dict


def _cantilever(law="neo-hookean", divisions=(12, 2, 2)):
    """The bundled large-rotation cantilever on a jittered Delaunay mesh of the same box."""
    text = resources.files("studies.scenes").joinpath("cantilever-large-rotation.toml")
    table = tomllib.loads(text.read_text())
    table["mesh"] = {**table["mesh"], "split": "delaunay", "divisions": list(divisions)}
    if law == "linear":
        table["material"] = {k: v for k, v in table["material"].items() if k != "formulation"}
        table["material"]["law"] = "linear"
    return scene_from_dict(table)


@pytest.fixture(scope="module")
def scene():
    return _cantilever()


def _random_F(rng, k):
    F = np.eye(3) + 0.6 * rng.standard_normal((3, 3))
    if k % 3 == 0:
        F[:, 0] *= -np.sign(np.linalg.det(F))  # inverted
    if k % 5 == 0:  # two equal singular values
        F = np.diag([1.3, 1.3, 0.7]) @ Rotation.random(random_state=k).as_matrix()
    return F


def test_compiled_svd_and_unit_determinant_are_numpys():
    """U diag(s) V^T = F with rotations U, V and numpy's signed singular values; the
    compiled Newton for the unit-determinant singular values is numpy's bisection."""
    rng = np.random.default_rng(0)
    for k in range(300):
        F = _random_F(rng, k)
        U, s, Vt = np.empty((3, 3)), np.empty(3), np.empty((3, 3))
        signed_svd3(F, U, s, Vt)
        _, s_ref, _ = signed_svd(F[None])
        np.testing.assert_allclose((U * s) @ Vt, F, atol=1e-12)
        np.testing.assert_allclose([np.linalg.det(U), np.linalg.det(Vt)], 1.0, atol=1e-12)
        np.testing.assert_allclose(s, s_ref[0], atol=1e-12)
        out = np.empty(3)
        unit_determinant(s, out)
        np.testing.assert_allclose(out, unit_determinant_ref(s[None])[0], rtol=1e-12)
        assert np.isclose(np.prod(out), 1.0, rtol=1e-12)


def test_projections_are_the_nearest_points():
    """R is no farther from F than any of 200 random rotations, S (det S = 1) no farther
    than small random moves of S kept on det = 1."""
    rng = np.random.default_rng(1)
    Q = Rotation.random(200, random_state=2).as_matrix()
    for k in range(20):
        F = _random_F(rng, k)
        R, S = projections(F[None])
        assert np.isclose(np.linalg.det(S[0]), 1.0)
        assert np.linalg.norm(F - R[0]) <= np.linalg.norm(F - Q, axis=(1, 2)).min() + 1e-12
        moves = S[0] + 1e-3 * rng.standard_normal((200, 3, 3))
        moves /= np.cbrt(np.linalg.det(moves))[:, None, None]
        assert np.linalg.norm(F - S[0]) <= np.linalg.norm(F - moves, axis=(1, 2)).min()


@pytest.mark.parametrize("energy", ["arap", "neo-hookean"])
def test_forces_are_minus_the_energy_gradient(scene, energy):
    s = PDEnergy(scene, energy)
    rng = np.random.default_rng(3)
    x = s.x0 + 1e-4 * rng.standard_normal(s.x0.shape)  # no element inverted
    f = s.internal(x).ravel()
    h = 1e-8
    for i in rng.choice(f.size, 8, replace=False):
        xp, xm = x.copy().ravel(), x.copy().ravel()
        xp[i] += h
        xm[i] -= h
        fd = (s.strain_energy(xp.reshape(-1, 3)) - s.strain_energy(xm.reshape(-1, 3))) / (2 * h)
        assert abs(fd + f[i]) <= 1e-6 * np.abs(f).max(), (i, fd, f[i])


def test_local_step_is_the_numpy_projection(scene):
    """The kernel's right-hand side sum_e V (2 mu R + 3 lam S) g_a against numpy's."""
    s = PDEnergy(scene)
    x = s.x0 + 1e-3 * np.random.default_rng(4).standard_normal(s.x0.shape)
    b = np.zeros_like(x)
    local_step(x, s.tets, s.G, s.V, s.mu, s.lam, b)
    R, S = projections(deformation_gradients(x, s.tets, s.G))
    p = s.V[:, None, None] * (2 * s.mu * R + 3 * s.lam * S)
    g = np.concatenate([-s.G.sum(axis=1, keepdims=True), s.G], axis=1)
    ref = np.zeros_like(x)
    np.add.at(ref, s.tets, np.einsum("kcd,kad->kac", p, g))
    np.testing.assert_allclose(b, ref, atol=1e-10 * np.abs(ref).max())


def _newton(system):
    info = static(system, tol=1e-10)
    assert info.converged
    return info.x - system.x0


def _error(u, ref):
    return np.abs(u - ref).max() / np.abs(ref).max()


def test_arap_energy_is_linear_elasticity_at_small_strain(scene):
    """psi(I + e B) / e^2 tends to mu |sym B|^2 + lam/2 tr(B)^2 (the scene's linear
    elasticity) for random B: the weights 2 mu V and 3 lam V give the scene's Lame
    constants; the remainder is O(e)."""
    s = PDEnergy(scene)
    B = np.random.default_rng(5).standard_normal((50, 3, 3))
    sym = 0.5 * (B + B.transpose(0, 2, 1))
    linear = s.mu * np.sum(sym**2, axis=(1, 2)) + 0.5 * s.lam * np.trace(B, axis1=1, axis2=2) ** 2
    for e in (1e-3, 1e-4):
        got = density(np.eye(3) + e * B, s.mu, s.lam, "arap") / e**2
        np.testing.assert_allclose(got, linear, rtol=30 * e)


def test_rest_state_is_the_newton_answer_of_its_energy(scene):
    """Default settings (local/global, 40 substeps x 2 of 60 Hz frames): rest equals the
    Newton answer of the ARAP-like energy to 0.1 %, at a tip sag of a quarter of the
    length (large rotation)."""
    ref = _newton(PDEnergy(scene))
    assert np.abs(ref).max() > 0.2 * 0.1
    out = PD(scene).solve()
    assert out.converged and _error(out.u, ref) < 1e-3, _error(out.u, ref)


def test_quasi_newton_rest_state_is_p1_neo_hookean(scene):
    """The quasi-Newton form minimises P1-NH's own energy (the coupled neo-Hookean of
    reference_fem): its rest state equals reference_fem's P1-NH solve on the same mesh to
    1e-4 (what is left is the rest tolerance, 1e-6 of the motion per frame)."""
    from studies import models

    ref = models.run(scene, "P1-NH").u
    out = PD(scene, PDSettings(energy="neo-hookean")).solve()
    assert out.converged and _error(out.u, ref) < 1e-4, _error(out.u, ref)


def test_plug_ins_are_registered_and_refuse_other_laws(scene):
    found = plugin_models()
    pd, pd_nh = found["pd"], found["pd-nh"]
    assert pd.applies(scene) is None and pd_nh.applies(scene) is None
    assert pd.system(scene) is None and {"substeps": 10, "iterations": 2} in pd.sweep  # type: ignore[attr-defined]
    linear = _cantilever("linear")
    assert pd.applies(linear) is None
    assert pd_nh.applies(linear) == "model pd-nh: no linear law; it takes neo-hookean"
    assert pd_nh.with_settings(iterations=3).settings["energy"] == "neo-hookean"  # type: ignore[attr-defined]
    for model in (pd, pd_nh, found["vbd"]):  # one iteration for springfem bench forces
        go, per_tet = model.kernel_pass(scene)  # type: ignore[attr-defined]
        go()
        assert 100 < per_tet < 1000
    with pytest.raises(InputError, match="energy 'stvk' is not one of"):
        PDSettings(energy="stvk")  # type: ignore[arg-type]
