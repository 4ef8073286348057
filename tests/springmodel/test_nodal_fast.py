"""The compiled nodal-average paths of the locking-free spring element against references.

References: the sparse products of ``B`` built by scipy (:func:`nodal_gradients`), the
``4 m`` virtual elements of the nodal strain (``group=False``, one per element copy, as the
element was first written), the numpy/scipy tangent of the nodal volume
(:meth:`NodalVolume.reference_tangent`), central finite differences, and the invariant that a
rigid motion gives no force. Meshes: a jittered Delaunay block and a gmsh organ at nu = 0.49.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import scipy.sparse as sp

from springfem.mesh.nodal_average import NodalAverage
from springfem.scene import scene_from_dict
from springmodel.model import SpringModel
from springmodel.nodal_strain import NodalStrainPart, nodal_deformation_gradients, nodal_gradients
from springmodel.nodal_volume import NodalVolume

from .test_nodal_strain import LOCKING_FREE, STIFFENED, block


def isotropic_block(nu: float = 0.49) -> dict:
    scene = block({**LOCKING_FREE}, divisions=(4, 2, 2), law="linear")
    scene["material"] = {"law": "neo-hookean", "E": 5.0, "nu": nu}
    return scene


def scipy_B(Gb, n):
    parts = []
    for beta in range(3):
        coo = Gb[beta].tocoo()
        for alpha in range(3):
            parts.append((9 * coo.row + 3 * alpha + beta, 3 * coo.col + alpha, coo.data))
    r, c, v = (np.concatenate(t) for t in zip(*parts, strict=True))
    return sp.csr_matrix((v, (r, c)), shape=(9 * n, 3 * n))


def rotation(seed: int) -> np.ndarray:
    q, _ = np.linalg.qr(np.random.default_rng(seed).standard_normal((3, 3)))
    return q * np.sign(np.linalg.det(q))


@pytest.fixture(scope="module")
def organ(tmp_path_factory):
    from springfem.mesh.organ import organ_scene
    from springfem.scene import load_scene

    path = organ_scene(tmp_path_factory.mktemp("organ"), tets=600, nu=0.49)
    return load_scene(path)


def test_operator_equals_the_scipy_products():
    model = SpringModel(scene_from_dict(isotropic_block()))
    X, tets = model.x0, model.elements.tets
    n = X.shape[0]
    op = NodalAverage.of(X, tets)
    Gb = nodal_gradients(X, tets)
    B = scipy_B(Gb, n)
    rng = np.random.default_rng(0)
    x = X + 0.1 * rng.standard_normal(X.shape)
    F = op.gradients(x)
    assert np.abs(F - nodal_deformation_gradients(Gb, x)).max() < 1e-13 * np.abs(F).max()
    T = rng.standard_normal((n, 3, 3))
    f = op.transpose(T)
    assert np.abs(f.ravel() - B.T @ T.ravel()).max() < 1e-13 * np.abs(f).max()
    A = rng.standard_normal((n, 9, 9))
    Ad = sp.bsr_matrix((A, np.arange(n), np.arange(n + 1)), shape=(9 * n, 9 * n)).tocsr()
    K = op.tangent(A)
    ref = (B.T @ Ad @ B).toarray()
    assert np.abs(K.toarray() - ref).max() < 1e-13 * np.abs(ref).max()
    Ke = rng.standard_normal((len(tets), 12, 12))
    Kd = op.matrix(op.add_elements(Ke, op.zeros())).toarray()
    dofs = (3 * tets[:, :, None] + np.arange(3)).reshape(-1, 12)
    ref = np.zeros_like(Kd)
    for k in range(len(tets)):
        ref[np.ix_(dofs[k], dofs[k])] += Ke[k]
    assert np.abs(Kd - ref).max() < 1e-13 * np.abs(ref).max()


@pytest.mark.parametrize("stiffened", [False, True])
def test_grouped_nodal_strain_equals_the_copies(stiffened):
    spring = {**LOCKING_FREE, **(STIFFENED if stiffened else {})}
    scene = scene_from_dict(isotropic_block()) if not stiffened else scene_from_dict(block(spring))
    model = SpringModel(scene)
    part = model.nodal_strain
    ref = NodalStrainPart(model.x0, scene.mesh.tets, _part_elements(model, scene),
                          model.options, part.part.stiffening.modulus if stiffened else None,
                          group=False)  # fmt: skip
    rng = np.random.default_rng(3)
    x = model.x0 + (0.001 if stiffened else 0.05) * rng.standard_normal(model.x0.shape)
    if not stiffened:
        assert part.grouped and part.nodes.size == model.x0.shape[0]  # one class: one per node
    f, fr = part.forces(x), ref.forces(x)
    assert np.abs(f - fr).max() < 1e-12 * np.abs(fr).max()
    assert part.energy(x) == pytest.approx(ref.energy(x), rel=1e-12)
    K, Kr = part.tangent(x).toarray(), ref.tangent(x).toarray()
    assert np.abs(K - Kr).max() < 1e-12 * np.abs(Kr).max()


def _part_elements(model, scene):
    """The nodal-strain elements of ``model`` (rebuilt as NodalStrainPart.split builds them)."""
    from springmodel.nodal_strain import scaled_deviatoric
    from springmodel.nodal_volume import NodalPart

    _, el = NodalPart.split(scene.mesh, model.elements, model.options, scene.material)
    alpha = float(model.options.strain_stabilisation)
    deviatoric = replace(el, k_axis_volume=np.zeros(el.n_elements))
    return scaled_deviatoric(deviatoric, (1 - alpha) / 4)


def test_nodal_volume_equals_its_numpy_reference():
    model = SpringModel(scene_from_dict(isotropic_block()))
    X, tets = model.x0, model.elements.tets
    rng = np.random.default_rng(5)
    term = NodalVolume(X, tets, rng.uniform(1.0, 2.0, len(tets)), "log")
    x = X + 0.03 * rng.standard_normal(X.shape)
    from springmodel.nodal_volume import tet_volumes_and_gradients
    from springmodel.springs.points import scatter

    V, dV = tet_volumes_and_gradients(x, term.tets)
    from springfem.volumetric import volumetric_energy

    _, dU, _ = volumetric_energy(term._ratios_of(V), term.kappa, term.kind)
    ref = scatter(-dU[term.tets].mean(axis=1)[:, None, None] * dV, term.tets, term.n)
    f = term.forces(x)
    assert np.abs(f - ref).max() < 1e-12 * np.abs(ref).max()
    K, Kr = term.tangent(x).toarray(), term.reference_tangent(x).toarray()
    assert np.abs(K - Kr).max() < 1e-12 * np.abs(Kr).max()


def test_organ_forces_gradient_tangent_and_rigid_motion(organ):
    """On a gmsh organ at nu = 0.49: forces = -dE/dx, K = -df/dx (directional differences),
    and a rigid motion of a deformed state rotates the forces with it (zero at rest)."""
    from studies.models import get

    model = get("spring-stabilised").system(organ)
    assert model.nodal_strain.grouped
    rng = np.random.default_rng(7)
    x0 = model.x0
    x = x0 + 0.5 * rng.standard_normal(x0.shape)
    f = model.internal(x)
    R, t = rotation(1), np.array([3.0, -2.0, 5.0])
    for rest in (x0, x0 @ R.T + t):  # round-off of the O(1e2) coordinates only
        assert np.abs(model.internal(rest)).max() < 1e-10 * np.abs(f).max()
    fr = model.internal(x @ R.T + t)
    assert np.abs(fr - f @ R.T).max() < 1e-10 * np.abs(f).max()
    dx = 1e-6 * rng.standard_normal(x.shape)
    dE = model.energy(x + dx, 0.0) - model.energy(x - dx, 0.0)
    # central differences, h ~ 1e-6 relative: truncation ~h^2, round-off ~1e-16 |W| / |dE|
    assert dE == pytest.approx(-2.0 * np.sum(f * dx), rel=1e-6)
    K = model.stiffness(x, 0.0)
    df = model.internal(x + dx) - model.internal(x - dx)
    assert np.abs(K @ dx.ravel() + df.ravel() / 2.0).max() < 1e-6 * np.abs(df).max()
    assert abs(K - K.T).max() < 1e-12 * abs(K).max()


def test_parallel_products_equal_the_serial_ones_bitwise():
    """Rows are independent: on all threads the same sums in the same order."""
    model = SpringModel(scene_from_dict(isotropic_block()))
    op = NodalAverage.of(model.x0, model.elements.tets)
    rng = np.random.default_rng(11)
    x = model.x0 + 0.1 * rng.standard_normal(model.x0.shape)
    T = rng.standard_normal((op.n, 3, 3))
    serial = op.gradients(x), op.transpose(T)
    op.parallel = True
    parallel = op.gradients(x), op.transpose(T)
    for a, b in zip(serial, parallel, strict=True):
        assert np.array_equal(a, b)
