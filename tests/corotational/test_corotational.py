"""Co-rotational P1 against independent references: numpy's SVD for the rotation (Irving et
al.'s sign fix), rigid motions, the linear P1 element stiffness of reference_fem
(scikit-fem's assembly), finite differences of the energy and of the forces, and P1
neo-Hookean on a large-rotation cantilever. On a gmsh mesh and on boxes."""

from __future__ import annotations

import doctest
import importlib

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from support.meshes import gmsh_box

from corotational.kernel import forces_numpy
from corotational.plugin import models
from corotational.polar import rotations
from corotational.system import Corotational
from reference_fem import element_stiffness_p1
from springfem.errors import InputError
from springfem.materials import isotropic_matrix, material_matrix
from springfem.mesh import TetMesh
from springfem.scene import load_scene, scene_from_dict
from springfem.testing import check_model
from studies import metrics
from studies import models as registry

ISOTROPIC = {"law": "linear", "E": 1.0e4, "nu": 0.3, "density": 1000.0}
TRANSVERSE = {
    "law": "transverse-linear", "E_fiber": 3.0e4, "E_cross": 1.0e4, "nu_fiber_cross": 0.3,
    "nu_cross": 0.4, "G_fiber": 5.0e3, "density": 1000.0,
}  # fmt: skip
AXES = {"fiber": [0.6, 0.8, 0.0], "sheet": [-0.8, 0.6, 0.0]}


def _scene(mesh, material=ISOTROPIC, load=True):
    table = {
        "mesh": mesh,
        "material": material,
        "axes": AXES,
        "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
    }
    if load:
        table["load"] = [{"type": "traction", "region": "x_max", "value": [0.0, 0.0, -1.0]}]
    return scene_from_dict(table)


@pytest.fixture(scope="module")
def gmsh_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("corot") / "box.msh"
    gmsh_box(path, 0.012, dims=(0.05, 0.02, 0.02))
    return path


@pytest.fixture(scope="module", params=["linear", "transverse-linear"])
def gmsh_scene(request, gmsh_file):
    return _scene({"file": str(gmsh_file)}, ISOTROPIC if request.param == "linear" else TRANSVERSE)


def _deformed(system, amplitude, seed=0):
    rng = np.random.default_rng(seed)
    L = np.ptp(system.x0, axis=0).max()
    return system.x0 + amplitude * L * rng.standard_normal(system.x0.shape)


# -- the rotation --------------------------------------------------------------------------


def test_rotation_is_irvings_svd_with_the_sign_fix():
    """R = U V^T of numpy's SVD, the last columns flipped to make U and V rotations (Irving,
    Teran & Fedkiw 2004), for random F, half of them inverted."""
    rng = np.random.default_rng(3)
    F = rng.standard_normal((500, 3, 3))
    U, _, Vt = np.linalg.svd(F)
    U[:, :, 2] *= np.linalg.det(U)[:, None]
    Vt[:, 2, :] *= np.linalg.det(Vt)[:, None]
    R = rotations(F)
    assert (np.linalg.det(F) < 0).sum() > 100
    np.testing.assert_allclose(R, U @ Vt, atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-12)
    S = np.einsum("kji,kjl->kil", R, F)  # R^T F symmetric: the polar stretch (signed)
    np.testing.assert_allclose(S, S.transpose(0, 2, 1), atol=1e-12)


def test_rotation_of_degenerate_gradients():
    """Flat (rank 2), linear (rank 1) and zero F still give rotations; a rotation gives
    itself."""
    Q = Rotation.from_rotvec([0.3, -1.2, 2.0]).as_matrix()
    F = np.stack([Q @ np.diag([1.0, 1.0, 0.0]), Q @ np.diag([2.0, 0.0, 0.0]), np.zeros((3, 3)), Q])
    R = rotations(F)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-12)
    np.testing.assert_allclose(R[0], Q, atol=1e-12)  # the plane's rotation is Q's
    np.testing.assert_allclose(R[3], Q, atol=1e-14)
    np.testing.assert_allclose(R[0][:, 0], Q[:, 0], atol=1e-12)
    np.testing.assert_allclose(R[1][:, 0], Q[:, 0], atol=1e-12)  # the line's direction


# -- forces ----------------------------------------------------------------------------------


@pytest.mark.parametrize("tangent", ["consistent", "warped"])
def test_conformance(gmsh_scene, tangent):
    """Rigid motion gives no force and f(Qy) = Q f(y); forces and consistent tangent are
    finite differences of the energy and the forces; both tangents at rest are the core's
    linear P1; velocity Verlet conserves the energy (springfem.testing.check_model). The
    warped stiffness misses the rotation terms by O(strain)."""
    model = next(m for m in models() if m.settings["tangent"] == tangent)
    claim = "exact" if tangent == "consistent" else "approximate"
    report = check_model(model, gmsh_scene, small_strain="exact", tangent=claim)
    assert report.status("finite rotation") == "passed"
    if tangent == "warped":
        assert report.checks[4].value > 1e-3


@pytest.mark.parametrize("law", ["linear", "transverse-linear"])
def test_tangents_are_symmetric_for_the_isotropic_law(law):
    """The consistent tangent is symmetric for the isotropic law (the forces of an
    energy), the warped stiffness ``R K R^T`` for both laws."""
    mat = ISOTROPIC if law == "linear" else TRANSVERSE
    s = Corotational(_scene({"generator": "box", "size": [0.1, 0.02, 0.01],
                             "divisions": [3, 2, 1]}, mat))  # fmt: skip
    x = _deformed(s, 0.03, seed=2)
    if law == "linear":
        K = s.stiffness(x).toarray()
        np.testing.assert_allclose(K, K.T, atol=1e-10 * np.abs(K).max())
    Kw = Corotational(s.scene, tangent="warped").stiffness(x).toarray()
    np.testing.assert_allclose(Kw, Kw.T, atol=1e-10 * np.abs(Kw).max())


def test_forces_are_r_k_rt_of_the_linear_element(gmsh_scene):
    """f_e = -R_e K_e (R_e^T x_e - X_e) with reference_fem's P1 element stiffness K_e and R
    from numpy's SVD, summed over the elements."""
    s = Corotational(gmsh_scene)
    x = _deformed(s, 0.05)
    C = material_matrix(gmsh_scene.material, np.asarray(gmsh_scene.frames))
    Ke = element_stiffness_p1(s.x0, s.tets, C if C.ndim == 3 else C)
    X, Y = s.x0[s.tets], x[s.tets]  # (m, 4, 3)
    F = np.einsum("kac,kad->kcd", Y[:, 1:] - Y[:, :1], s.G)
    U, _, Vt = np.linalg.svd(F)
    U[:, :, 2] *= np.linalg.det(U)[:, None]
    Vt[:, 2, :] *= np.linalg.det(Vt)[:, None]
    R = U @ Vt
    local = np.einsum("kji,kaj->kai", R, Y) - X  # R^T x - X per node
    fe = -np.einsum(
        "kij,kaj->kai", R, np.einsum("kij,kj->ki", Ke, local.reshape(-1, 12)).reshape(-1, 4, 3)
    )
    f = np.zeros_like(x)
    np.add.at(f, s.tets, fe)
    np.testing.assert_allclose(s.internal(x), f, atol=1e-10 * np.abs(f).max())
    np.testing.assert_allclose(
        forces_numpy(x, s.tets, s.G, s.V, s.D), f, atol=1e-10 * np.abs(f).max()
    )


def test_an_inverted_element_is_pushed_back():
    """One tet with its apex pushed through the opposite face: the apex's force points back
    through the face (Irving's sign fix), and the element energy is larger than at rest."""
    mesh = TetMesh(
        np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]), np.array([[0, 1, 2, 3]])
    )
    scene = scene_from_dict({"mesh": mesh, "material": ISOTROPIC})
    s = Corotational(scene)
    x = s.x0.copy()
    x[3, 2] = -0.3
    f = s.internal(x)
    assert s.last_inverted == 1
    assert f[3, 2] > 0
    assert s.strain_energy(x) > 0


# -- solves ---------------------------------------------------------------------------------


def test_large_rotation_cantilever_follows_neo_hookean_p1():
    """The bundled slender cantilever bent through a large rotation at strains <= 5 %:
    co-rotational P1 is within 1 % (relative L2) of P1 neo-Hookean on the same mesh, linear
    P1 is more than 20 % off it."""
    scene = load_scene("cantilever-large-rotation")
    got = {n: registry.run(scene, n) for n in ("corotational", "P1-NH", "P1")}
    assert all(o.ok for o in got.values()), {n: o.message for n, o in got.items()}
    assert abs(got["P1-NH"].u[:, 2]).max() > 0.3 * 0.1  # a large deflection
    e_corot = metrics.relative_l2_error(got["corotational"].u, got["P1-NH"].u)
    e_p1 = metrics.relative_l2_error(got["P1"].u, got["P1-NH"].u)
    assert e_corot < 0.01 < 0.2 < e_p1


def test_small_load_static_solve_is_linear_p1(gmsh_file):
    """At a small load the static solution is linear P1's (scikit-fem) to O(load)."""
    scene = _scene({"file": str(gmsh_file)}, load=True)
    scene = scene_from_dict({**scene.raw, "load": [{"type": "traction", "region": "x_max",
                                                    "value": [0.0, 0.0, -1e-3]}]})  # fmt: skip
    a, b = registry.run(scene, "corotational"), registry.run(scene, "P1")
    assert a.ok and b.ok
    assert metrics.relative_l2_error(a.u, b.u) < 1e-4
    assert a.solution.result.model == "corotational" and a.solution.result.converged


def test_refusals_are_one_line():
    tissue = {"law": "guccione", "C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0, "kappa": 50.0}
    scene = _scene({"generator": "box", "size": [1, 1, 1], "divisions": [1, 1, 1]}, tissue)
    assert "guccione" in registry.get("corotational").applies(scene)
    with pytest.raises(InputError, match="guccione"):
        Corotational(scene)
    with pytest.raises(InputError, match="tangent"):
        Corotational(
            _scene({"generator": "box", "size": [1, 1, 1], "divisions": [1, 1, 1]}),
            tangent="secant",
        )  # type: ignore[arg-type]


def test_isotropic_matrix_of_the_kernel_is_the_cores():
    s = Corotational(_scene({"generator": "box", "size": [1, 1, 1], "divisions": [1, 1, 1]}))
    np.testing.assert_allclose(s.D[0], isotropic_matrix(1.0e4, 0.3), rtol=1e-14)


@pytest.mark.parametrize("name", ["polar", "kernel", "system", "plugin", "__init__"])
def test_docstring_examples(name):
    module = importlib.import_module("corotational" + ("" if name == "__init__" else f".{name}"))
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0 and result.attempted > 0


@pytest.mark.parametrize("tangent", ["consistent", "warped"])
def test_compiled_tangent_is_the_numpy_one(gmsh_scene, tangent):
    """The compiled element tangents (what stiffness() assembles) equal the numpy ones."""
    s = Corotational(gmsh_scene, tangent=tangent)
    x = _deformed(s, 0.03, seed=9)
    a, b = s.element_tangents(x), s.element_tangents_numpy(x)
    np.testing.assert_allclose(a, b, atol=1e-12 * np.abs(b).max())
