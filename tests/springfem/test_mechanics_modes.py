"""Zero-mode counts of tangents (springfem.mechanics.modes) against known kernels.

A P1 linear-elastic stiffness has exactly the six rigid-body modes as its kernel on any
mesh (free body), none once clamped; deleting the stiffness of one element of a chain
frees its nodes and adds zero modes we can count by hand. Both the dense and the
shift-invert paths are checked on the same matrix.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.spatial import Delaunay

import reference_fem.problem as fem_problem
from springfem.mechanics import modes
from springfem.mesh import TetMesh
from springfem.scene import scene_from_dict


def _delaunay_mesh(n: int = 60, seed: int = 3) -> TetMesh:
    rng = np.random.default_rng(seed)
    X = rng.uniform(0.0, 1.0, (n, 3)) * np.array([2.0, 1.0, 0.5])  # elongated, irregular
    T = Delaunay(X).simplices
    V = np.linalg.det(X[T][:, 1:] - X[T][:, :1]) / 6
    keep = np.abs(V) > 1e-3 * np.abs(V).mean()
    T, V = T[keep], V[keep]
    T[V < 0] = T[V < 0][:, [0, 2, 1, 3]]
    used = np.unique(T)
    remap = np.full(n, -1)
    remap[used] = np.arange(used.size)
    return TetMesh(X[used], remap[T])


def _stiffness(clamped: bool):
    table = {
        "mesh": _delaunay_mesh(),
        "material": {"law": "linear", "E": 1.0, "nu": 0.3},
        "boundary": [
            {"region": {"box": [[-1.0, -1.0, -1.0], [0.4, 2.0, 2.0]]}, "fix": ["x", "y", "z"]}
        ]
        if clamped
        else [],
    }
    p = fem_problem.FemProblem(scene_from_dict(table), order=1)
    K = sp.csr_matrix(p.stiffness)
    return K[p.free][:, p.free] if clamped else K


def test_free_body_has_the_six_rigid_modes():
    K = _stiffness(clamped=False)
    z = modes.zero_modes(K)
    assert z.count == 6 and z.negative == 0
    # the kernel is spanned by rigid motions: projecting them out leaves nothing
    X = _delaunay_mesh().points
    R = np.linalg.qr(
        np.column_stack(
            [np.tile(e, len(X)) for e in np.eye(3)] + [np.cross(e, X).ravel() for e in np.eye(3)]
        )
    )[0]
    residual = z.modes - R @ (R.T @ z.modes)
    assert np.abs(residual).max() < 1e-8
    assert modes.spurious_modes(K, free_body=True) == 0


def test_clamped_body_has_none():
    assert modes.zero_modes(_stiffness(clamped=True)).count == 0


def test_a_body_pinned_at_one_node_keeps_its_three_rotations():
    table = {
        "mesh": _delaunay_mesh(),
        "material": {"law": "linear", "E": 1.0, "nu": 0.3},
        "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],  # one node of a point cloud
    }
    p = fem_problem.FemProblem(scene_from_dict(table), order=1)
    assert p.fixed_dofs.size == 3
    K = sp.csr_matrix(p.stiffness)[p.free][:, p.free]
    assert modes.zero_modes(K).count == 3


def test_a_chain_with_a_cut_spring_has_one_mode_per_loose_piece():
    # a chain of 6 unit springs fixed at node 0; spring 3 removed: nodes 4..6 float as one
    n = 6
    k = np.ones(n)
    k[3] = 0.0
    K = np.zeros((n + 1, n + 1))
    for i, ki in enumerate(k):
        K[np.ix_([i, i + 1], [i, i + 1])] += ki * np.array([[1, -1], [-1, 1]])
    assert modes.zero_modes(K[1:, 1:]).count == 1


@pytest.mark.parametrize("clamped", [False, True])
def test_shift_invert_path_agrees_with_dense(monkeypatch, clamped):
    K = _stiffness(clamped)
    dense = modes.zero_modes(K)
    monkeypatch.setattr(modes, "DENSE_MAX_DOFS", 10)
    sparse = modes.zero_modes(K, k=10)
    assert sparse.count == dense.count
    assert sparse.lambda_max == pytest.approx(dense.lambda_max, rel=1e-8)
    n = 10
    np.testing.assert_allclose(sparse.values[:n], dense.values[:n], atol=1e-9)
