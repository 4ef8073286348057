"""The direct solver: PARDISO and SuperLU give the same solutions (each checked against
the matrix by its residual, and against numpy's dense solve), the symbolic analysis is
reused while the pattern is unchanged and redone when it changes, a nearly symmetric
matrix is solved exactly (refined against itself, or by LU when the refinement cannot
converge), the saddle point of a mixed formulation (zero pressure block, missing diagonal
entries) is solved, and without PARDISO everything falls back to SuperLU."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from springfem.mechanics import LinearSolver, pardiso
from springfem.mechanics.direct import DirectSolver

BACKENDS = ["superlu"] + (["pardiso"] if pardiso.available() else [])


def stiffness(n_side: int = 7, seed: int = 1) -> sp.csr_matrix:
    """SPD graph Laplacian-plus-mass of a jittered random point cloud (irregular pattern)."""
    rng = np.random.default_rng(seed)
    n = n_side**3
    pts = rng.uniform(0, 1, (n, 3))
    d = np.linalg.norm(pts[:, None] - pts[None], axis=2)
    W = np.where((d < 1.6 / n_side) & (d > 0), 1.0 / (d + 0.1), 0.0)
    L = np.diag(W.sum(1)) - W + 0.05 * np.eye(n)
    return sp.csr_matrix(L)


def saddle_point(seed: int = 2) -> sp.csr_matrix:
    """[[K, B^T], [B, 0]] with an empty pressure block: indefinite, zero diagonal entries."""
    K = stiffness(6, seed)
    rng = np.random.default_rng(seed)
    B = sp.random(40, K.shape[0], density=0.05, random_state=rng, format="csr")
    B = B + sp.eye(40, K.shape[0], format="csr")  # full row rank
    return sp.bmat([[K, B.T], [B, None]], format="csr")


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("kind", ["spd", "saddle", "unsymmetric", "near-symmetric"])
def test_solution_matches_dense_solve(backend, kind):
    """Same solution as numpy's dense LU to 1e-9 relative (the matrices' condition numbers
    are below 1e4, so a correct solve is good to ~1e-12; a wrong permutation, triangle or
    refinement is off by O(1))."""
    A = saddle_point() if kind == "saddle" else stiffness()
    rng = np.random.default_rng(4)
    n = A.shape[0]
    if kind in ("unsymmetric", "near-symmetric"):
        S = sp.random(n, n, density=0.02, random_state=rng)
        S.data[:] = rng.standard_normal(S.nnz)
        amp = 0.3 if kind == "unsymmetric" else 1e-4
        A = (A + amp * abs(A).max() * (S - S.T)).tocsr()
    free = rng.uniform(size=n) > 0.1
    b = rng.standard_normal(int(free.sum()))
    f = DirectSolver(backend).factor(A, free)
    x = f.solve(b)
    ref = np.linalg.solve(A.toarray()[np.ix_(free, free)], b)
    assert np.linalg.norm(x - ref) <= 1e-9 * np.linalg.norm(ref)
    if backend == "pardiso":
        assert f.name == ("pardiso-lu" if kind == "unsymmetric" else "pardiso-ldlt")


@pytest.mark.skipif(not pardiso.available(), reason="needs MKL PARDISO (pypardiso)")
def test_analysis_reused_for_the_same_pattern_and_redone_for_a_new_one():
    """Three matrices of one pattern: one analysis; an entry added: a second one. Each
    factor solves its own matrix (not the first one's)."""
    A = stiffness()
    solver = DirectSolver("pardiso")
    b = np.ones(A.shape[0])
    for k in range(3):
        Ak = (A + sp.diags(np.full(A.shape[0], float(k)))).tocsr()
        x = solver.factor(Ak).solve(b)
        assert np.linalg.norm(Ak @ x - b) <= 1e-10 * np.linalg.norm(b)
    assert solver.analyses == 1
    B = A.tolil()
    B[0, A.shape[0] - 1] = B[A.shape[0] - 1, 0] = -0.01  # a new entry: a new pattern
    B = B.tocsr()
    x = solver.factor(B).solve(b)
    assert solver.analyses == 2 and np.linalg.norm(B @ x - b) <= 1e-10 * np.linalg.norm(b)


@pytest.mark.skipif(not pardiso.available(), reason="needs MKL PARDISO (pypardiso)")
def test_refinement_that_cannot_converge_falls_back_to_lu():
    """A strongly skew matrix with a symmetric part that is nearly singular: refining the
    symmetric factor diverges, the factor switches to LU and solves exactly, and the
    pattern's later matrices are factorised by LU at once."""
    n = 60
    rng = np.random.default_rng(0)
    S = np.diag(np.linspace(1e-3, 1.0, n))
    N = 5e-3 * rng.standard_normal((n, n))
    A = sp.csr_matrix(S + N - N.T)  # asymmetry 1e-2 of max |A|: within NEAR_SYMMETRIC
    solver = DirectSolver("pardiso")
    f = solver.factor(A)
    b = rng.standard_normal(n)
    x = f.solve(b)
    assert f.name == "pardiso-lu" and np.linalg.norm(A @ x - b) <= 1e-10 * np.linalg.norm(b)
    assert solver.factor(A).name == "pardiso-lu"


def test_without_pardiso_the_linear_solver_uses_superlu(monkeypatch):
    """The MKL runtime hidden (as on a machine without pypardiso): SuperLU, the lower size
    rule, the same solution."""
    monkeypatch.setattr(pardiso, "_runtime", lambda: None)
    A = stiffness()
    b = np.ones(A.shape[0])
    ls = LinearSolver()
    assert ls.direct.backend == "superlu" and ls.direct_max_dofs == 5_000
    x = ls.solve(A, b)
    assert ls.name == "direct" and np.linalg.norm(A @ x - b) <= 1e-10 * np.linalg.norm(b)
    with pytest.raises(pardiso.PardisoError, match="not available"):
        pardiso.Pardiso(symmetric=True)


def test_a_missing_pardiso_is_said_in_one_line(monkeypatch, capsys):
    """Without the package the runtime is None and one note on stderr names the fallback."""
    import builtins

    real_import = builtins.__import__

    def no_pypardiso(name, *args, **kw):
        if name == "pypardiso":
            raise ImportError("hidden by the test")
        return real_import(name, *args, **kw)

    monkeypatch.delenv("SPRINGFEM_NO_PARDISO", raising=False)
    monkeypatch.setattr(builtins, "__import__", no_pypardiso)
    pardiso._runtime.cache_clear()
    try:
        assert pardiso._runtime() is None
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "falls back to SuperLU" in err
    finally:
        monkeypatch.undo()
        pardiso._runtime.cache_clear()
