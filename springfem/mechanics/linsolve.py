"""Linear solves with a tangent: SuperLU, or CG / GMRES with smoothed-aggregation AMG.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> A = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(4, 4))
>>> x, name = solve_linear(A, np.ones(4))
>>> np.round(x, 12).tolist(), name
([2.0, 3.0, 3.0, 2.0], 'direct')
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from springfem.errors import SolverError

LinearSolverKind = Literal["auto", "direct", "amg"]

#: Above this many free DOFs, ``linear_solver="auto"`` uses CG/GMRES + smoothed-aggregation AMG.
AMG_THRESHOLD = 12_000
#: Relative asymmetry ``|K - K^T| / |K|`` below which a tangent is treated as symmetric
#: (the central-difference Jacobian of a gradient field is symmetric to ~1e-10).
SYMMETRY_TOL = 1e-6


def is_symmetric(A: sp.spmatrix) -> bool:
    """Whether ``|A - A^T| <= SYMMETRY_TOL |A|`` (Frobenius norms).

    Parameters
    ----------
    A
        Square sparse matrix.

    Returns
    -------
    bool
        ``True`` for a symmetric matrix up to finite-difference noise.
    """
    nrm = spla.norm(A)
    return bool(nrm == 0 or spla.norm(A - A.T) <= SYMMETRY_TOL * nrm)


class LinearSolver:
    """A factorised (free-DOF) tangent: solve ``A x = b`` for several right-hand sides.

    ``direct`` is SuperLU; ``amg`` is CG (symmetric ``A``) or GMRES (non-symmetric, e.g. the
    Jacobian of the non-gradient torsion springs) preconditioned by pyamg smoothed
    aggregation with ``near_nullspace`` (the rigid-body modes) as candidates. ``auto`` is
    direct up to :data:`AMG_THRESHOLD` unknowns; a failed direct solve falls back to AMG.
    A tangent whose asymmetry is below :data:`SYMMETRY_TOL` (finite-difference noise) is
    symmetrised for CG.

    Attributes
    ----------
    name
        The solver that produced the last solution (``direct``, ``cg+amg``, ``gmres+amg``).
    """

    def __init__(
        self,
        A: sp.spmatrix,
        method: LinearSolverKind = "auto",
        near_nullspace: np.ndarray | None = None,
        rtol: float = 1e-10,
    ):
        self.A = sp.csr_matrix(A)
        n = self.A.shape[0]
        if method == "auto":
            method = "direct" if n <= AMG_THRESHOLD else "amg"
        if method not in ("direct", "amg"):
            raise ValueError(f"unknown linear solver {method!r}; valid: 'auto', 'direct', 'amg'")
        self.method = method
        self.B = near_nullspace
        self.rtol = rtol
        self.name = "none"
        self._lu = None
        self._ml = None
        if method == "direct":
            try:
                self._lu = spla.splu(self.A.tocsc())
            except RuntimeError:  # exactly singular factor: try AMG
                self._lu = None

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Solve ``A x = b``.

        Raises
        ------
        SolverError
            When no solver produces a finite solution with a small residual (singular ``A``).
        """
        b = np.asarray(b, dtype=float)
        bnorm = float(np.linalg.norm(b))
        if bnorm == 0:
            return np.zeros(self.A.shape[0])
        if self._lu is not None:
            x = self._lu.solve(b)
            if np.all(np.isfinite(x)) and np.linalg.norm(self.A @ x - b) <= 1e-6 * bnorm:
                self.name = "direct"
                return x
        x, A_used = self._solve_amg(b)
        if (
            not np.all(np.isfinite(x))
            or np.linalg.norm(A_used @ x - b) > max(1e-6, 10 * self.rtol) * bnorm
        ):
            raise SolverError(
                "singular stiffness: the tangent has a zero-energy mode (a mechanism of the "
                "spring network, a limit point, or a missing boundary condition)"
            )
        return x

    def _solve_amg(self, b: np.ndarray) -> tuple[np.ndarray, sp.csr_matrix]:
        if self._ml is None:
            import pyamg

            self._sym = is_symmetric(self.A)
            self._As = ((self.A + self.A.T) * 0.5).tocsr() if self._sym else self.A
            B = self.B
            kw = {"B": B} if B is not None and B.shape[0] == self.A.shape[0] else {}
            self._ml = pyamg.smoothed_aggregation_solver(
                self._As, symmetry="hermitian" if self._sym else "nonsymmetric", **kw
            )
        M = self._ml.aspreconditioner(cycle="V")
        maxiter = max(200, self.A.shape[0] // 10)
        if self._sym:
            x, _ = spla.cg(self._As, b, rtol=self.rtol, atol=0.0, maxiter=maxiter, M=M)
            self.name = "cg+amg"
            return x, self._As
        x, _ = spla.gmres(self.A, b, rtol=self.rtol, atol=0.0, restart=60, maxiter=maxiter, M=M)
        self.name = "gmres+amg"
        return x, self.A


def solve_linear(
    A: sp.spmatrix,
    b: np.ndarray,
    method: LinearSolverKind = "auto",
    near_nullspace: np.ndarray | None = None,
    rtol: float = 1e-10,
) -> tuple[np.ndarray, str]:
    """Solve ``A x = b`` once with a :class:`LinearSolver`; returns ``(x, solver name)``."""
    solver = LinearSolver(A, method, near_nullspace, rtol)
    x = solver.solve(b)
    return x, solver.name
