"""Assembly, load vectors and tangents against scikit-fem's own forms, the spring model's
nodal loads, and finite differences."""

import numpy as np
import pytest
import scipy.sparse as sp
import skfem
from skfem.helpers import ddot, sym_grad
from skfem.models.elasticity import lame_parameters, linear_elasticity

from reference_fem import FemProblem, element_stiffness_p1, material_matrix
from reference_fem.assembly import BlockPattern, linear_element_blocks
from reference_fem.loads import ExternalLoads
from reference_fem.space import Space
from springfem.loads import external_forces
from springfem.materials import isotropic_matrix, voigt_to_tensor
from springfem.mechanics import rigid_body_modes
from springfem.mesh import box_mesh
from springfem.scene import Material, scene_from_dict

CLAMP = [{"region": "x_min", "fix": ["x", "y", "z"]}]


def load(kind, value, region=None):
    """A ``[[load]]`` table."""
    return {"type": kind, "value": value} | ({} if region is None else {"region": region})


def distorted_box(divisions=(3, 2, 2), amount=0.08, seed=0):
    """A box mesh with interior nodes moved randomly (irregular tets, same boundary)."""
    m = box_mesh((1.0, 0.8, 0.6), divisions)
    rng = np.random.default_rng(seed)
    lo, hi = m.bounding_box()
    inside = ((m.points > lo + 1e-9) & (m.points < hi - 1e-9)).all(axis=1)
    m.points[inside] += amount * 0.2 * rng.uniform(-1, 1, (inside.sum(), 3))
    assert (m.volumes() > 0).all()
    return m


def random_frames(n, seed=3):
    rng = np.random.default_rng(seed)
    q, _ = np.linalg.qr(rng.standard_normal((n, 3, 3)))
    q[np.linalg.det(q) < 0, :, 2] *= -1
    return q


TRANSVERSE = Material(
    "transverse-linear",
    1.0e4,
    0.4,
    E_fiber=3.0e4,
    E_cross=1.0e4,
    nu_fiber_cross=0.3,
    nu_cross=0.4,
    G_fiber=5.0e3,
)


@pytest.mark.parametrize("order", [1, 2])
def test_isotropic_stiffness_equals_scikit_fem(order):
    mesh = distorted_box()
    space = Space(mesh, order)
    D = isotropic_matrix(2.0e3, 0.3)
    K = BlockPattern(space.element_nodes, space.n_nodes).matrix(
        linear_element_blocks(space.grads, space.dx, D[None], np.zeros(mesh.n_tets, int))
    )
    basis = skfem.Basis(space.skmesh, skfem.ElementVector(space.element))  # default quadrature
    K_sk = skfem.asm(linear_elasticity(*lame_parameters(2.0e3, 0.3)), basis)
    assert abs(K - K_sk).max() <= 1e-12 * abs(K_sk).max()


@pytest.mark.parametrize("order", [1, 2])
def test_transverse_stiffness_equals_scikit_fem_form(order):
    """Per-element rotated material (random frames) against a scikit-fem BilinearForm."""
    mesh = distorted_box()
    frames = random_frames(mesh.n_tets)
    mesh.cell_data.update(fiber=frames[:, 0], sheet=frames[:, 1])
    space = Space(mesh, order)
    scene = scene_from_dict(
        {"mesh": mesh, "material": TRANSVERSE, "axes": {"type": "cells"}, "boundary": CLAMP}
    )
    # the frames the scene holds: the random ones re-orthonormalised (round-off apart)
    assert np.abs(scene.frames - frames).max() < 1e-14
    problem_K = FemProblem(scene, order).stiffness
    C = voigt_to_tensor(material_matrix(TRANSVERSE, scene.frames))  # (m, 3, 3, 3, 3)

    @skfem.BilinearForm
    def form(u, v, w):
        eps_u = sym_grad(u)
        sig = np.einsum("eijkl,kleq->ijeq", C, eps_u)
        return ddot(sig, sym_grad(v))

    basis = skfem.Basis(space.skmesh, skfem.ElementVector(space.element), intorder=2)
    K_sk = skfem.asm(form, basis)
    assert abs(problem_K - K_sk).max() <= 1e-11 * abs(K_sk).max()


def test_element_stiffness_p1_properties():
    mesh = distorted_box()
    D = material_matrix(TRANSVERSE, random_frames(mesh.n_tets))
    Ke = element_stiffness_p1(mesh.points, mesh.tets, D)
    assert Ke.shape == (mesh.n_tets, 12, 12)
    np.testing.assert_allclose(Ke, Ke.transpose(0, 2, 1), atol=1e-9)
    # rigid-body motions of each element carry no force
    for e in range(0, mesh.n_tets, 7):
        B = rigid_body_modes(mesh.points[mesh.tets[e]])
        assert np.abs(Ke[e] @ B).max() < 1e-10 * np.abs(Ke[e]).max()
    # assembled with coo it equals the block assembly
    dofs = (3 * mesh.tets[:, :, None] + np.arange(3)).reshape(-1, 12)
    rows = np.repeat(dofs, 12, axis=1).ravel()
    cols = np.tile(dofs, (1, 12)).ravel()
    n = 3 * mesh.n_points
    K_coo = sp.coo_matrix((Ke.ravel(), (rows, cols)), shape=(n, n)).tocsr()
    space = Space(mesh, 1)
    K = BlockPattern(space.element_nodes, space.n_nodes).matrix(
        linear_element_blocks(space.grads, space.dx, D, np.arange(mesh.n_tets))
    )
    assert abs(K - K_coo).max() <= 1e-12 * abs(K_coo).max()


def test_p1_load_vectors_equal_spring_model_nodal_forces():
    """Consistent P1 loads equal springfem.loads (area/3, rho V/4, force by area)."""
    mesh = distorted_box()
    scene = scene_from_dict(
        {
            "mesh": mesh,
            "material": {"law": "linear", "E": 1.0e3, "nu": 0.3, "density": 1100.0},
            "boundary": CLAMP,
            "load": [
                load("traction", [1.0, -2.0, 0.5], "x_max"),
                load("gravity", [0.0, 0.0, -9.81]),
                load("force", [0.3, 0.0, -0.7], "y_max"),
                load("pressure", 2.5, "z_max"),
                load("force", [0.0, 1.0, 0.0], {"point": [0.5, 0.4, 0.3]}),
            ],
        }
    )
    loads = ExternalLoads.from_scene(scene, Space(mesh, 1), follower=False)
    f = loads.vector(None)
    np.testing.assert_allclose(f, external_forces(scene).ravel(), atol=1e-13)


def test_p2_load_vectors_total_force():
    """P2 consistent loads: totals equal traction x area, rho g V, the given force."""
    mesh = distorted_box()
    vol = mesh.volumes().sum()
    scene = scene_from_dict(
        {
            "mesh": mesh,
            "material": {"law": "linear", "E": 1.0e3, "nu": 0.3, "density": 1100.0},
            "boundary": CLAMP,
            "load": [
                load("traction", [1.0, -2.0, 0.5], "x_max"),
                load("gravity", [0.0, 0.0, -9.81]),
                load("force", [0.3, 0.0, -0.7], "y_max"),
            ],
        }
    )
    f = ExternalLoads.from_scene(scene, Space(mesh, 2), follower=False).vector(None)
    total = f.reshape(-1, 3).sum(axis=0)
    expect = 0.8 * 0.6 * np.array([1.0, -2.0, 0.5]) + 1100 * vol * np.array([0, 0, -9.81])
    expect += [0.3, 0.0, -0.7]
    np.testing.assert_allclose(total, expect, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize(
    "law",
    [
        "neo-hookean/coupled",
        "neo-hookean/uncoupled/log",
        "neo-hookean/uncoupled/quadratic",
        "neo-hookean/uncoupled/simo-taylor",
    ],
)
def test_tangent_at_zero_equals_linear_stiffness(order, law):
    mesh = distorted_box()
    scene = scene_from_dict(
        {"mesh": mesh, "material": Material("neo-hookean", 5.0e3, 0.45), "boundary": CLAMP}
    )
    nonlinear = FemProblem(scene, order, law)
    linear = FemProblem(scene, order, "linear")
    R, K, symmetric, _ = nonlinear.residual_tangent(np.zeros(nonlinear.n_dofs))
    assert symmetric and np.abs(R).max() == 0.0
    K_lin = linear.stiffness
    assert abs(K - K_lin).max() <= 1e-12 * abs(K_lin).max()


@pytest.mark.parametrize("order", [1, 2])
def test_tangent_with_follower_pressure_matches_finite_differences(order):
    """dR/du (internal + pressure load stiffness) against central differences of R."""
    mesh = distorted_box((2, 2, 2))
    scene = scene_from_dict(
        {
            "mesh": mesh,
            "material": Material(
                "neo-hookean", 1.0e3, 0.35, formulation="uncoupled", volumetric="log"
            ),
            "boundary": CLAMP,
            "load": [load("pressure", 150.0, "x_max"), load("pressure", -80.0, "y_max")],
        }
    )
    problem = FemProblem(scene, order)
    rng = np.random.default_rng(5)
    u = 0.02 * rng.standard_normal(problem.n_dofs)
    R, K, symmetric, _ = problem.residual_tangent(u)
    assert not symmetric
    K = K.toarray()
    h = 1e-6
    for j in rng.choice(problem.n_dofs, 12, replace=False):
        e = np.zeros(problem.n_dofs)
        e[j] = h
        col = (problem.residual(u + e)[0] - problem.residual(u - e)[0]) / (2 * h)
        # central differences: truncation ~ h^2, round-off ~ 1e-16 |R| / h
        np.testing.assert_allclose(K[:, j], col, atol=1e-6 * np.abs(K).max())


def test_follower_pressure_is_dead_load_at_rest_and_rotates_with_body():
    mesh = distorted_box((2, 2, 2))
    scene = scene_from_dict(
        {
            "mesh": mesh,
            "material": Material("neo-hookean", 1.0e3, 0.3),
            "boundary": CLAMP,
            "load": [load("pressure", 10.0, "x_max")],
        }
    )
    space = Space(mesh, 2)
    loads = ExternalLoads.from_scene(scene, space, follower=True)
    f0 = loads.vector(np.zeros((space.n_nodes, 3)))
    dead = ExternalLoads.from_scene(scene, space, follower=False).vector(None)
    np.testing.assert_allclose(f0, dead, atol=1e-14)
    total0 = f0.reshape(-1, 3).sum(axis=0)
    np.testing.assert_allclose(total0, [-10.0 * 0.8 * 0.6, 0.0, 0.0], atol=1e-12)
    # rigid rotation about z by 90 degrees: total force turns with the surface
    X = space.node_coordinates
    Q = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    f1 = loads.vector(X @ Q.T - X).reshape(-1, 3).sum(axis=0)
    np.testing.assert_allclose(f1, Q @ total0, atol=1e-12)


def test_interpolation_matrix_equals_scikit_fem_probes():
    mesh = distorted_box()
    space = Space(mesh, 2)
    rng = np.random.default_rng(7)
    tets = rng.choice(mesh.n_tets, 6, replace=False)
    bary = rng.dirichlet(np.ones(4), 6)
    pts = np.einsum("pa,pai->pi", bary, mesh.points[mesh.tets[tets]])
    P = space.interpolation_matrix(tets, pts)
    P_sk = space.basis.probes(pts.T)
    np.testing.assert_allclose(P.toarray(), P_sk.toarray(), atol=1e-13)
    # a quadratic field is reproduced exactly
    U = space.node_coordinates**2
    np.testing.assert_allclose(P @ U, pts**2, atol=1e-14)
