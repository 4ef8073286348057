"""Patch tests: a linear displacement prescribed on the boundary is reproduced exactly
inside, on a distorted mesh, for P1 and P2, isotropic and transversely isotropic (fibers
along an oblique direction; a homogeneous material, since a constant strain is in
equilibrium only if the stress is constant too)."""

import numpy as np
import pytest

from reference_fem import FemProblem, solve
from springfem.mesh import box_mesh
from springfem.scene import Material, scene_from_dict

ISOTROPIC = Material("linear", 2.0e3, 0.3)
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
GRAD = np.array([[0.010, -0.004, 0.002], [0.003, -0.006, 0.005], [-0.002, 0.007, 0.004]])
SHIFT = np.array([0.001, -0.002, 0.0005])


def linear_field(x):
    return x @ GRAD.T + SHIFT


def distorted_mesh(seed=0):
    m = box_mesh((1.0, 0.7, 0.5), (3, 3, 2))
    lo, hi = m.bounding_box()
    inside = ((m.points > lo + 1e-9) & (m.points < hi - 1e-9)).all(axis=1)
    m.points[inside] += 0.06 * np.random.default_rng(seed).uniform(-1, 1, (inside.sum(), 3))
    assert (m.volumes() > 0).all()
    return m


def oblique_frames(n, seed=1):
    q, _ = np.linalg.qr(np.random.default_rng(seed).standard_normal((3, 3)))
    if np.linalg.det(q) < 0:
        q[:, 2] *= -1
    return np.broadcast_to(q.T, (n, 3, 3)).copy()


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("material", [ISOTROPIC, TRANSVERSE], ids=["isotropic", "transverse"])
def test_linear_boundary_field_is_reproduced_inside(order, material):
    mesh = distorted_mesh()
    frames = oblique_frames(mesh.n_tets)
    mesh.cell_data.update(fiber=frames[:, 0], sheet=frames[:, 1])
    scene = scene_from_dict({"mesh": mesh, "material": material, "axes": {"type": "cells"}})
    problem = FemProblem(scene, order)
    space = problem.space
    boundary = space.region_nodes(np.unique(mesh.boundary_facets()))
    dofs = (3 * boundary[:, None] + np.arange(3)).ravel()
    u = np.zeros(space.n_dofs)
    u[dofs] = linear_field(space.node_coordinates[boundary]).ravel()
    free = np.ones(space.n_dofs, dtype=bool)
    free[dofs] = False
    assert free.sum() > 0
    K = problem.stiffness
    u += problem.linear_solver.solve(K, -(K @ u), free)
    exact = linear_field(space.node_coordinates).ravel()
    # exact up to the solver's round-off (condition ~1e3 on this small mesh)
    np.testing.assert_allclose(u, exact, atol=1e-12 * np.abs(exact).max())
    # and the internal forces vanish at the interior nodes
    assert np.abs((K @ u)[free]).max() < 1e-10 * np.abs(K @ u).max()


@pytest.mark.parametrize("order", [1, 2])
def test_uniform_traction_gives_uniform_stress(order):
    """Constant-stress patch through the public API: uniaxial stress from a traction."""
    mesh = distorted_mesh()
    E, nu, t = 2.0e3, 0.3, 5.0
    scene = scene_from_dict(
        {
            "mesh": mesh,
            "material": {"law": "linear", "E": E, "nu": nu},
            "boundary": [
                {"region": "x_min", "fix": ["x"]},
                {"region": {"point": [0.0, 0.0, 0.0]}, "fix": ["y", "z"]},
                {"region": {"point": [0.0, 0.7, 0.0]}, "fix": ["z"]},
            ],
            "load": [{"type": "traction", "value": [t, 0.0, 0.0], "region": "x_max"}],
            "probe": [{"name": "far", "point": [1.0, 0.7, 0.5]}],
        }
    )
    sol = solve(scene, order=order)
    # u = (t/E) (x, -nu y, -nu z) from the pinned corner
    np.testing.assert_allclose(
        sol.result.probes["far"], t / E * np.array([1.0, -nu * 0.7, -nu * 0.5]), rtol=1e-9
    )
    np.testing.assert_allclose(sol.cell_data["von_mises"], t, rtol=1e-9)
    np.testing.assert_allclose(sol.result.reactions["x_min"], [-t * 0.7 * 0.5, 0, 0], atol=1e-9)
