"""Nodal-strain linear tets (``[fem] formulation = "nodal-strain"``): the consistent tangent
and the forces against finite differences of the energy, the patch test against plain P1 on
an irregular mesh with varying fibre frames, the limits ``alpha = 1`` (nodal-volume) and
small strain (the linear law), and the options."""

import numpy as np
import pytest

from reference_fem import FemProblem
from reference_fem.nodal_strain import NodalStrainProblem
from reference_fem.nodal_volume import NodalVolumeProblem
from reference_fem.options import FemOptions, parse_fem_options
from springfem.errors import SceneError
from springfem.mesh import box_mesh
from springfem.scene import TableReader, scene_from_dict

NEO = {"law": "neo-hookean", "E": 10.0, "nu": 0.45}
GUCCIONE = {"law": "guccione", "C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0, "kappa": 50.0}
HOLZAPFEL_OGDEN = {
    **dict(law="holzapfel-ogden", a=0.059, b=8.023, a_f=18.472, b_f=16.026),
    **dict(a_s=2.481, b_s=11.12, a_fs=0.216, b_fs=11.436, kappa=50.0),
}
LAWS = {"neo": NEO, "guccione": GUCCIONE, "ho": HOLZAPFEL_OGDEN}
#: Rule-based fibres turning through the wall: a frame per element, several per patch.
RULE_AXES = {
    "type": "rule-based",
    "fiber_angle_endo": 60.0,
    "fiber_angle_epi": -60.0,
    "sheet": [0.0, 0.0, 1.0],
}
GRAD = np.array([[0.03, -0.01, 0.02], [0.01, -0.02, 0.015], [-0.02, 0.025, 0.01]])


def irregular_mesh(divisions=(2, 2, 2), seed=3):
    return box_mesh((1.0, 0.8, 0.6), divisions, split="delaunay", seed=seed)


def scene(material, fem, axes=None, **extra):
    return scene_from_dict(
        {
            "mesh": irregular_mesh(),
            "material": material,
            "axes": axes or {"fiber": [1.0, 1.0, 0.2], "sheet": [-1.0, 1.0, 0.0]},
            "fem": fem,
            **extra,
        }
    )


def problem(material, alpha, f=1e-4, **extra):
    fem = {"formulation": "nodal-strain", "strain_stabilisation": alpha, "stabilisation": f}
    return NodalStrainProblem(scene(material, fem, **extra))


def varying_frames_scene(material, alpha):
    """The anisotropic laws with frames that differ between the elements of a patch."""
    fem = {"formulation": "nodal-strain", "strain_stabilisation": alpha}
    data = {
        "mesh": irregular_mesh(),
        "material": material,
        "axes": {"fiber": [1.0, 1.0, 0.2], "sheet": [-1.0, 1.0, 0.0]},
        "fem": fem,
    }
    sc = scene_from_dict(data)
    rng = np.random.default_rng(5)
    angles = rng.uniform(-1.0, 1.0, sc.mesh.n_tets)
    c, s = np.cos(angles), np.sin(angles)
    frames = np.zeros((sc.mesh.n_tets, 3, 3))
    frames[:, 0] = np.stack([c, s, 0 * c], 1)  # fibre rows turning about z
    frames[:, 1] = np.stack([-s, c, 0 * c], 1)
    frames[:, 2] = [0.0, 0.0, 1.0]
    sc.__dict__["frames"] = frames  # a per-element field, as rule-based fibres give
    return sc


@pytest.mark.parametrize("alpha", [0.0, 0.3])
@pytest.mark.parametrize("name", LAWS)
def test_tangent_and_forces_are_the_derivatives(name, alpha):
    p = problem(LAWS[name], alpha)
    u = 0.01 * np.random.default_rng(0).standard_normal(p.n_dofs)
    fi, K = p.internal_force(u, tangent=True)
    K = K.toarray()
    h = 1e-6
    eye = np.eye(p.n_dofs)
    Kfd = np.column_stack(
        [(p.internal_force(u + h * e)[0] - p.internal_force(u - h * e)[0]) / (2 * h) for e in eye]
    )
    g = np.array([(p.energy(u + h * e) - p.energy(u - h * e)) / (2 * h) for e in eye])
    # central differences: truncation ~h^2 times the third derivative (exponential laws)
    assert np.abs(K - Kfd).max() <= 1e-6 * np.abs(K).max()
    assert np.abs(K - K.T).max() <= 1e-12 * np.abs(K).max()
    assert np.abs(fi - g).max() <= 1e-6 * np.abs(fi).max()


def test_frames_that_vary_within_a_patch_keep_forces_and_tangent_consistent():
    """Each element's part carries its own frame at the nodal strain (no nodal frame)."""
    sc = varying_frames_scene(GUCCIONE, 0.3)
    assert len(np.unique(sc.frames.reshape(-1, 9), axis=0)) == sc.mesh.n_tets
    p = NodalStrainProblem(sc)
    rng = np.random.default_rng(1)
    u = 0.02 * rng.standard_normal(p.n_dofs)
    fi, K = p.internal_force(u, tangent=True)
    d = rng.standard_normal(p.n_dofs)
    d /= np.linalg.norm(d)
    h = 1e-6  # central differences: the truncation error falls as h^2 (measured 4e-7 here)
    fd = (p.internal_force(u + h * d)[0] - p.internal_force(u - h * d)[0]) / (2 * h)
    assert np.linalg.norm(fd - K @ d) <= 2e-6 * np.linalg.norm(K @ d)
    de = (p.energy(u + h * d) - p.energy(u - h * d)) / (2 * h)
    assert de == pytest.approx(fi @ d, rel=1e-6)


@pytest.mark.parametrize("name", LAWS)
def test_patch_test_a_homogeneous_deformation_gives_plain_p1_forces(name):
    """Every Fbar_a and J_a equals the one F: the forces are P1's, interior nodes free."""
    p = problem(LAWS[name], 0.3)
    p1 = FemProblem(p.scene, 1)
    X = p.space.node_coordinates
    u = (X @ GRAD.T).ravel()
    Fbar = p.nodal_deformation_gradients(u)
    assert np.allclose(Fbar, np.eye(3) + GRAD, atol=1e-13)
    f, f1 = p.internal_force(u)[0], p1.internal_force(u)[0]
    assert np.abs(f - f1).max() <= 1e-12 * np.abs(f1).max()
    boundary = np.zeros(len(X), bool)
    boundary[np.unique(p.scene.mesh.boundary_facets())] = True
    interior = np.repeat(~boundary, 3)
    assert interior.any()
    assert np.abs(f[interior]).max() <= 1e-12 * np.abs(f).max()


def test_alpha_one_is_the_nodal_volume_formulation():
    p = problem(GUCCIONE, 1.0)
    nv = NodalVolumeProblem(scene(GUCCIONE, {"formulation": "nodal-volume", "stabilisation": 1e-4}))
    u = 0.01 * np.random.default_rng(2).standard_normal(p.n_dofs)
    (f, K), (fv, Kv) = p.internal_force(u, True), nv.internal_force(u, True)
    assert np.allclose(f, fv, rtol=0, atol=1e-13 * np.abs(fv).max())
    assert abs(K - Kv).max() <= 1e-13 * abs(Kv).max()
    assert p.energy(u) == pytest.approx(nv.energy(u), rel=1e-13)


@pytest.mark.parametrize("alpha", [0.0, 0.4])
def test_linear_law_is_the_small_strain_limit_of_neo_hookean(alpha):
    """Coupled neo-Hookean's split at rest: ``mu`` shear on the blend, ``lam`` on volumes."""
    lin = problem({"law": "linear", "E": 10.0, "nu": 0.45}, alpha)
    neo = problem(NEO, alpha)
    K_lin, K_neo = lin.stiffness.toarray(), neo.internal_force(np.zeros(neo.n_dofs), True)[1]
    assert np.abs(K_lin - K_neo.toarray()).max() <= 1e-12 * np.abs(K_lin).max()


def test_the_nodal_measure_softens_bending():
    """Between nodal-volume P1 (``alpha = 1``) and pure smoothing (``alpha = 0``)."""
    sc = {
        "mesh": box_mesh((6.0, 1.0, 1.0), (6, 1, 1), split="delaunay", seed=4),
        "material": {"law": "linear", "E": 10.0, "nu": 0.3},
        "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
        "load": [{"type": "traction", "region": "x_max", "value": [0.0, 0.0, -0.01]}],
    }
    tip = []
    for alpha in (0.0, 0.3, 1.0):
        fem = {"formulation": "nodal-strain", "strain_stabilisation": alpha}
        p = NodalStrainProblem(scene_from_dict({**sc, "fem": fem}))
        from reference_fem.solver import solve_linear_problem

        u = solve_linear_problem(p).reshape(-1, 3)
        tip.append(-u[:, 2].min())
    assert tip[0] > tip[1] > tip[2] > 0


def test_default_volumetric_share_is_alpha_mu_over_kappa():
    """An element volumetric stiffness of ``alpha mu``: the share falls as ``nu -> 1/2``."""
    for nu in (0.3, 0.49, 0.4999):
        mat = {"law": "neo-hookean", "E": 10.0, "nu": nu, "formulation": "uncoupled"}
        p = NodalStrainProblem(scene(mat, {"formulation": "nodal-strain"}))
        mu, kappa = 10.0 / (2 * (1 + nu)), 10.0 / (3 * (1 - 2 * nu))
        assert p.fraction == pytest.approx(0.3 * mu / kappa, rel=1e-9)
    given = {"formulation": "nodal-strain", "stabilisation": 0.01}
    assert NodalStrainProblem(scene(mat, given)).fraction == 0.01


def test_options():
    opts = parse_fem_options(
        TableReader({"formulation": "nodal-strain", "strain_stabilisation": 0.2}, "[fem]", "s")
    )
    assert (opts.strain_stabilisation, opts.stabilisation) == (0.2, None)
    assert FemOptions(formulation="nodal-volume").volumetric_share == 1e-4
    with pytest.raises(SceneError, match="strain_stabilisation.*nodal-strain"):
        parse_fem_options(TableReader({"strain_stabilisation": 0.2}, "[fem]", "s"))
    with pytest.raises(SceneError, match=r"must lie in \[0, 1\]"):
        parse_fem_options(
            TableReader({"formulation": "nodal-strain", "strain_stabilisation": 2.0}, "[fem]", "s")
        )
    with pytest.raises(SceneError, match="order 1"):
        parse_fem_options(TableReader({"formulation": "nodal-strain", "order": 2}, "[fem]", "s"))
    ok = parse_fem_options(
        TableReader({"formulation": "nodal-strain", "stabilisation": 0.01}, "[fem]", "s")
    )
    assert ok.stabilisation == 0.01
