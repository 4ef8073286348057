"""Calibration (springmodel.calibration): material matrices, effective matrix, constants.

Independent references: Hooke's law compliances, the P1 finite-element stiffness
``V B^T C B`` built here from scratch, finite-difference Hessians of the element energy
``W_k(F)``, and the optimality of non-negative least squares.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from springfem import materials
from springfem.mesh import box_mesh
from springmodel import rest_geometry, springs
from springmodel.element_energy import effective_matrix, element_energy_from_F
from springmodel.elements import build_spring_elements
from springmodel.options import SpringOptions

REGULAR = np.array([[1.0, 1, 1], [-1, 1, -1], [1, -1, -1], [-1, -1, 1]])
TRANSVERSE = {
    "law": "transverse-linear",
    "E_fiber": 50e3,
    "E_cross": 10e3,
    "nu_fiber_cross": 0.35,
    "nu_cross": 0.45,
    "G_fiber": 6e3,
}


#: Energy torsion: the specification's cosine law is not a gradient and its tangent has a skew part
#: (tests/springmodel/test_exact.py), so exactness claims are made for the energy forms.
ENERGY = SpringOptions(torsion="energy")


def iso(nu: float, E: float = 1.0e3) -> dict:
    return {"law": "linear", "E": E, "nu": nu}


def p1_gradients(X: np.ndarray) -> np.ndarray:
    """Shape-function gradients of one tet, ``(4, 3)``, from the inverse of [1 x]."""
    M = np.hstack([np.ones((4, 1)), X])
    return np.linalg.inv(M)[1:].T


def p1_stiffness(X: np.ndarray, C: np.ndarray) -> np.ndarray:
    """Linear P1 element stiffness ``V B^T C B`` (12 x 12), engineering-shear Voigt."""
    g = p1_gradients(X)
    B = np.zeros((6, 12))
    for i in range(4):
        dx, dy, dz = g[i]
        B[:, 3 * i : 3 * i + 3] = [
            [dx, 0, 0],
            [0, dy, 0],
            [0, 0, dz],
            [0, dz, dy],
            [dz, 0, dx],
            [dy, dx, 0],
        ]
    V = abs(np.linalg.det(X[1:] - X[0])) / 6
    return V * B.T @ C @ B


def spring_rest_stiffness(el, k: int) -> np.ndarray:
    """Exact rest stiffness ``sum_a k_a grad g_a grad g_a^T`` of element ``k`` (energy forms).

    The measures' gradients are written out here from the rest geometry: axial
    ``G_il zh_l``, torsion ``G_il (zh_m - c zh_l)/l_l + G_im (zh_l - c zh_m)/l_m``, volume
    ``xh_i - mean xh`` (G from the shape gradients, not from C).
    """
    G = p1_gradients(el.xi0[k]) @ el.zeta0[k].T  # (4, 3): grad N_i . zeta0_l (translated tet)
    L = np.linalg.norm(el.zeta0[k], axis=1)
    u = el.zeta0[k] / L[:, None]
    grads, ks = [], []
    for l in range(3):
        grads.append(G[:, l, None] * u[l])
        ks.append(el.k_axial[k, l])
    for p, (l, m) in enumerate([(0, 1), (0, 2), (1, 2)]):
        c = u[l] @ u[m]
        grads.append(
            G[:, l, None] * (u[m] - c * u[l]) / L[l] + G[:, m, None] * (u[l] - c * u[m]) / L[m]
        )
        ks.append(el.k_torsion[k, p])
    xh = el.xi0[k] / np.linalg.norm(el.xi0[k], axis=1)[:, None]
    grads.append(xh - xh.mean(axis=0))
    ks.append(el.k_volume[k])
    K = np.zeros((12, 12))
    for g, kk in zip(grads, ks, strict=True):
        K += kk * np.outer(g.ravel(), g.ravel())
    return K


# --------------------------------------------------------------------------- materials


@pytest.mark.parametrize("nu", [0.0, 0.3, 0.49])
def test_isotropic_matrix_is_hookes_law(nu):
    E = 2.0e3
    S = np.linalg.inv(materials.material_matrix(iso(nu, E)))
    np.testing.assert_allclose(np.diag(S)[:3], 1 / E, rtol=1e-12)
    np.testing.assert_allclose(S[0, 1], -nu / E, rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(np.diag(S)[3:], 2 * (1 + nu) / E, rtol=1e-12)


def test_transverse_matrix_compliance_and_isotropic_limit():
    S = np.linalg.inv(materials.material_matrix(TRANSVERSE))
    t = TRANSVERSE
    np.testing.assert_allclose(S[0, 0], 1 / t["E_fiber"], rtol=1e-12)
    np.testing.assert_allclose(S[1, 1], 1 / t["E_cross"], rtol=1e-12)
    np.testing.assert_allclose(S[0, 1], -t["nu_fiber_cross"] / t["E_fiber"], rtol=1e-12)
    np.testing.assert_allclose(S[1, 2], -t["nu_cross"] / t["E_cross"], rtol=1e-12)
    np.testing.assert_allclose(S[3, 3], 2 * (1 + t["nu_cross"]) / t["E_cross"], rtol=1e-12)
    np.testing.assert_allclose(S[4, 4], 1 / t["G_fiber"], rtol=1e-12)
    same = {
        "law": "transverse-linear",
        "E_fiber": 1e3,
        "E_cross": 1e3,
        "nu_fiber_cross": 0.3,
        "nu_cross": 0.3,
        "G_fiber": 1e3 / 2.6,
    }
    np.testing.assert_allclose(
        materials.material_matrix(same), materials.material_matrix(iso(0.3)), rtol=1e-12, atol=1e-9
    )


def test_transverse_rotation_preserves_energy():
    # energy of a strain in the global frame with the rotated matrix == energy of the same
    # strain expressed in the fibre frame (eps_local = Q eps Q^T) with the local matrix
    rng = np.random.default_rng(0)
    frames = Rotation.random(5, random_state=1).as_matrix()
    C_global = materials.material_matrix(TRANSVERSE, frames)
    C_local = materials.material_matrix(TRANSVERSE)
    for k in range(5):
        eps = rng.standard_normal((3, 3))
        eps = eps + eps.T
        g = materials.strain_voigt(eps)
        g_local = materials.strain_voigt(frames[k] @ eps @ frames[k].T)
        assert g @ C_global[k] @ g == pytest.approx(g_local @ C_local @ g_local, rel=1e-12)
    # fibre along the first axis: the fibre modulus acts along frames[k, 0]
    d = frames[0, 0]
    stress_dir = np.outer(d, d)
    S = np.linalg.inv(C_global[0])
    strain = materials.strain_tensor(S @ materials.voigt_vector(stress_dir))
    assert d @ strain @ d == pytest.approx(1 / TRANSVERSE["E_fiber"], rel=1e-10)


# --------------------------------------------------------------------------- effective matrix


def test_effective_matrix_is_the_energy_hessian():
    # D_k vs the finite-difference Hessian (w.r.t. the engineering Voigt strain) of W_k(F)/V
    # at F = I, on irregular tets with NON-orthogonal axes (c0 != 0) and random constants.
    # Tolerance 1e-6: second differences with h = 1e-4 (O(h^2) truncation).
    rng = np.random.default_rng(2)
    X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    X = X[None] + 0.25 * rng.standard_normal((3, 4, 3))
    X[np.linalg.det(X[:, 1:] - X[:, :1]) < 0] = X[np.linalg.det(X[:, 1:] - X[:, :1]) < 0][
        :, [0, 2, 1, 3]
    ]
    frames = Rotation.random(3, random_state=3).as_matrix() + 0.3 * rng.standard_normal((3, 3, 3))
    frames /= np.linalg.norm(frames, axis=2, keepdims=True)
    tets = np.arange(12).reshape(3, 4)
    el = build_spring_elements(X.reshape(-1, 3), tets, frames, SpringOptions(), iso(0.3))
    assert np.abs(el.c0).max() > 0.05
    ka = rng.uniform(1, 2, (3, 3))
    kt = rng.uniform(1, 2, (3, 3))
    kv = rng.uniform(1, 2, 3)
    D = effective_matrix(el, ka, kt, kv)

    def W(g):
        F = np.eye(3) + materials.strain_tensor(g)
        return element_energy_from_F(np.broadcast_to(F, (3, 3, 3)), el, ka, kt, kv) / el.V0

    h = 1e-4
    H = np.zeros((3, 6, 6))
    E = np.eye(6) * h
    for a in range(6):
        for b in range(6):
            H[:, a, b] = (W(E[a] + E[b]) - W(E[a] - E[b]) - W(-E[a] + E[b]) + W(-E[a] - E[b])) / (
                4 * h * h
            )
    assert np.abs(H - D).max() < 1e-6 * np.abs(D).max()


@pytest.mark.parametrize("nu", [0.0, 0.3, 0.45, 0.49])
def test_analytic_calibration_reproduces_p1_stiffness_on_regular_tet(nu):
    # regular tet (R = rho I), random orthonormal axes, isotropic material: the spring
    # element's rest stiffness equals the P1 element stiffness to round-off (1e-10)
    material = iso(nu)
    for seed in range(3):
        frames = Rotation.random(1, random_state=seed).as_matrix()
        el = build_spring_elements(REGULAR, np.array([[0, 1, 2, 3]]), frames, ENERGY, material)
        K_fem = p1_stiffness(REGULAR, materials.material_matrix(material))
        K_spring = spring_rest_stiffness(el, 0)
        assert np.abs(K_spring - K_fem).max() < 1e-10 * np.abs(K_fem).max()
        assert el.mismatch[0] < 1e-12
        lsq = build_spring_elements(
            REGULAR,
            np.array([[0, 1, 2, 3]]),
            frames,
            SpringOptions(calibration="analytic-lsq", torsion="energy"),
            material,
        )
        np.testing.assert_allclose(lsq.k_volume, el.k_volume, rtol=1e-12, atol=1e-12)
        # the constants of docs/calibration.rst#analytic-calibration
        mu = 1e3 / (2 * (1 + nu))
        lam = 1e3 * nu / ((1 + nu) * (1 - 2 * nu))
        V, l0 = el.V0[0], el.l0[0]
        rho = np.trace(rest_geometry.radial_tensor(el.xi0)[0]) / 3
        np.testing.assert_allclose(el.k_axial[0], 2 * mu * V / l0**2, rtol=1e-12)
        np.testing.assert_allclose(el.k_torsion[0], mu * V, rtol=1e-12)
        np.testing.assert_allclose(el.k_volume[0], lam * V / rho**2, rtol=1e-12, atol=1e-12)


def test_spring_forces_linearise_to_p1_stiffness():
    # links the force code to the check above: finite differences of the oracle's forces
    # (energy forms) at rest == P1 stiffness; 1e-6 relative (central differences)
    material = iso(0.3)
    frames = Rotation.random(1, random_state=7).as_matrix()
    el = build_spring_elements(REGULAR, np.array([[0, 1, 2, 3]]), frames, None, material)
    options = SpringOptions(torsion="energy")
    K = np.zeros((12, 12))
    h = 1e-6
    for j in range(12):
        dx = np.zeros(12)
        dx[j] = h
        fp = springs.internal_forces(REGULAR + dx.reshape(4, 3), None, el, options)
        fm = springs.internal_forces(REGULAR - dx.reshape(4, 3), None, el, options)
        K[:, j] = -(fp - fm).ravel() / (2 * h)
    K_fem = p1_stiffness(REGULAR, materials.material_matrix(material))
    assert np.abs(K - K_fem).max() < 1e-6 * np.abs(K_fem).max()


def test_transverse_analytic_mismatch_on_regular_tet():
    # on a regular tet the only mismatch left by the analytic calibration is the single
    # volume-spring off-diagonal b = mean(C01, C02, C12) standing in for C01 = C02 != C12;
    # the expected value is computed from the frame-local matrix
    frames = Rotation.random(1, random_state=4).as_matrix()
    el = build_spring_elements(REGULAR, np.array([[0, 1, 2, 3]]), frames, ENERGY, TRANSVERSE)
    C = materials.material_matrix(TRANSVERSE)
    b = (2 * C[0, 1] + C[1, 2]) / 3
    expected = np.sqrt(4 * (C[0, 1] - b) ** 2 + 2 * (C[1, 2] - b) ** 2) / np.linalg.norm(
        materials.to_mandel(C)
    )
    assert expected > 1e-3
    assert el.mismatch[0] == pytest.approx(expected, rel=1e-9)


# --------------------------------------------------------------------------- NNLS, meshes


@pytest.mark.parametrize(
    "material", [iso(0.3), iso(0.45), TRANSVERSE], ids=["nu0.3", "nu0.45", "transverse"]
)
def test_nnls_is_never_worse_than_analytic(material):
    # nnls minimises the same (Mandel) norm over k >= 0, and the analytic constants are a
    # feasible point: element by element, nnls mismatch <= analytic mismatch (+ round-off)
    mesh = box_mesh((1.0, 1.2, 0.8), (2, 2, 2), split="five")
    rng = np.random.default_rng(5)
    pts = mesh.points + 0.03 * rng.standard_normal(mesh.points.shape)
    frames = Rotation.random(mesh.n_tets, random_state=6).as_matrix()
    a, lsq, n = (
        build_spring_elements(pts, mesh.tets, frames, SpringOptions(calibration=c), material)
        for c in ("analytic", "analytic-lsq", "nnls")
    )
    assert np.all(n.mismatch <= a.mismatch + 1e-9)
    assert np.all(n.mismatch <= lsq.mismatch + 1e-9)
    assert np.all(n.k_axial >= 0) and np.all(n.k_torsion >= 0) and np.all(n.k_volume >= 0)
    assert n.mismatch.mean() < a.mismatch.mean()


def test_box_mesh_mismatch_distributions():
    # five-tet split of cubes: the central tet is regular, so its analytic mismatch is zero
    # for isotropic material; the corner tets are not. Six-tet split: all tets congruent.
    # The numbers are printed (pytest -s) for the report.
    material = iso(0.3)
    rows = []
    for split in ("five", "six"):
        mesh = box_mesh((1.0, 1.0, 1.0), (2, 2, 2), split=split)
        for axes in ("aligned", "random"):
            frames = (
                np.broadcast_to(np.eye(3), (mesh.n_tets, 3, 3))
                if axes == "aligned"
                else Rotation.random(mesh.n_tets, random_state=8).as_matrix()
            )
            for method in ("analytic", "analytic-lsq", "nnls"):
                opts = SpringOptions(calibration=method, torsion="energy")
                el = build_spring_elements(mesh.points, mesh.tets, frames, opts, material)
                q = np.percentile(el.mismatch, [0, 50, 100])
                rows.append((split, axes, method, *q, el.mismatch.mean()))
                if split == "five" and method == "analytic":
                    central = el.mismatch.reshape(-1, 5)[:, 4]
                    corner = el.mismatch.reshape(-1, 5)[:, :4]
                    assert central.max() < 1e-12
                    assert corner.min() > 0.1
                if split == "six" and axes == "aligned":
                    assert np.ptp(el.mismatch) < 1e-9
    for r in rows:
        print("{:5s} {:8s} {:12s} min {:.3f} median {:.3f} max {:.3f} mean {:.3f}".format(*r))


def test_explicit_constants_override_calibration():
    frames = Rotation.random(1, random_state=9).as_matrix()
    opts = SpringOptions(k_axial=2.0, k_torsion=3.0, k_volume=4.0)
    el = build_spring_elements(REGULAR, np.array([[0, 1, 2, 3]]), frames, opts, None)
    np.testing.assert_array_equal(el.k_axial, 2.0)
    np.testing.assert_array_equal(el.k_torsion, 3.0)
    np.testing.assert_array_equal(el.k_volume, 4.0)
    assert np.isnan(el.mismatch).all()
    with pytest.raises(ValueError, match="material"):
        build_spring_elements(
            REGULAR, np.array([[0, 1, 2, 3]]), frames, SpringOptions(k_axial=1.0), None
        )
