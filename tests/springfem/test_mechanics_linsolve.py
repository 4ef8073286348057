"""The one linear solver: direct and AMG agree on an irregular mesh, in both forms (free
block, and full matrix with eliminated constraints), symmetric and not; the size rule;
a singular matrix is refused."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from springfem.errors import SolverError
from springfem.mechanics import DIRECT_MAX_DOFS, LinearSolver, rigid_body_modes
from springfem.mechanics.linsolve import SUPERLU_MAX_DOFS
from springfem.mesh import box_mesh

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the shared test systems
from mechanics_systems import EdgeSprings  # noqa: E402


def jittered_block():
    """Edge springs on a 6x3x3 box whose interior nodes are moved by up to 0.2 h: no two
    elements alike, so nothing depends on the regular grid. Clamped at x = 0."""
    mesh = box_mesh((2.0, 1.0, 1.0), (6, 3, 3))
    x0 = mesh.points.copy()
    rng = np.random.default_rng(7)
    interior = np.all((x0 > 1e-9) & (x0 < np.array([2.0, 1.0, 1.0]) - 1e-9), axis=1)
    x0[interior] += rng.uniform(-0.2, 0.2, (interior.sum(), 3)) / 3.0
    clamped = np.flatnonzero(x0[:, 0] < 1e-9)
    fixed = (3 * clamped[:, None] + np.arange(3)).ravel()
    sys = EdgeSprings(x0, mesh.tets, fixed)
    K = sp.csr_matrix(sys.stiffness(x0))
    free = np.ones(K.shape[0], dtype=bool)
    free[fixed] = False
    b = np.random.default_rng(3).standard_normal(K.shape[0])
    return K, free, b, rigid_body_modes(x0)


def test_direct_and_amg_agree_on_a_jittered_mesh():
    """CG stops at |r| <= 1e-12 |b|; the solution error is at most cond(K) times that
    (cond ~ 1e3 for this small block), so 1e-8 holds with margin and fails for any wrong
    elimination, preconditioner or block layout."""
    K, free, b, B = jittered_block()
    direct = LinearSolver("direct").solve(K, b, free)
    amg = LinearSolver("amg", near_nullspace=B, rtol=1e-12)
    x = amg.solve(K, b, free)
    assert amg.name == "cg+amg" and amg.stats["krylov_iterations"] > 0
    assert np.all(direct[~free] == 0) and np.all(x[~free] == 0)
    assert np.linalg.norm(x - direct) <= 1e-8 * np.linalg.norm(direct)
    # residual of the direct solve on the free rows: round-off
    r = (K @ direct - b)[free]
    assert np.linalg.norm(r) <= 1e-10 * np.linalg.norm(b[free])
    # the free-block form gives the same solution
    Kff = K[free][:, free]
    xf = LinearSolver("amg", near_nullspace=B[free], rtol=1e-12).solve(Kff, b[free])
    assert np.linalg.norm(xf - direct[free]) <= 1e-8 * np.linalg.norm(direct)


def test_gmres_for_a_non_symmetric_matrix():
    """K + a skew part (as non-gradient torsion gives): GMRES + AMG on the symmetric part
    agrees with SuperLU to the Krylov tolerance times the condition number."""
    K, free, b, B = jittered_block()
    Kff = K[free][:, free]
    rng = np.random.default_rng(5)
    S = sp.random(Kff.shape[0], Kff.shape[0], density=0.01, random_state=rng)
    A = (Kff + 0.05 * abs(Kff).max() * (S - S.T)).tocsr()
    direct = LinearSolver("direct").solve(A, b[free])
    amg = LinearSolver("amg", near_nullspace=B[free], rtol=1e-12)
    x = amg.solve(A, b[free])
    assert amg.name == "gmres+amg"
    assert np.linalg.norm(A @ direct - b[free]) <= 1e-10 * np.linalg.norm(b[free])
    assert np.linalg.norm(x - direct) <= 1e-8 * np.linalg.norm(direct)


def test_size_rule():
    """PARDISO's crossover with AMG is higher than SuperLU's; a saddle point is always
    factorised (smoothed aggregation cannot precondition an indefinite matrix)."""
    auto = LinearSolver()
    n = auto.direct_max_dofs
    assert n == (DIRECT_MAX_DOFS if auto.direct.backend == "pardiso" else SUPERLU_MAX_DOFS)
    assert auto.kind(n) == "direct" and auto.kind(n + 1) == "amg"
    assert LinearSolver("direct").kind(10**6) == "direct"
    assert LinearSolver("amg", saddle_point=True).kind(10**6) == "direct"


@pytest.mark.parametrize("method", ["direct", "amg"])
def test_singular_matrix_is_refused(method):
    """No constraint: the springs' rigid-body modes make K singular; a net force has no
    solution, and both solvers say so instead of returning garbage."""
    K, free, b, B = jittered_block()
    b = np.zeros(K.shape[0])
    b[0::3] = 1.0  # a net force along x
    solver = LinearSolver(method, near_nullspace=B, maxiter=200)
    with pytest.raises(SolverError, match="singular stiffness"):
        solver.solve(K, b, np.ones(K.shape[0], dtype=bool))


def test_reused_hierarchy_solves_the_new_matrix():
    """A hierarchy built for ``K`` preconditions CG on ``K + D`` (a stiffer nearby matrix,
    as the next Newton tangent): the solution is ``(K + D)^-1 b`` (checked against SuperLU
    to 1e-8, the cond * rtol margin of the test above), not ``K^-1 b``, and no hierarchy is
    built again."""
    K, free, b, B = jittered_block()
    Kff, bf = K[free][:, free], b[free]
    Kn = (Kff + sp.diags(0.3 * Kff.diagonal())).tocsr()  # a different SPD matrix
    solver = LinearSolver("amg", near_nullspace=B[free], rtol=1e-12)
    first = solver.factorize(Kff)
    first.solve(bf)
    second = solver.factorize(Kn, reuse=first)
    assert second._ml is first._ml  # the hierarchy is shared, not rebuilt
    x = second.solve(bf)
    ref = LinearSolver("direct").solve(Kn, bf)
    assert np.linalg.norm(x - ref) <= 1e-8 * np.linalg.norm(ref)
    old = LinearSolver("direct").solve(Kff, bf)
    assert np.linalg.norm(x - old) > 1e-3 * np.linalg.norm(ref)  # the new matrix's answer


def test_stale_hierarchy_is_rebuilt():
    """Once the reused hierarchy's iterations exceed REUSE_GROWTH times its first count,
    the next factorisation builds its own; the direct solver never shares anything."""
    from springfem.mechanics.linsolve import REUSE_GROWTH

    K, free, b, B = jittered_block()
    Kff, bf = K[free][:, free], b[free]
    solver = LinearSolver("amg", near_nullspace=B[free], rtol=1e-12)
    first = solver.factorize(Kff)
    first.solve(bf)
    first._last_iterations = int(REUSE_GROWTH * first._fresh_iterations) + 3
    assert solver.factorize(Kff, reuse=first)._ml is None  # built afresh on first solve
    lu = LinearSolver("direct").factorize(Kff, reuse=first)
    assert lu._ml is None and lu._lu is not None
