"""Analytic tangent stiffness (springmodel.hessian) of the conservative spring variants.

Independent references: central finite differences of the numpy oracle forces
(springmodel.springs.internal_forces), rigid-motion invariants, the P1 FEM element stiffness
``V B^T C B`` of a regular tet (docs/calibration.rst#analytic-calibration), scipy's own COO -> CSR
assembly, and the fused
force kernel of a SpringModel.
"""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest
import scipy.sparse as sp

from springfem.mesh import box_mesh
from springmodel.elements import build_spring_elements
from springmodel.hessian import SpringHessian, csr_pattern
from springmodel.options import SpringOptions
from springmodel.springs import internal_forces

MATERIAL = {"law": "linear", "E": 1.0e3, "nu": 0.3}
# Central differences with h = 1e-6 on a unit-size mesh: truncation ~h^2 |f'''| and round-off
# ~eps |f| / h are both ~1e-10 of |K|; 1e-6 leaves margin while any wrong term (O(1)) fails.
FD_RTOL = 1e-6
FD_STEP = 1e-6
CONSERVATIVE = [
    SpringOptions(axial=a, torsion=t, volume=v, axial_coefficients=(0.7, 0.4))
    for a, t, v in itertools.product(("linear", "quadratic", "cubic"), ("off", "energy"), (0, 1))
]


def _id(o: SpringOptions) -> str:
    return f"{o.axial}-{o.torsion}-{'vol' if o.volume else 'novol'}"


# --------------------------------------------------------------------------- helpers


def random_frames(m: int, rng: np.random.Generator) -> np.ndarray:
    """Random right-handed orthonormal frames (rows = axes) from QR of Gaussian matrices."""
    q, r = np.linalg.qr(rng.standard_normal((m, 3, 3)))
    q = q * np.sign(np.diagonal(r, axis1=1, axis2=2))[:, None, :]
    q[np.linalg.det(q) < 0, :, 2] *= -1.0
    return q.transpose(0, 2, 1)


def small_mesh(seed: int = 0):
    """Jittered 2x2x1 six-tet box (18 nodes, 24 tets), positively oriented."""
    rng = np.random.default_rng(seed)
    mesh = box_mesh((1.0, 1.0, 0.6), (2, 2, 1))
    pts = mesh.points + 0.06 * rng.standard_normal(mesh.points.shape)
    X = pts[mesh.tets]
    assert (np.linalg.det(X[:, 1:] - X[:, :1]) > 0).all()
    return pts, mesh.tets


def random_elements(options: SpringOptions, seed: int = 0):
    """Elements on :func:`small_mesh` with random frames and randomly scaled constants."""
    rng = np.random.default_rng(seed + 100)
    pts, tets = small_mesh(seed)
    m = tets.shape[0]
    el = build_spring_elements(pts, tets, random_frames(m, rng), options, MATERIAL)
    el.k_axial = rng.uniform(0.5, 2.0, (m, 3)) * el.k_axial
    el.k_torsion = rng.uniform(0.5, 2.0, (m, 3)) * el.k_torsion
    el.k_volume = rng.uniform(0.5, 2.0, m) * el.k_volume
    el.k_volume0 = el.k_volume.copy()
    return pts, el


def deformed(pts: np.ndarray, seed: int = 0, amount: float = 0.2) -> np.ndarray:
    """A large random affine deformation plus node noise (every spring strained)."""
    rng = np.random.default_rng(seed + 200)
    F = np.eye(3) + amount * rng.standard_normal((3, 3))
    assert np.linalg.det(F) > 0.3
    return pts @ F.T + 0.05 * rng.standard_normal(pts.shape)


def fd_stiffness(x: np.ndarray, el, options: SpringOptions, h: float = FD_STEP) -> np.ndarray:
    """``-d forces / dx`` by central differences of the numpy oracle, dense ``(3n, 3n)``."""
    n = x.size
    K = np.empty((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        fp = internal_forces(x + e.reshape(-1, 3), None, el, options).ravel()
        fm = internal_forces(x - e.reshape(-1, 3), None, el, options).ravel()
        K[:, j] = -(fp - fm) / (2 * h)
    return K


def rel_err(A: np.ndarray, B: np.ndarray) -> float:
    return float(np.abs(A - B).max() / np.abs(B).max())


# --------------------------------------------------------------------------- finite differences


@pytest.mark.parametrize("options", CONSERVATIVE, ids=_id)
def test_matches_finite_differences_of_forces(options):
    pts, el = random_elements(options)
    x = deformed(pts)
    K = SpringHessian(el, options).matrix(x).toarray()
    assert rel_err(K, fd_stiffness(x, el, options)) < FD_RTOL


@pytest.mark.parametrize("part", ["axial", "torsion", "volume"])
def test_each_part_alone_matches_finite_differences(part):
    """One part at a time, so that a small wrong term cannot hide behind a larger part."""
    options = SpringOptions(axial="cubic", axial_coefficients=(0.7, 0.4), torsion="energy")
    pts, el = random_elements(options, seed=3)
    zero = {
        "axial": {"k_torsion": 0 * el.k_torsion, "k_volume": 0 * el.k_volume},
        "torsion": {"k_axial": 0 * el.k_axial, "k_volume": 0 * el.k_volume},
        "volume": {"k_axial": 0 * el.k_axial, "k_torsion": 0 * el.k_torsion},
    }[part]
    el = dataclasses.replace(el, **zero)
    x = deformed(pts, seed=3, amount=0.3)
    K = SpringHessian(el, options).matrix(x).toarray()
    assert np.abs(K).max() > 0
    assert rel_err(K, fd_stiffness(x, el, options)) < FD_RTOL


@pytest.mark.parametrize("options", CONSERVATIVE[-2:], ids=_id)
def test_numba_kernel_matches_numpy_reference(options):
    pts, el = random_elements(options, seed=5)
    x = deformed(pts, seed=5)
    Kn = SpringHessian(el, options, backend="numba").element_matrices(x)
    Kp = SpringHessian(el, options, backend="numpy").element_matrices(x)
    # same formulas, different summation order: round-off only
    assert rel_err(Kn, Kp) < 1e-12
    # the serial and parallel drivers run the same per-element code: identical bits
    for par in (False, True):
        Ks = SpringHessian(el, options, parallel=par).element_matrices(x)
        assert np.array_equal(Ks, Kn)


# --------------------------------------------------------------------------- invariants


@pytest.mark.parametrize("options", CONSERVATIVE[-2:], ids=_id)
def test_symmetric(options):
    pts, el = random_elements(options, seed=1)
    K = SpringHessian(el, options).matrix(deformed(pts, seed=1))
    # element matrices are symmetrised and summed in the same order for (r, c) and (c, r)
    assert abs(K - K.T).max() <= 1e-14 * abs(K).max()


@pytest.mark.parametrize("options", CONSERVATIVE, ids=_id)
def test_rigid_translation_is_a_null_mode_at_any_state(options):
    pts, el = random_elements(options, seed=2)
    x = deformed(pts, seed=2)
    K = SpringHessian(el, options).matrix(x)
    scale = abs(K).max() * np.sqrt(x.size)
    for c in range(3):
        t = np.zeros_like(x)
        t[:, c] = 1.0
        assert np.linalg.norm(K @ t.ravel()) < 1e-12 * scale


@pytest.mark.parametrize("options", CONSERVATIVE, ids=_id)
def test_infinitesimal_rotation_is_a_null_mode_at_rest(options):
    pts, el = random_elements(options, seed=4)
    K = SpringHessian(el, options).matrix(pts)
    scale = abs(K).max() * np.linalg.norm(pts - pts.mean(0)) * 3
    for w in np.eye(3):
        rot = np.cross(w, pts - pts.mean(axis=0))
        assert np.linalg.norm(K @ rot.ravel()) < 1e-12 * scale


@pytest.mark.parametrize("options", CONSERVATIVE[-2:], ids=_id)
def test_rotation_of_a_stressed_state_turns_the_forces(options):
    """Objectivity ``f(R x) = R f(x)`` gives ``K (w x x) = -(w x f)`` at any state."""
    pts, el = random_elements(options, seed=6)
    x = deformed(pts, seed=6)
    f = internal_forces(x, None, el, options)
    K = SpringHessian(el, options).matrix(x)
    w = np.array([0.3, -0.7, 0.5])
    Kr = (K @ np.cross(w, x).ravel()).reshape(-1, 3)
    assert np.abs(f).max() > 0
    assert rel_err(Kr, -np.cross(w, f)) < 1e-10


# --------------------------------------------------------------------------- FEM equivalence


def p1_stiffness(X: np.ndarray, E: float, nu: float) -> np.ndarray:
    """P1 element stiffness ``V B^T C B`` (Voigt xx, yy, zz, yz, xz, xy; engineering shear)."""
    M = np.hstack([np.ones((4, 1)), X])
    grad = np.linalg.inv(M)[1:].T  # (4, 3): grad N_i
    B = np.zeros((6, 12))
    for i, (gx, gy, gz) in enumerate(grad):
        c = 3 * i
        B[0, c], B[1, c + 1], B[2, c + 2] = gx, gy, gz
        B[3, c + 1], B[3, c + 2] = gz, gy
        B[4, c], B[4, c + 2] = gz, gx
        B[5, c], B[5, c + 1] = gy, gx
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    C = np.diag([2 * mu] * 3 + [mu] * 3)
    C[:3, :3] += lam
    V = abs(np.linalg.det(X[1:] - X[0])) / 6
    return V * B.T @ C @ B


@pytest.mark.parametrize("nu", [0.0, 0.3, 0.45])
def test_regular_tet_at_rest_equals_p1_fem(nu):
    """docs/calibration.rst#analytic-calibration: with orthonormal axes and an isotropic radial
    tensor the analytically
    calibrated energy variant is the isotropic P1 element."""
    rng = np.random.default_rng(int(nu * 100))
    X = np.array([[1.0, 1, 1], [-1, 1, -1], [1, -1, -1], [-1, -1, 1]])
    X = 0.37 * X @ random_frames(1, rng)[0] + rng.standard_normal(3)
    if np.linalg.det(X[1:] - X[0]) < 0:
        X = X[[0, 2, 1, 3]]
    tets = np.array([[0, 1, 2, 3]])
    E = 2.5e3
    options = SpringOptions(torsion="energy", volume=True)
    for frame in random_frames(3, rng):
        el = build_spring_elements(X, tets, frame[None], options, {"E": E, "nu": nu})
        K = SpringHessian(el, options).matrix(X).toarray()
        assert rel_err(K, p1_stiffness(X, E, nu)) < 1e-10


# --------------------------------------------------------------------------- structure, LMS


def test_pattern_matches_scipy_assembly():
    options = SpringOptions(torsion="energy")
    pts, el = random_elements(options, seed=7)
    H = SpringHessian(el, options)
    x = deformed(pts, seed=7)
    Ke = H.element_matrices(x)
    dofs = (3 * el.tets[:, :, None] + np.arange(3)).reshape(-1, 12)
    rows = np.repeat(dofs, 12, axis=1).ravel()
    cols = np.tile(dofs, (1, 12)).ravel()
    ref = sp.coo_matrix((Ke.ravel(), (rows, cols)), shape=H.shape).tocsr()
    ref.sum_duplicates()
    K = H.matrix(x)
    assert K.has_canonical_format
    np.testing.assert_array_equal(K.indptr, ref.indptr)
    np.testing.assert_array_equal(K.indices, ref.indices)
    np.testing.assert_allclose(K.data, ref.data, rtol=1e-13, atol=1e-13 * abs(ref.data).max())
    # summing chunk by chunk (bounded memory) changes only the order of the additions
    Kc = SpringHessian(el, options, chunk=5).matrix(x)
    np.testing.assert_array_equal(Kc.indices, K.indices)
    np.testing.assert_allclose(Kc.data, K.data, rtol=1e-13, atol=1e-13 * abs(K.data).max())
    indptr, indices, index_map = csr_pattern(el.tets, el.n_points)
    assert index_map.shape == (el.n_elements, 144) and index_map.max() < indices.size


def test_volume_constants_are_read_at_call_time():
    options = SpringOptions(torsion="energy")
    pts, el = random_elements(options, seed=8)
    x = deformed(pts, seed=8)
    H = SpringHessian(el, options)
    K_old = H.matrix(x).toarray()
    kv = el.k_volume * np.random.default_rng(8).uniform(2.0, 5.0, el.n_elements)
    el_new = el.with_volume_stiffness(kv)
    K_fd = fd_stiffness(x, el_new, options)
    assert rel_err(K_old, K_fd) > 1e-2  # the change matters
    assert rel_err(H.matrix(x, k_volume=kv).toarray(), K_fd) < FD_RTOL
    H.set_volume_stiffness(kv)
    assert rel_err(H.matrix(x).toarray(), K_fd) < FD_RTOL
    H.set_volume_stiffness(None)
    el.k_volume = kv  # mutating the shared elements is seen too
    assert rel_err(H.matrix(x).toarray(), K_fd) < FD_RTOL


@pytest.mark.parametrize(
    "change",
    [{"torsion": "cosine"}, {"axial": "stress-scaled"}, {"volume_form": "spec"},
     {"volume_damping": 0.1}],
)  # fmt: skip
def test_refuses_non_conservative_options(change):
    options = dataclasses.replace(SpringOptions(torsion="energy"), **change)
    _, el = random_elements(SpringOptions(torsion="energy"))
    with pytest.raises(ValueError, match="conservative"):
        SpringHessian(el, options)


SCENE = {
    "name": "small",
    "mesh": {"generator": "box", "size": [0.1, 0.02, 0.02], "divisions": [4, 2, 2]},
    "material": {"law": "linear", "E": 1.0e4, "nu": 0.3},
    "axes": {"fiber": [1.0, 0.2, 0.0], "sheet": [0.0, 1.0, 0.3]},
    "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
    "load": [{"type": "traction", "region": "x_max", "value": [0.0, 0.0, -0.1]}],
    # the coefficients of test_fastkernels' cubic variant: one compiled kernel for both
    "spring": {"torsion": "energy", "axial": "cubic", "axial_coefficients": [0.6, 0.4]},
}


def test_spring_model_stiffness_is_the_tangent_of_its_fused_kernel():
    from springfem.scene import scene_from_dict
    from springmodel.model import SpringModel

    model = SpringModel(scene_from_dict(SCENE), parallel=False)
    rng = np.random.default_rng(9)
    x = deformed(model.x0 / 0.1, seed=9) * 0.1
    K = model.stiffness(x)
    assert K is not None
    h = 1e-6 * 0.1
    for _ in range(3):
        v = rng.standard_normal(x.shape)
        df = (model.forces(x + h * v, None) - model.forces(x - h * v, None)) / (2 * h)
        assert rel_err(K @ v.ravel(), -df.ravel()) < FD_RTOL
