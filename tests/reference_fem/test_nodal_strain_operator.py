"""The nodal-strain FEM's compiled nodal average against its sparse operator ``B``.

Reference: :func:`reference_fem.nodal_strain.strain_gradient`, the scipy matrix the
formulation was written with (``Fbar = I + B u``, forces ``B^T T``, tangent
``B^T diag(A) B``), on an irregular Delaunay mesh at nu = 0.49; and central differences of
the forces for the tangent.
"""

import numpy as np
import scipy.sparse as sp

from reference_fem.nodal_strain import NodalStrainProblem

from .test_nodal_strain import scene

NEO49 = {"law": "neo-hookean", "E": 10.0, "nu": 0.49}


def problem():
    return NodalStrainProblem(scene(NEO49, {"formulation": "nodal-strain"}))


def test_average_equals_the_sparse_operator():
    p = problem()
    n = p.space.n_nodes
    rng = np.random.default_rng(0)
    u = 0.05 * rng.standard_normal(3 * n)
    B = p.B_strain
    F = p.nodal_deformation_gradients(u)
    ref = (B @ u).reshape(-1, 3, 3) + np.eye(3)
    assert np.abs(F - ref).max() < 1e-14 * np.abs(ref).max()
    T = rng.standard_normal((n, 3, 3))
    f = p.average.transpose(T).ravel()
    assert np.abs(f - B.T @ T.ravel()).max() < 1e-13 * np.abs(f).max()
    A = rng.standard_normal((n, 9, 9))
    Ad = sp.bsr_matrix((A, np.arange(n), np.arange(n + 1)), shape=(9 * n, 9 * n)).tocsr()
    ref = (B.T @ Ad @ B).toarray()
    assert np.abs(p.average.tangent(A).toarray() - ref).max() < 1e-13 * np.abs(ref).max()


def test_tangent_is_the_force_derivative():
    p = problem()
    rng = np.random.default_rng(1)
    u = 0.005 * rng.standard_normal(p.n_dofs)  # at 0.02 the h^2 truncation reaches 4e-5
    fi, K = p.internal_force(u, tangent=True)
    du = 1e-6 * rng.standard_normal(p.n_dofs)
    df = p.internal_force(u + du)[0] - p.internal_force(u - du)[0]
    # central differences: truncation ~|du|^2 (measured 9e-11 here), round-off ~1e-16 |f| / |du|
    assert np.abs(K @ du - df / 2.0).max() < 1e-8 * np.abs(df).max()
    dE = p.energy(u + du) - p.energy(u - du)
    assert abs(dE - 2.0 * fi @ du) < 1e-6 * abs(dE)
