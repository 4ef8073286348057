"""Spring elements that are exact on any mesh (
docs/theory.rst#the-exact-element-is-the-p1-element).

Independent references: the P1 element stiffness ``V B^T C B`` built here from the shape
gradients (inverse of ``[1 x]``), central finite differences of the oracle forces and of the
energy, the mesh's own tet volumes (for ``J``), and eigenvalues (positive definiteness).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from springfem import materials
from springfem.mesh import box_mesh
from springmodel.elements import build_spring_elements
from springmodel.hessian import SpringHessian
from springmodel.options import SpringOptions
from springmodel.rest_geometry import RestGeometry
from springmodel.springs import internal_forces, spring_energy
from springmodel.tangent import spring_tangent, tangent_basis

ISO = {"law": "linear", "E": 1.0e3, "nu": 0.3}
TRANSVERSE = {
    "law": "transverse-linear",
    "E_fiber": 50e3,
    "E_cross": 10e3,
    "nu_fiber_cross": 0.35,
    "nu_cross": 0.45,
    "G_fiber": 6e3,
}
EXACT = SpringOptions(volume="axes", torsion="energy", calibration="exact")
EXACT_COUPLED = SpringOptions(volume="axes", torsion="energy", calibration="exact", coupling=True)


def p1_gradients(X: np.ndarray) -> np.ndarray:
    """Shape-function gradients ``(4, 3)`` of one tet, from the inverse of ``[1 x]``."""
    return np.linalg.inv(np.hstack([np.ones((4, 1)), X]))[1:].T


def p1_stiffness(X: np.ndarray, C: np.ndarray) -> np.ndarray:
    """``V B^T C B`` (12 x 12) with engineering-shear Voigt ``C``."""
    g = p1_gradients(X)
    B = np.zeros((6, 12))
    for i, (dx, dy, dz) in enumerate(g):
        B[:, 3 * i : 3 * i + 3] = [
            [dx, 0, 0], [0, dy, 0], [0, 0, dz], [0, dz, dy], [dz, 0, dx], [dy, dx, 0],
        ]  # fmt: skip
    return abs(np.linalg.det(X[1:] - X[0])) / 6 * B.T @ C @ B


def random_tets(n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` random positively oriented tets ``(n, 4, 3)``; every third one a sliver."""
    out = []
    while len(out) < n:
        X = rng.standard_normal((4, 3))
        if len(out) % 3 == 2:  # sliver: a square's corners at alternating heights 0, 0.02
            X = np.array([[0.0, 0, 0], [1, 0, 0.02], [1, 1, 0], [0, 1, 0.02]])
            X = X @ Rotation.random(random_state=rng).as_matrix() + rng.standard_normal(3)
        if np.linalg.det(X[1:] - X[0]) < 0:
            X = X[[0, 2, 1, 3]]
        out.append(X)
    return np.array(out)


def fd_stiffness(x, el, opts, h=1e-6):
    n = x.size
    K = np.zeros((n, n))
    for j in range(n):
        d = np.zeros(n)
        d[j] = h
        fp = internal_forces(x + d.reshape(-1, 3), None, el, opts)
        fm = internal_forces(x - d.reshape(-1, 3), None, el, opts)
        K[:, j] = -(fp - fm).ravel() / (2 * h)
    return K


# --------------------------------------------------------------------------- exactness


@pytest.mark.parametrize(
    "material, options",
    [(ISO, EXACT), (ISO, EXACT_COUPLED), (TRANSVERSE, EXACT_COUPLED)],
    ids=["iso", "iso-coupled", "transverse-coupled"],
)
def test_small_strain_element_equals_p1_on_random_tets(material, options):
    # the analytic Hessian at rest vs V B^T C B, random orthonormal frames, slivers included;
    # 1e-10 relative: both are exact formulas (round-off ~1e-14 x the condition of the sliver)
    rng = np.random.default_rng(11)
    for k, X in enumerate(random_tets(12, rng)):
        frame = Rotation.random(1, random_state=100 + k).as_matrix()
        el = build_spring_elements(X, np.array([[0, 1, 2, 3]]), frame, options, material)
        K = SpringHessian(el, options).matrix(X).toarray()
        K_p1 = p1_stiffness(X, materials.material_matrix(material, frame)[0])
        assert np.abs(K - K_p1).max() < 1e-10 * np.abs(K_p1).max()
        assert el.mismatch[0] < 1e-12


def test_transverse_without_coupling_is_not_exact_and_says_so():
    # one axis-volume constant cannot carry C01 = C02 != C12: the mismatch is the expected
    # residual of the off-diagonals (computed here from the frame-local matrix)
    rng = np.random.default_rng(12)
    X = random_tets(1, rng)[0]
    frame = Rotation.random(1, random_state=3).as_matrix()
    el = build_spring_elements(X, np.array([[0, 1, 2, 3]]), frame, EXACT, TRANSVERSE)
    C = materials.material_matrix(TRANSVERSE)
    b = (2 * C[0, 1] + C[1, 2]) / 3
    expected = np.sqrt(4 * (C[0, 1] - b) ** 2 + 2 * (C[1, 2] - b) ** 2) / np.linalg.norm(
        materials.to_mandel(C)
    )
    assert el.mismatch[0] == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize("torsion", ["energy", "cosine"])
def test_tangent_is_the_linearised_force(torsion):
    # spring_tangent (incl. the cosine law's non-symmetric part) gives the element stiffness
    # V0 dN A dN that central differences of the oracle forces give; 1e-6 (h = 1e-6)
    rng = np.random.default_rng(13)
    X = random_tets(1, rng)[0]
    frame = Rotation.random(1, random_state=4).as_matrix()
    opts = SpringOptions(volume=True, torsion=torsion, coupling=True)
    el = build_spring_elements(X, np.array([[0, 1, 2, 3]]), frame, opts, ISO)
    el.k_coupling[:] = rng.uniform(0.1, 1.0, 3) * el.V0[0] * 100
    g = RestGeometry(el.zeta0, el.xi0, el.V0)
    k = np.concatenate([el.k_axial, el.k_torsion, el.k_volume[:, None], el.k_coupling], 1)
    A = spring_tangent(g, k, opts)[0]
    dN = p1_gradients(X)
    K = el.V0[0] * np.einsum("ic,acbd,jd->iajb", dN, A, dN).reshape(12, 12)
    K_fd = fd_stiffness(X, el, opts)
    assert np.abs(K - K_fd).max() < 1e-6 * np.abs(K_fd).max()
    if torsion == "cosine":  # not symmetric: the net torque of the spec's law
        assert np.abs(K - K.T).max() > 1e-3 * np.abs(K).max()


def test_cosine_torsion_is_reported_as_a_mismatch():
    # energy torsion is exact; the cosine law leaves a skew part that the mismatch counts
    rng = np.random.default_rng(14)
    X = random_tets(1, rng)[0]
    frame = Rotation.random(1, random_state=5).as_matrix()
    cos = SpringOptions(volume="axes", torsion="cosine", calibration="exact")
    el = build_spring_elements(X, np.array([[0, 1, 2, 3]]), frame, cos, ISO)
    assert el.mismatch[0] > 1e-3
    assert tangent_basis(el, "cosine", "axes", False).shape == (1, 7, 3, 3, 3, 3)


# --------------------------------------------------------------------------- nnls


@pytest.mark.parametrize("split", ["six", "five"])
def test_nnls_at_nu_049_gives_positive_definite_elements(split):
    # every element's rest stiffness has exactly the six rigid-body zero modes and is
    # positive on the other six (eigenvalues relative to the largest; 1e-9 separates the
    # round-off zeros ~1e-15 from the softest physical mode)
    mesh = box_mesh((1.0, 1.0, 1.0), (2, 2, 2), split=split)
    frames = np.broadcast_to(np.eye(3), (mesh.n_tets, 3, 3))
    opts = SpringOptions(torsion="energy", calibration="nnls")
    el = build_spring_elements(mesh.points, mesh.tets, frames, opts, {"E": 1.0, "nu": 0.49})
    Ke = SpringHessian(el, opts).element_matrices(mesh.points)
    ev = np.linalg.eigvalsh(Ke) / np.abs(Ke).max(axis=(1, 2))[:, None]
    assert np.all(np.abs(ev[:, :6]) < 1e-12)
    assert np.all(ev[:, 6:] > 1e-9)
    assert np.all(el.k_torsion > 0)


# --------------------------------------------------------------------------- large strain


def deformed_mesh(seed: int):
    mesh = box_mesh((1.0, 1.2, 0.8), (2, 2, 2), split="five")
    rng = np.random.default_rng(seed)
    pts = mesh.points + 0.05 * rng.standard_normal(mesh.points.shape)
    frames = Rotation.random(mesh.n_tets, random_state=seed).as_matrix()
    F = np.eye(3) + 0.2 * rng.standard_normal((3, 3))
    x = pts @ F.T + 0.03 * rng.standard_normal(pts.shape)
    return mesh, pts, frames, x


@pytest.mark.parametrize("volumetric", ["quadratic", "log", "simo-taylor"])
def test_axis_volume_ratio_is_the_tet_volume_ratio(volumetric):
    # J from the axes equals the ratio of the mesh's own tet volumes under a large
    # deformation (exact identity, round-off 1e-12); so the energy is V0 U(V/V0)
    from springfem.volumetric import volumetric_energy
    from springmodel.axis_springs import volume_ratio

    mesh, pts, frames, x = deformed_mesh(15)
    opts = SpringOptions(volume="axes", volumetric=volumetric, torsion="off", k_axial=1e-30)
    el = build_spring_elements(pts, mesh.tets, frames, opts, ISO)
    zeta = np.einsum("kil,kic->klc", el.G, x[mesh.tets])
    V = np.linalg.det(x[mesh.tets][:, 1:] - x[mesh.tets][:, :1]) / 6
    np.testing.assert_allclose(volume_ratio(zeta, el.det0), V / el.V0, rtol=1e-12)
    W, _ = spring_energy(x, el, opts)
    U = volumetric_energy(V / el.V0, el.k_axis_volume, volumetric)[0]
    np.testing.assert_allclose(W, el.V0 * U, rtol=1e-9, atol=1e-30)


@pytest.mark.parametrize("volumetric", ["quadratic", "log", "simo-taylor"])
def test_forces_are_minus_energy_gradient(volumetric):
    # central differences of the total energy, h = 1e-6 (error ~1e-10 of |f|); 1e-7
    mesh, pts, frames, x = deformed_mesh(16)
    opts = SpringOptions(
        volume="axes", volumetric=volumetric, torsion="energy", calibration="exact",
        coupling=True, axial="cubic", axial_coefficients=(0.5, 0.3),
    )  # fmt: skip
    el = build_spring_elements(pts, mesh.tets, frames, opts, TRANSVERSE)
    assert np.abs(el.k_coupling).max() > 0
    f = internal_forces(x, None, el, opts)
    h = 1e-6
    g = np.zeros(x.size)
    for j in range(x.size):
        d = np.zeros(x.size)
        d[j] = h
        g[j] = (
            spring_energy(x + d.reshape(-1, 3), el, opts)[1]
            - spring_energy(x - d.reshape(-1, 3), el, opts)[1]
        ) / (2 * h)
    assert np.abs(f.ravel() + g).max() < 1e-7 * np.abs(f).max()
    assert np.abs(f.sum(axis=0)).max() < 1e-10 * np.abs(f).max()  # net force zero


@pytest.mark.parametrize("backend", ["numba", "numpy"])
@pytest.mark.parametrize("volumetric", ["quadratic", "log", "simo-taylor"])
def test_hessian_equals_finite_difference_hessian(volumetric, backend):
    # central differences of the oracle forces, h = 1e-6: 1e-6 relative (see test_hessian)
    mesh, pts, frames, x = deformed_mesh(17)
    opts = SpringOptions(
        volume="axes", volumetric=volumetric, torsion="energy", calibration="exact",
        coupling=True,
    )  # fmt: skip
    el = build_spring_elements(pts, mesh.tets, frames, opts, TRANSVERSE)
    K = SpringHessian(el, opts, backend=backend).matrix(x).toarray()
    K_fd = fd_stiffness(x, el, opts)
    assert np.abs(K - K_fd).max() < 1e-6 * np.abs(K_fd).max()


def test_volume_damping_dissipates_the_volume_rate():
    # the damping force is -eta V0 (dJ/dt) dJ/dx: its power is -eta sum V0 (dJ/dt)^2, with
    # dJ/dt from a central difference of the tet volumes along v (1e-7 relative, h = 1e-6)
    mesh, pts, frames, x = deformed_mesh(18)
    eta = 0.7
    opts = SpringOptions(volume="axes", torsion="off", volume_damping=eta)
    el = build_spring_elements(pts, mesh.tets, frames, opts, ISO)
    v = np.random.default_rng(18).standard_normal(x.shape)
    f_damp = internal_forces(x, v, el, opts) - internal_forces(x, None, el, opts)
    h = 1e-6

    def vol(y):
        return np.linalg.det(y[mesh.tets][:, 1:] - y[mesh.tets][:, :1]) / 6

    Jdot = (vol(x + h * v) - vol(x - h * v)) / (2 * h) / el.V0
    power = np.sum(f_damp * v)
    assert power == pytest.approx(-eta * np.sum(el.V0 * Jdot**2), rel=1e-7)


@pytest.mark.parametrize(
    "parallel",
    # the parallel drivers of these four variants compile ~4 s more; the parallel path is
    # checked by default in test_parallel_kernels.py
    [False, pytest.param(True, marks=pytest.mark.slow)],
)
@pytest.mark.parametrize(
    "volumetric",
    # each case compiles four kernel variants (~8 s); the other two U(J) run with -m slow
    ["quadratic", *(pytest.param(v, marks=pytest.mark.slow) for v in ("log", "simo-taylor"))],
)
def test_fused_kernel_equals_oracle(volumetric, parallel):
    # same arithmetic in a different order: 1e-12 relative to the largest force
    from springmodel.spring_kernel import SpringKernel

    mesh, pts, frames, x = deformed_mesh(19)
    v = np.random.default_rng(19).standard_normal(x.shape)
    for coupling in (False, True):
        opts = SpringOptions(
            volume="axes", volumetric=volumetric, torsion="energy", calibration="exact",
            coupling=coupling, volume_damping=0.3, axial_damping=0.2,
        )  # fmt: skip
        el = build_spring_elements(pts, mesh.tets, frames, opts, TRANSVERSE)
        for vel in (None, v):
            f = SpringKernel(el, opts, parallel=parallel).forces(x, vel)
            f_ref = internal_forces(x, vel, el, opts)
            assert np.abs(f - f_ref).max() < 1e-12 * np.abs(f_ref).max()


def test_options_parse_axes_volumetric_coupling():
    from springfem.errors import SceneError
    from springfem.scene import TableReader
    from springmodel.options import parse_spring_options

    t = {"volume": "axes", "volumetric": "log", "coupling": True, "calibration": "exact"}
    o = parse_spring_options(TableReader(t, "spring", "s.toml"))
    assert (o.volume, o.volumetric, o.coupling, o.calibration) == ("axes", "log", True, "exact")
    assert o.axis_volume and not o.barycentric_volume
    assert SpringOptions().barycentric_volume and not SpringOptions(volume=False).volume
    for bad in ({"volume": "bary"}, {"volumetric": "cubic"}, {"coupling": "yes"}):
        with pytest.raises(SceneError):
            parse_spring_options(TableReader(bad, "spring", "s.toml"))
