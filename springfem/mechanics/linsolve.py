"""The one linear solver of both models: SuperLU, or CG / GMRES preconditioned by pyamg
smoothed aggregation with the rigid-body modes as near-nullspace (DESIGN §5).

A :class:`LinearSolver` holds the choice (``auto``, ``direct``, ``amg``) and the settings;
:meth:`LinearSolver.factorize` prepares one matrix (an LU factor or an AMG hierarchy) for
several right-hand sides, :meth:`LinearSolver.solve` solves once. The matrix is either the
free-DOF block itself or, with ``free`` given, the full matrix whose constrained DOFs are
eliminated symmetrically (rows and columns zeroed, unit diagonal), which keeps the 3x3
block structure smoothed aggregation works best with.

Size rule (``auto``): direct up to :data:`DIRECT_MAX_DOFS` unknowns, AMG above. Measured on
the FEM stiffness of a clamped 2:1:1 box (P1 and P2, ν = 0.3, one process, warm caches):
SuperLU and AMG-CG cost the same at about 4,100 DOFs on P1 (nnz 160k) and about 6,000 on P2
(nnz 450k); at 7,600 DOFs direct is 1.8x (P1) and 1.3x (P2) slower, at 19,600 DOFs 3.5x and
3.7x, at 28,600 P2 DOFs 5.9x, and its cost grows superlinearly (fill-in) while AMG's grows
about linearly. The crossover in DOFs is about the same for both orders (it is not in nnz),
so the rule counts DOFs; below it a factorisation is also exact, which suits the small,
ill-conditioned problems (slender beams, near-incompressible P1) tests use.

A solution is accepted when its relative residual ``|A x - b| / |b|`` is at most
:data:`RESIDUAL_ACCEPT`; otherwise the solve raises :class:`~springfem.errors.SolverError`
(a singular or ill-conditioned matrix). A failed factorisation falls back to AMG.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> A = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(4, 4))
>>> x, name = solve_linear(A, np.ones(4))
>>> np.round(x, 12).tolist(), name
([2.0, 3.0, 3.0, 2.0], 'direct')
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from springfem.errors import InputError, SolverError

from .matrices import SYMMETRY_TOL, eliminate, is_symmetric

__all__ = [
    "DIRECT_MAX_DOFS", "RESIDUAL_ACCEPT", "REUSE_GROWTH", "SYMMETRY_TOL", "Factorization",
    "LinearSolver", "LinearSolverKind", "eliminate", "is_symmetric", "solve_linear",
]  # fmt: skip

LinearSolverKind = Literal["auto", "direct", "amg"]

#: ``auto`` factorises (SuperLU) up to this many unknowns and uses AMG above (see the
#: module docstring for the measurement).
DIRECT_MAX_DOFS = 5_000
#: Largest accepted relative residual ``|A x - b| / |b|`` of a solution.
RESIDUAL_ACCEPT = 1e-6
#: A reused AMG hierarchy is rebuilt past this growth of its Krylov iterations.
REUSE_GROWTH = 2.0


@dataclass
class LinearSolver:
    """The choice of linear solver and its settings.

    Parameters
    ----------
    method
        ``direct`` (SuperLU), ``amg`` (CG for a symmetric matrix, GMRES otherwise, with a
        smoothed-aggregation preconditioner built on the symmetric part) or ``auto``
        (the size rule :data:`DIRECT_MAX_DOFS`).
    near_nullspace
        ``(n, 6)`` rigid-body modes of the matrix's unknowns, for smoothed aggregation.
    rtol
        Relative residual tolerance of the Krylov methods.
    maxiter
        Krylov iterations at most.
    direct_max_dofs
        The size rule of ``auto``.

    Attributes
    ----------
    stats
        ``solves`` and ``krylov_iterations`` so far.
    name
        The solver that produced the last solution (``direct``, ``cg+amg``, ``gmres+amg``).
    """

    method: str = "auto"
    near_nullspace: np.ndarray | None = None
    rtol: float = 1e-10
    maxiter: int = 2000
    direct_max_dofs: int = DIRECT_MAX_DOFS
    stats: dict = field(default_factory=lambda: {"solves": 0, "krylov_iterations": 0})
    name: str = "none"

    def __post_init__(self):
        if self.method not in ("auto", "direct", "amg"):
            raise InputError(f"linear_solver {self.method!r} is not one of auto, direct, amg")

    def kind(self, n_dofs: int) -> str:
        """``direct`` or ``amg``: what ``method`` means for ``n_dofs`` unknowns.

        Parameters
        ----------
        n_dofs
            Number of unknowns.

        Returns
        -------
        str
            ``direct`` or ``amg``.
        """
        if self.method == "auto":
            return "direct" if n_dofs <= self.direct_max_dofs else "amg"
        return self.method

    def factorize(
        self,
        A: sp.spmatrix,
        free: np.ndarray | None = None,
        symmetric: bool | None = None,
        where: str = "",
        reuse: Factorization | None = None,
    ) -> Factorization:
        """Prepare ``A`` for solves (LU factor or AMG hierarchy).

        Parameters
        ----------
        A
            The matrix: the free-DOF block, or the full matrix when ``free`` is given.
        free
            Boolean mask of the free DOFs of a full matrix (``None``: all unknowns free).
        symmetric
            Whether ``A`` is symmetric (``None``: test with :func:`is_symmetric`).
        where
            Prefix of error messages (e.g. ``"step 2 iteration 3: "``).
        reuse
            A factorisation of a nearby matrix (the last Newton tangent) whose AMG
            hierarchy may precondition ``A`` (:class:`Factorization`); not for ``direct``.

        Returns
        -------
        Factorization
            Call its ``solve(b)``.
        """
        return Factorization(self, A, free, symmetric, where, reuse)

    def solve(
        self,
        K: sp.spmatrix,
        b: np.ndarray,
        free: np.ndarray | None = None,
        symmetric: bool | None = None,
        where: str = "",
    ) -> np.ndarray:
        """Solve ``K x = b`` once (``x = 0`` on the constrained DOFs when ``free`` is given).

        Parameters
        ----------
        K, free, symmetric, where
            As in :meth:`factorize`.
        b
            Right-hand side (its constrained entries are ignored).

        Returns
        -------
        numpy.ndarray
            The solution.

        Raises
        ------
        SolverError
            Non-finite right-hand side, or no solution within :data:`RESIDUAL_ACCEPT`.
        """
        return self.factorize(K, free, symmetric, where).solve(b)


class Factorization:
    """A matrix prepared by :meth:`LinearSolver.factorize`; ``solve(b)`` for each ``b``.

    Parameters
    ----------
    solver
        The settings (its ``stats`` and ``name`` are updated).
    A, free, symmetric, where, reuse
        As in :meth:`LinearSolver.factorize`.

    Notes
    -----
    With ``reuse`` the previous hierarchy (costly to build; successive Newton tangents
    differ little) preconditions CG on the *new* matrix, whose solution it still is to
    ``rtol``. It is rebuilt when a solve with it fails or its iterations exceed
    :data:`REUSE_GROWTH` times (+ 2) those of the first solve after it was built.
    """

    def __init__(self, solver: LinearSolver, A, free, symmetric, where: str, reuse=None):
        self.solver = solver
        self.free = None if free is None else np.asarray(free, dtype=bool)
        self.A = eliminate(A, self.free) if self.free is not None else sp.csr_matrix(A)
        self.where = where
        n = self.A.shape[0]
        self.symmetric = is_symmetric(self.A) if symmetric is None else bool(symmetric)
        # CG needs an exactly symmetric matrix: a tangent symmetric to finite-difference
        # noise is symmetrised for the Krylov solve (and checked against that)
        self._K = self.A if symmetric is not None else (0.5 * (self.A + self.A.T)).tocsr()
        if not self.symmetric:
            self._K = self.A
        self.kind = solver.kind(n)
        self.name = "none"
        self._lu = None
        self._ml = None
        self._coarse = "splu"  # pinv's dense SVD is slow with oversubscribed BLAS threads
        self._fresh_iterations = self._last_iterations = None  # Krylov its (fresh, last)
        self._reused = reuse is not None and self.kind == "amg" and reuse._reusable(self)
        if self._reused:
            self._ml, self._coarse = reuse._ml, reuse._coarse
            self._fresh_iterations = reuse._fresh_iterations
        if self.kind == "direct":
            with warnings.catch_warnings():
                # a rank-deficient factor is judged by the residual of its solutions (a
                # singular but consistent system, e.g. a mechanism the load does not move,
                # is solvable)
                warnings.simplefilter("ignore", spla.MatrixRankWarning)
                try:
                    # minimum degree on A^T + A: ~4x less fill than COLAMD on these matrices
                    self._lu = spla.splu(self.A.tocsc(), permc_spec="MMD_AT_PLUS_A")
                except RuntimeError:
                    self._lu = None  # exactly singular factor: try AMG, which reports it

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Solve ``A x = b``.

        Parameters
        ----------
        b
            Right-hand side.

        Returns
        -------
        numpy.ndarray
            The solution (zero on the constrained DOFs).

        Raises
        ------
        SolverError
            Non-finite right-hand side, or no solution within :data:`RESIDUAL_ACCEPT`.
        """
        b = np.asarray(b, dtype=float)
        if self.free is not None:
            b = np.where(self.free, b, 0.0)
        if not np.all(np.isfinite(b)):
            raise SolverError(f"{self.where}non-finite right-hand side")
        self.solver.stats["solves"] += 1
        bnorm = float(np.linalg.norm(b))
        if bnorm == 0:
            return np.zeros(self.A.shape[0])
        A, x = self.A, None
        if self._lu is not None:
            x = self._lu.solve(b)
            self.name = "direct"
        if x is None or not self._accepted(A, x, b, bnorm):
            A = self._K
            try:
                x = self._krylov(b)
                if self._reused and not self._accepted(A, x, b, bnorm):
                    self._ml, self._reused = None, False  # stale hierarchy: rebuild once
                    x = self._krylov(b)
            except RuntimeError:
                # exactly singular coarsest level (a mechanism): its pseudo-inverse lets CG
                # solve a singular but consistent system; an inconsistent one is refused
                self._ml, self._coarse = None, "pinv"
                try:
                    x = self._krylov(b)
                except (RuntimeError, ValueError, np.linalg.LinAlgError):
                    x = np.full(b.shape, np.nan)
        self.solver.name = self.name
        if self.free is not None:
            x[~self.free] = 0.0
        if not self._accepted(A, x, b, bnorm):
            r = np.linalg.norm(A @ x - b) / bnorm if np.all(np.isfinite(x)) else np.inf
            raise SolverError(
                f"{self.where}singular stiffness: linear solve failed with relative residual "
                f"{r:.2e} (the tangent has a zero-energy mode: a mechanism, a limit point, or "
                "a missing boundary condition)"
            )
        return x

    @staticmethod
    def _accepted(A, x: np.ndarray, b: np.ndarray, bnorm: float) -> bool:
        if not np.all(np.isfinite(x)):
            return False
        return bool(np.linalg.norm(A @ x - b) <= RESIDUAL_ACCEPT * bnorm)

    def _reusable(self, other: Factorization) -> bool:
        """Whether this hierarchy may precondition ``other`` (same form, not stale)."""
        fresh, last = self._fresh_iterations or 0, self._last_iterations or 0
        same = self.A.shape == other.A.shape and self.symmetric == other.symmetric
        return self._ml is not None and same and last <= REUSE_GROWTH * fresh + 2

    def _hierarchy(self):
        if self._ml is None:
            self._fresh_iterations = None
            import pyamg

            A = self.A
            S = self._K if self.symmetric else (0.5 * (A + A.T)).tocsr()
            n = A.shape[0]
            if self.free is not None and n % 3 == 0:
                S = S.tobsr(blocksize=(3, 3))
            B = self.solver.near_nullspace
            self._ml = pyamg.smoothed_aggregation_solver(
                S,
                B=B if B is not None and B.shape[0] == n else None,
                symmetry="hermitian",
                strength=("symmetric", {"theta": 0.0}),
                smooth="jacobi",
                max_coarse=500,
                coarse_solver=self._coarse,
            )
        return self._ml

    def _krylov(self, b: np.ndarray) -> np.ndarray:
        M = self._hierarchy().aspreconditioner(cycle="V")
        count = [0]

        def cb(_):
            count[0] += 1

        s = self.solver
        if self.symmetric:
            x, _ = spla.cg(self._K, b, rtol=s.rtol, atol=0.0, maxiter=s.maxiter, M=M, callback=cb)
            self.name = "cg+amg"
        else:
            x, _ = spla.gmres(
                self.A, b, rtol=s.rtol, atol=0.0, restart=60, maxiter=s.maxiter, M=M,
                callback=cb, callback_type="pr_norm",
            )  # fmt: skip
            self.name = "gmres+amg"
        s.stats["krylov_iterations"] += count[0]
        self._last_iterations = count[0]
        self._fresh_iterations = self._fresh_iterations or count[0]
        return x


def solve_linear(
    A: sp.spmatrix,
    b: np.ndarray,
    method: LinearSolverKind = "auto",
    near_nullspace: np.ndarray | None = None,
    rtol: float = 1e-10,
) -> tuple[np.ndarray, str]:
    """Solve ``A x = b`` once with a :class:`LinearSolver`.

    Parameters
    ----------
    A
        Square sparse matrix (all unknowns free).
    b
        Right-hand side.
    method, near_nullspace, rtol
        As in :class:`LinearSolver`.

    Returns
    -------
    x, name
        The solution and the solver that produced it.
    """
    solver = LinearSolver(method, near_nullspace, rtol)
    x = solver.solve(A, b)
    return x, solver.name
