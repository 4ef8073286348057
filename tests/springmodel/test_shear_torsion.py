"""The ``shear`` torsion law: an energy of the axis angle that stays convex at large shear.

The ``energy`` torsion law ``U = k/2 (c - c0)^2`` (``c`` the cosine of the angle between two
axes) has ``U = k/2 sin^2 g`` in a pure shear by ``g``: its moment ``k/2 sin 2g`` peaks at
``g = 45 deg`` and the element loses its shear stiffness beyond (the land-ventricle scene's
Newton stalls exactly there). ``shear`` is ``U = k/2 delta^2`` with
``delta = s0^3 (cot(theta) - cot(theta0))``, ``s0 = sin(theta0)``: quadratic in the
simple-shear amount ``cot(theta)`` between the axes, with the same small-strain tangent.

References used here: central finite differences of that energy written independently in
this file from the axis vectors ``zeta_l = sum_i G_il x_i``, and the ``energy`` law near rest
(same small-strain tangent).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from springfem.mesh import box_mesh
from springmodel.elements import build_spring_elements
from springmodel.hessian import SpringHessian
from springmodel.options import SpringOptions
from springmodel.rest_geometry import TORSION_PAIRS
from springmodel.spring_kernel import SpringKernel
from springmodel.springs import is_conservative, spring_energy, torsion_forces

MATERIAL = {"law": "linear", "E": 1.0e3, "nu": 0.3}


def _setup(torsion: str):
    mesh = box_mesh((1.0, 1.3, 0.7), (2, 2, 1), split="five")
    rng = np.random.default_rng(3)
    points = mesh.points + 0.04 * rng.standard_normal(mesh.points.shape)
    frames = Rotation.random(mesh.n_tets, random_state=2).as_matrix()
    opts = SpringOptions(torsion=torsion, volume=False)
    el = build_spring_elements(points, mesh.tets, frames, opts, MATERIAL)
    return points, el, opts


def _torsion_energy(x: np.ndarray, rest: np.ndarray, el) -> float:
    """The shear energy from the axis vectors, independent of the kernels."""
    zeta = np.einsum("kil,kic->klc", el.G, x[el.tets])
    z0 = np.einsum("kil,kic->klc", el.G, rest[el.tets])
    total = 0.0
    for p, (a, b) in enumerate(TORSION_PAIRS):
        c = np.einsum("kc,kc->k", zeta[:, a], zeta[:, b]) / (
            np.linalg.norm(zeta[:, a], axis=1) * np.linalg.norm(zeta[:, b], axis=1)
        )
        c0 = np.einsum("kc,kc->k", z0[:, a], z0[:, b]) / (
            np.linalg.norm(z0[:, a], axis=1) * np.linalg.norm(z0[:, b], axis=1)
        )
        s03 = (1 - c0**2) ** 1.5
        delta = s03 * (c / np.sqrt(1 - c**2) - c0 / np.sqrt(1 - c0**2))
        total += float(np.sum(0.5 * el.k_torsion[:, p] * delta**2))
    return total


@pytest.fixture(scope="module")
def shear_model():
    points, el, opts = _setup("shear")
    off = SpringKernel(el, SpringOptions(torsion="off", volume=False))
    return points, el, SpringKernel(el, opts), off


def test_shear_forces_are_minus_the_gradient_of_the_energy(shear_model):
    """Large random deformation (axis angles change by up to ~40 deg): the kernel's torsion
    forces (shear minus torsion off) equal -dU/dx by central differences. Tolerance 1e-6
    relative: central differences with h = 1e-6 of an energy of size ~1 (O(h^2) truncation
    plus roundoff ~1e-16/h = 1e-10)."""
    points, el, kernel, off = shear_model
    rng = np.random.default_rng(7)
    x = points @ Rotation.random(random_state=5).as_matrix().T
    x = x + 0.25 * rng.standard_normal(x.shape)
    f = kernel.forces(x) - off.forces(x)
    h = 1e-6
    g = np.zeros_like(x)
    for i in range(x.shape[0]):
        for c in range(3):
            xp, xm = x.copy(), x.copy()
            xp[i, c] += h
            xm[i, c] -= h
            g[i, c] = (_torsion_energy(xp, points, el) - _torsion_energy(xm, points, el)) / (2 * h)
    assert np.abs(f + g).max() <= 1e-6 * np.abs(g).max()


def test_shear_has_the_energy_laws_small_strain_tangent():
    """At rest both laws have dU/dc = 0 and d2U/dc2 = k (c0 = 0 here: orthonormal frames),
    so the forces of a small deformation agree to second order: with strain 1e-5 the
    difference is O(1e-10) relative (bound 1e-8)."""
    points, el, opts = _setup("shear")
    k_shear = SpringKernel(el, opts)
    k_energy = SpringKernel(el, SpringOptions(torsion="energy", volume=False))
    rng = np.random.default_rng(11)
    x = points + 1e-5 * rng.standard_normal(points.shape)
    f1, f2 = k_shear.forces(x), k_energy.forces(x)
    assert np.abs(f1 - f2).max() <= 1e-8 * np.abs(f2).max()


def _deformed(points: np.ndarray, scale: float) -> np.ndarray:
    rng = np.random.default_rng(7)
    x = points @ Rotation.random(random_state=5).as_matrix().T
    return x + scale * rng.standard_normal(x.shape)


def test_shear_is_conservative_and_its_energy_is_the_independent_one(shear_model):
    """``spring_energy`` (torsion part: shear minus off) equals the energy written in this
    file, to round-off (1e-12 relative: the same closed form evaluated differently)."""
    points, el, _, _ = shear_model
    assert is_conservative(SpringOptions(torsion="shear", volume="axes", coupling=True))
    x = _deformed(points, 0.25)
    w_shear = spring_energy(x, el, SpringOptions(torsion="shear", volume=False))[1]
    w_off = spring_energy(x, el, SpringOptions(torsion="off", volume=False))[1]
    ref = _torsion_energy(x, points, el)
    assert abs(w_shear - w_off - ref) <= 1e-12 * ref


def test_numpy_oracle_forces_equal_the_kernel_and_minus_the_energy_gradient(shear_model):
    """The oracle's shear torsion forces equal the fused kernel's (1e-12 relative: the same
    formula, different summation order) and ``-dU/dx`` of the independent energy by central
    differences (1e-6 relative: h = 1e-6, O(h^2) truncation and 1e-16/h roundoff)."""
    points, el, kernel, off = shear_model
    x = _deformed(points, 0.25)
    f = torsion_forces(x, el, SpringOptions(torsion="shear", volume=False))
    f_kernel = kernel.forces(x) - off.forces(x)
    assert np.abs(f - f_kernel).max() <= 1e-12 * np.abs(f).max()
    h, g = 1e-6, np.zeros_like(x)
    for i in range(x.shape[0]):
        for c in range(3):
            xp, xm = x.copy(), x.copy()
            xp[i, c] += h
            xm[i, c] -= h
            g[i, c] = (_torsion_energy(xp, points, el) - _torsion_energy(xm, points, el)) / (2 * h)
    assert np.abs(f + g).max() <= 1e-6 * np.abs(g).max()


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_shear_hessian_is_minus_the_force_jacobian(backend):
    """Full exact element (axes volume, coupling, shear torsion) under a large deformation
    (axis angles change by tens of degrees, past 45 deg on some tets): the analytic Hessian
    equals the central-difference Jacobian of the kernel forces, ``-df/dx``. Tolerance 1e-6
    of the largest entry: h = 1e-6 (O(h^2) = 1e-12 truncation relative to a second
    derivative of order 1, roundoff 1e-16 |f| / h ~ 1e-10)."""
    points, _, _ = _setup("shear")
    mesh = box_mesh((1.0, 1.3, 0.7), (2, 2, 1), split="five")
    frames = Rotation.random(mesh.n_tets, random_state=2).as_matrix()
    opts = SpringOptions(torsion="shear", volume="axes", coupling=True, calibration="exact")
    el = build_spring_elements(points, mesh.tets, frames, opts, MATERIAL)
    x = _deformed(points, 0.2)
    kernel = SpringKernel(el, opts)
    K = SpringHessian(el, opts, backend=backend).matrix(x).toarray()
    h, n = 1e-6, x.size
    J = np.zeros((n, n))
    for j in range(n):
        xp, xm = x.copy().ravel(), x.copy().ravel()
        xp[j] += h
        xm[j] -= h
        J[:, j] = -(kernel.forces(xp.reshape(x.shape)) - kernel.forces(xm.reshape(x.shape))).ravel()
        J[:, j] /= 2 * h
    zeta = np.einsum("kil,kic->klc", el.G, x[el.tets])
    zh = zeta / np.linalg.norm(zeta, axis=2)[..., None]
    cos = [np.abs(np.einsum("kc,kc->k", zh[:, a], zh[:, b])) for a, b in TORSION_PAIRS]
    assert np.degrees(np.arcsin(np.max(cos))) > 45.0  # the regime where shear matters
    assert np.abs(K - J).max() <= 1e-6 * np.abs(J).max()
