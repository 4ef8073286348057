"""h-refinement with a manufactured smooth solution: L2 error rates 2 (P1) and 3 (P2).

``u_k = sin(a_k . x + phi_k)`` on the unit cube, exact Dirichlet values on the whole
boundary and the body force ``b_i = -C_ijkl d_j d_l u_k = C_ijkl a_kj a_kl u_k``. The error
is integrated with a degree-6 rule; the rate is fitted with ``np.polyfit(log h, log err)``.
"""

import numpy as np
import pytest

from reference_fem.assembly import stiffness_matrix
from reference_fem.loads import body_force_vector
from reference_fem.materials import material_matrix
from reference_fem.space import Space
from springfem.axes import uniform_frames
from springfem.materials import isotropic_matrix, voigt_to_tensor
from springfem.mechanics import LinearSolver
from springfem.mesh import box_mesh
from springfem.scene import Material

WAVES = np.array([[1.0, 0.5, 0.3], [-0.4, 1.2, 0.7], [0.6, -0.8, 1.1]])  # a_k as rows
PHASES = np.array([0.2, 0.5, -0.3])
TRANSVERSE = Material(
    "transverse-linear",
    1.0,
    0.4,
    E_fiber=3.0,
    E_cross=1.0,
    nu_fiber_cross=0.3,
    nu_cross=0.4,
    G_fiber=0.5,
)


def u_exact(x):
    return np.sin(x @ WAVES.T + PHASES)


def l2_error(n, order, D):
    mesh = box_mesh((1.0, 1.0, 1.0), (n, n, n))
    C = voigt_to_tensor(D)

    def body_force(x):
        return np.einsum("ijkl,kj,kl,...k->...i", C, WAVES, WAVES, u_exact(x))

    space = Space(mesh, order)
    K = stiffness_matrix(space, D[None], np.zeros(mesh.n_tets, dtype=int))
    f = body_force_vector(Space(mesh, order, 4), body_force)  # smooth load, accurate rule
    boundary = space.region_nodes(np.unique(mesh.boundary_facets()))
    dofs = (3 * boundary[:, None] + np.arange(3)).ravel()
    u = np.zeros(space.n_dofs)
    u[dofs] = u_exact(space.node_coordinates[boundary]).ravel()
    free = np.ones(space.n_dofs, dtype=bool)
    free[dofs] = False
    u += LinearSolver("direct").solve(K, f - K @ u, free)
    q = Space(mesh, order, 6)
    uh = np.einsum("qa,eai->eqi", q.values, u.reshape(-1, 3)[q.element_nodes])
    err2 = (q.dx * ((uh - u_exact(q.quadrature_points())) ** 2).sum(axis=-1)).sum()
    return np.sqrt(err2)


def fitted_rate(order, divisions, D):
    h = 1.0 / np.asarray(divisions, dtype=float)
    err = [l2_error(n, order, D) for n in divisions]
    return np.polyfit(np.log(h), np.log(err), 1)[0]


@pytest.mark.parametrize(
    "order,divisions,expected",
    [(1, (4, 8, 12), 2.0), (2, (2, 4, 6), 3.0)],
)
def test_l2_rate_isotropic(order, divisions, expected):
    rate = fitted_rate(order, divisions, isotropic_matrix(1.0, 0.3))
    # pre-asymptotic meshes: measured 1.99 (P1) and 2.95 (P2)
    assert rate == pytest.approx(expected, abs=0.15)


def test_l2_rate_transverse_p2():
    frames = uniform_frames(1, [0.6, 0.64, 0.48], [0.8, -0.48, -0.36])
    D = material_matrix(TRANSVERSE, frames)[0]
    assert fitted_rate(2, (2, 4, 6), D) == pytest.approx(3.0, abs=0.15)


@pytest.mark.slow
@pytest.mark.parametrize(
    "order,divisions,expected", [(1, (8, 12, 16, 20), 2.0), (2, (4, 6, 8), 3.0)]
)
def test_l2_rate_finer_meshes(order, divisions, expected):
    rate = fitted_rate(order, divisions, isotropic_matrix(1.0, 0.3))
    assert rate == pytest.approx(expected, abs=0.05)
