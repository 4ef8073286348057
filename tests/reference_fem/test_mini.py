"""The MINI pair (``[fem] formulation = "mini"``): consistent tangent against finite
differences, the patch test (a homogeneous deformation and its constant pressure are exact
in P1-bubble / P1), the closed-form incompressible stretch, and the options."""

import numpy as np
import pytest

from reference_fem import solve
from reference_fem.mini import MiniProblem
from reference_fem.options import parse_fem_options
from springfem.errors import SceneError
from springfem.mesh import box_mesh
from springfem.scene import TableReader, scene_from_dict

NEO = {"law": "neo-hookean", "E": 10.0, "nu": 0.49}
GUCCIONE = {"law": "guccione", "C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0}
AXES = {"fiber": [1.0, 1.0, 0.2], "sheet": [-1.0, 1.0, 0.0]}
GRAD = np.array([[0.03, -0.01, 0.02], [0.01, -0.02, 0.015], [-0.02, 0.025, 0.01]])


def mini(material, mesh=None, **extra):
    mesh = mesh or box_mesh((1.0, 0.8, 0.6), (2, 2, 1), split="delaunay", seed=3)
    scene = scene_from_dict(
        {"mesh": mesh, "material": material, "axes": AXES, "fem": {"formulation": "mini"}, **extra}
    )
    return MiniProblem(scene)


@pytest.mark.parametrize("material", [NEO, {**GUCCIONE, "kappa": 50.0}], ids=["neo", "guccione"])
def test_tangent_is_the_derivative_of_the_residual(material):
    p = mini(material)
    rng = np.random.default_rng(2)
    x = np.zeros(p.n_dofs)
    x[: p.nu] = 0.01 * rng.standard_normal(p.nu)
    x[p.nu :] = 0.05 * rng.standard_normal(p.n_p)
    _, K, _, _ = p.residual_tangent(x, 1.0)
    v = rng.standard_normal(p.n_dofs)
    h = 1e-6
    fd = (p.residual(x + h * v)[0] - p.residual(x - h * v)[0]) / (2 * h)
    # central differences: O(h^2) truncation, which the exponential law's third derivative
    # makes ~1e-7 relative, plus round-off
    assert np.abs(fd - K @ v).max() <= 1e-6 * np.abs(K @ v).max()
    np.testing.assert_allclose(K.toarray(), K.toarray().T, atol=1e-12 * abs(K).max())


# finite kappa: with the whole boundary prescribed an incompressible body's pressure is
# defined only up to a constant (a singular system), as in the continuum
@pytest.mark.parametrize("material", [NEO, {**GUCCIONE, "kappa": 50.0}], ids=["neo", "guccione"])
def test_patch_homogeneous_deformation_is_reproduced_inside(material):
    p = mini(material, box_mesh((1.0, 0.8, 0.6), (3, 3, 3), split="delaunay", seed=1))
    F = np.eye(3) + 2.0 * GRAD
    X = p.space.node_coordinates.copy()
    X[p.space.n_vertices :] = 0.0  # the bubbles' exact amplitude is zero
    exact = (X @ (F - np.eye(3)).T).ravel()
    boundary = np.unique(p.scene.mesh.boundary_facets())
    free = np.ones(p.n_dofs, dtype=bool)
    free[(3 * boundary[:, None] + np.arange(3)).ravel()] = False
    x = np.zeros(p.n_dofs)
    for load in np.linspace(0.25, 1.0, 4):
        x[: p.nu][~free[: p.nu]] = load * exact[~free[: p.nu]]
        for _ in range(20):
            R, K = p.internal_force(x, tangent=True)
            if np.abs(R[free]).max() <= 1e-13 * max(np.abs(R).max(), 1e-300):
                break
            x[free] += p.linear_solver.solve(K, -R, free)[free]
    U, pressure = p.split(x)
    # the bubbles vanish and the field is the linear one, to Newton's tolerance
    np.testing.assert_allclose(U.ravel(), exact, atol=1e-10 * np.abs(exact).max())
    assert np.ptp(pressure) <= 1e-8 * np.abs(pressure).max()  # one constant pressure


def test_incompressible_uniaxial_stretch_is_the_closed_form():
    """Guccione, fibre along x, incompressible: F = diag(l, l^-1/2, l^-1/2) under P_11."""
    C, bf, bt = GUCCIONE["C"], GUCCIONE["b_f"], GUCCIONE["b_t"]
    stretch = 1.15
    lat = stretch**-0.5
    lams = np.array([stretch, lat, lat])
    Bd = np.array([bf, bt, bt])
    E = 0.5 * (lams**2 - 1)
    d = C * np.exp((Bd * E**2).sum()) * Bd * E * lams
    P = d[0] - lat / stretch * d[1]
    scene = scene_from_dict(
        {
            "mesh": {"generator": "box", "size": [1, 1, 1], "divisions": [1, 1, 1]},
            "material": {**GUCCIONE, "incompressible": True},
            "axes": {"fiber": [1, 0, 0], "sheet": [0, 1, 0]},
            "boundary": [
                {"region": "x_min", "fix": ["x"]},
                {"region": "y_min", "fix": ["y"]},
                {"region": "z_min", "fix": ["z"]},
            ],
            "load": [{"type": "traction", "region": "x_max", "value": [P, 0.0, 0.0]}],
            "probe": [{"name": "corner", "point": [1, 1, 1]}],
            "fem": {"formulation": "mini", "load_steps": 2},
        }
    )
    got = 1.0 + np.array(solve(scene).result.probes["corner"])
    assert got == pytest.approx(lams, rel=1e-7)  # Newton tolerance 1e-10 on |R|


def test_mini_needs_order_1():
    with pytest.raises(SceneError, match="order"):
        parse_fem_options(TableReader({"formulation": "mini", "order": 2}, "[fem]", "s.toml"))
