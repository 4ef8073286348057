"""The iterative half of the one linear solver (:mod:`.linsolve`): a pyamg smoothed
aggregation hierarchy with the rigid-body modes as near-nullspace, and CG (symmetric) or
GMRES (otherwise) preconditioned by one V-cycle of it. Each Krylov iteration calls
:func:`~springfem.mechanics.limits.checkpoint`, so a time cap or Ctrl-C stops a long solve.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> A = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(50, 50), format="csr")
>>> ml = hierarchy(A, blocks=False, near_nullspace=None, coarse="splu")
>>> x, its, name = krylov(A, np.ones(50), ml, symmetric=True, rtol=1e-10, maxiter=100)
>>> name, bool(np.linalg.norm(A @ x - 1.0) < 1e-8)
('cg+amg', True)
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .limits import checkpoint

__all__ = ["hierarchy", "krylov"]


def hierarchy(S: sp.csr_matrix, blocks: bool, near_nullspace: np.ndarray | None, coarse: str):
    """Smoothed-aggregation hierarchy of the symmetric matrix ``S``.

    Parameters
    ----------
    S
        Symmetric matrix (the symmetric part of the one to solve).
    blocks
        Aggregate 3x3 nodal blocks (a full displacement matrix with its constrained DOFs
        eliminated).
    near_nullspace
        ``(n, k)`` near-nullspace (rigid-body modes), or ``None`` (constants).
    coarse
        Coarsest-level solver: ``splu``, or ``pinv`` for an exactly singular one.

    Returns
    -------
    pyamg.multilevel.MultilevelSolver
        The hierarchy.
    """
    import pyamg

    n = S.shape[0]
    if blocks and n % 3 == 0:
        S = S.tobsr(blocksize=(3, 3))
    B = near_nullspace
    return pyamg.smoothed_aggregation_solver(
        S,
        B=B if B is not None and B.shape[0] == n else None,
        symmetry="hermitian",
        strength=("symmetric", {"theta": 0.0}),
        smooth="jacobi",
        max_coarse=500,
        coarse_solver=coarse,
    )


def krylov(
    A: sp.csr_matrix, b: np.ndarray, ml, symmetric: bool, rtol: float, maxiter: int
) -> tuple[np.ndarray, int, str]:
    """CG (``symmetric``) or GMRES(60) on ``A x = b``, preconditioned by a V-cycle of ``ml``.

    Parameters
    ----------
    A
        The matrix (exactly symmetric for CG).
    b
        Right-hand side.
    ml
        The :func:`hierarchy`.
    symmetric
        CG, else GMRES.
    rtol, maxiter
        Relative residual tolerance and iterations at most.

    Returns
    -------
    x, iterations, name
        The last iterate (the caller checks its residual), the iterations and ``cg+amg``
        or ``gmres+amg``.
    """
    M = ml.aspreconditioner(cycle="V")
    count = [0]

    def cb(_):
        count[0] += 1
        checkpoint()

    if symmetric:
        x, _ = spla.cg(A, b, rtol=rtol, atol=0.0, maxiter=maxiter, M=M, callback=cb)
        return x, count[0], "cg+amg"
    x, _ = spla.gmres(
        A, b, rtol=rtol, atol=0.0, restart=60, maxiter=maxiter, M=M, callback=cb,
        callback_type="pr_norm",
    )  # fmt: skip
    return x, count[0], "gmres+amg"
