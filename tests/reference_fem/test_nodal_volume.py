"""Nodal-volume linear tets (``[fem] formulation = "nodal-volume"``): the consistent tangent
against finite differences, the energy against the forces, the patch test on an irregular
mesh, the limits ``f = 1`` (plain P1) and small strain (the linear law), and the options."""

import numpy as np
import pytest
import scipy.sparse as sp

from reference_fem import FemProblem
from reference_fem.nodal_volume import NodalVolumeProblem
from reference_fem.options import FemOptions, parse_fem_options
from springfem.errors import InputError, SceneError
from springfem.mesh import box_mesh
from springfem.scene import TableReader, scene_from_dict

NEO = {"law": "neo-hookean", "E": 10.0, "nu": 0.45}
NEO_UNCOUPLED = {**NEO, "formulation": "uncoupled", "volumetric": "simo-taylor"}
GUCCIONE = {"law": "guccione", "C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0, "kappa": 50.0}
HOLZAPFEL_OGDEN = {
    **dict(law="holzapfel-ogden", a=0.059, b=8.023, a_f=18.472, b_f=16.026),
    **dict(a_s=2.481, b_s=11.12, a_fs=0.216, b_fs=11.436, kappa=50.0),
}
LAWS = {"neo": NEO, "neo-uncoupled": NEO_UNCOUPLED, "guccione": GUCCIONE, "ho": HOLZAPFEL_OGDEN}
#: An oblique fibre frame, so that the anisotropic laws are tested off the mesh axes.
AXES = {"fiber": [1.0, 1.0, 0.2], "sheet": [-1.0, 1.0, 0.0]}
GRAD = np.array([[0.03, -0.01, 0.02], [0.01, -0.02, 0.015], [-0.02, 0.025, 0.01]])


def irregular_mesh(divisions=(2, 2, 2), seed=3):
    return box_mesh((1.0, 0.8, 0.6), divisions, split="delaunay", seed=seed)


def problem(material, f, mesh=None, **extra):
    scene = scene_from_dict(
        {
            "mesh": mesh or irregular_mesh(),
            "material": material,
            "axes": AXES,
            "fem": {"formulation": "nodal-volume", "stabilisation": f},
            **extra,
        }
    )
    return NodalVolumeProblem(scene)


@pytest.mark.parametrize("f", [0.0, 0.3])
@pytest.mark.parametrize("name", LAWS)
def test_tangent_and_forces_are_the_derivatives(name, f):
    p = problem(LAWS[name], f)
    u = 0.01 * np.random.default_rng(0).standard_normal(p.n_dofs)
    fi, K = p.internal_force(u, tangent=True)
    K = K.toarray()
    h = 1e-6
    eye = np.eye(p.n_dofs)
    Kfd = np.column_stack(
        [(p.internal_force(u + h * e)[0] - p.internal_force(u - h * e)[0]) / (2 * h) for e in eye]
    )
    g = np.array([(p.energy(u + h * e) - p.energy(u - h * e)) / (2 * h) for e in eye])
    # central differences: truncation ~h^2 times the third derivative, which the exponential
    # laws make large (b up to 16): 1e-6 of the largest entry covers it, a wrong term does not
    assert np.abs(K - Kfd).max() <= 1e-6 * np.abs(K).max()
    assert np.abs(g - fi).max() <= 1e-6 * np.abs(fi).max()
    np.testing.assert_allclose(K, K.T, atol=1e-13 * np.abs(K).max())  # it is a Hessian


def homogeneous_patch(p, F):
    """Impose ``u = (F - I) X`` on the boundary, solve the interior by Newton."""
    X = p.space.node_coordinates
    exact = (X @ (F - np.eye(3)).T).ravel()
    boundary = np.unique(p.scene.mesh.boundary_facets())
    free = np.ones(p.n_dofs, dtype=bool)
    free[(3 * boundary[:, None] + np.arange(3)).ravel()] = False
    assert free.sum() > 0
    u = np.zeros(p.n_dofs)
    for load in np.linspace(0.2, 1.0, 5):  # five increments: plain Newton, no line search
        u[~free] = load * exact[~free]
        for _ in range(20):
            fi, K = p.internal_force(u, tangent=True)
            if np.abs(fi[free]).max() <= 1e-13 * np.abs(fi).max():
                break
            u[free] += p.linear_solver.solve(K, -fi, free)[free]
    return u, exact, free


@pytest.mark.parametrize("f", [0.0, 0.1])
@pytest.mark.parametrize("name", ["neo", "neo-uncoupled", "guccione", "ho"])
def test_patch_homogeneous_deformation_is_reproduced_inside(name, f):
    p = problem(LAWS[name], f, irregular_mesh((3, 3, 3), seed=1))
    F = np.eye(3) + 3.0 * GRAD  # 6-9 % strains: a finite deformation
    u, exact, free = homogeneous_patch(p, F)
    # exact up to Newton's tolerance and round-off (condition ~1e3-1e4 on this mesh)
    np.testing.assert_allclose(u[free], exact[free], atol=1e-10 * np.abs(exact).max())


def test_patch_linear_law():
    p = problem({"law": "linear", "E": 10.0, "nu": 0.499}, 0.0, irregular_mesh((3, 3, 3)))
    u, exact, free = homogeneous_patch(p, np.eye(3) + GRAD)
    np.testing.assert_allclose(u[free], exact[free], atol=1e-10 * np.abs(exact).max())


def test_full_stabilisation_is_plain_p1():
    """``f = 1`` keeps all the volumetric energy per element: the P1 residual and tangent."""
    p = problem(NEO, 1.0)
    ref = FemProblem(p.scene, order=1)
    u = 0.01 * np.random.default_rng(1).standard_normal(p.n_dofs)
    f1, K1 = p.internal_force(u, tangent=True)
    f0, K0 = ref.internal_force(u, tangent=True)
    np.testing.assert_allclose(f1, f0, atol=1e-12 * np.abs(f0).max())
    np.testing.assert_allclose(K1.toarray(), K0.toarray(), atol=1e-12 * abs(K0).max())


@pytest.mark.parametrize("f", [0.0, 0.2])
def test_linear_law_is_the_tangent_at_rest_of_coupled_neo_hookean(f):
    lin = problem({"law": "linear", "E": 10.0, "nu": 0.45}, f)
    neo = problem(NEO, f)
    K_lin, K_neo = lin.stiffness.toarray(), neo.stiffness.toarray()
    np.testing.assert_allclose(K_lin, K_neo, atol=1e-12 * np.abs(K_neo).max())


def test_nodal_volume_ratio_of_a_homogeneous_state():
    p = problem(NEO, 0.0)
    F = np.eye(3) + GRAD
    u = (p.space.node_coordinates @ (F - np.eye(3)).T).ravel()
    np.testing.assert_allclose(p.nodal_volume_ratio(u), np.linalg.det(F), rtol=1e-13)


def reader(table):
    return TableReader(table, "[fem]", "scene.toml")


def test_options_accept_nodal_volume():
    opts = parse_fem_options(reader({"formulation": "nodal-volume", "stabilisation": 0.01}))
    assert (opts.formulation, opts.stabilisation) == ("nodal-volume", 0.01)
    assert "nodal-volume" in FemOptions.choices("formulation")


@pytest.mark.parametrize(
    "table, key",
    [
        ({"formulation": "nodal-volume", "order": 2}, "order"),
        ({"formulation": "nodal-volume", "stabilisation": 1.5}, "stabilisation"),
        ({"formulation": "nodal-volume", "stabilisation": -0.1}, "stabilisation"),
        ({"stabilisation": 0.1}, "stabilisation"),
    ],
)
def test_options_refuse_with_the_key_named(table, key):
    with pytest.raises(SceneError) as exc:
        parse_fem_options(reader(table))
    msg = str(exc.value)
    assert key in msg and "\n" not in msg


def test_transverse_linear_is_refused():
    material = {
        **dict(law="transverse-linear", E_fiber=3.0, E_cross=1.0),
        **dict(nu_fiber_cross=0.3, nu_cross=0.4, G_fiber=0.5),
    }
    with pytest.raises(InputError, match="transverse-linear"):
        problem(material, 0.0)


def test_nodal_pressure_factorisation_gives_the_newton_correction():
    """The augmented solve (reference_fem.nodal_pressure_solve) equals a solve with K."""
    from springfem.mechanics import LinearSolver

    p = problem(GUCCIONE, 0.0, **{"boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}]})
    u = 0.01 * np.random.default_rng(3).standard_normal(p.n_dofs)
    u[p.fixed_dofs] = 0.0
    R, K, symmetric, _ = p.residual_tangent(u)
    assert hasattr(K, "nodal_parts")
    du = p.linear_solver.factorize(K, p.free, symmetric).solve(-R)
    ref = LinearSolver("direct").solve(sp.csr_matrix(K), -R, p.free, symmetric)
    # both direct, condition ~1e4: agreement to round-off
    np.testing.assert_allclose(du, ref, atol=1e-10 * np.abs(ref).max())
