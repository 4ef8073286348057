"""The one linear solver of both models: a sparse direct factorisation (MKL PARDISO, or
SuperLU without it: :mod:`.direct`), or CG / GMRES preconditioned by pyamg smoothed
aggregation with the rigid-body modes as near-nullspace.

A :class:`LinearSolver` holds the choice (``auto``, ``direct``, ``amg``), the settings and
the direct solver's per-pattern state (so the matrices of one solve reuse the symbolic
analysis); :meth:`LinearSolver.factorize` prepares one matrix for several right-hand sides,
:meth:`LinearSolver.solve` solves once. With ``free`` given the matrix is the full one: the
direct solver factorises its free block, AMG its symmetric elimination (constrained rows
and columns zeroed, unit diagonal: the 3x3 blocks smoothed aggregation works best with).

Size rule (``auto``): direct up to :data:`DIRECT_MAX_DOFS` unknowns, AMG above; a saddle
point (``saddle_point``: mixed u–p, indefinite, which smoothed aggregation cannot
precondition) is always factorised. With SuperLU the crossover with AMG-CG on the P1 and P2
stiffness of a clamped box is at about 4,000–6,000 DOFs, the same in DOFs for both orders
(not in nnz), and SuperLU's cost grows superlinearly (fill-in) while AMG's grows about
linearly. PARDISO moves the crossover on that box to about 25,000 DOFs (P1) and 35,000
(P2); on the slender P2 tangents of the bundled scenes (14k–19k DOFs) it is 15–35 times
faster than AMG-CG, whose iterations grow with the slenderness. A factorisation is also
exact, which suits the small, ill-conditioned problems (slender beams, near-incompressible
P1) tests use.

A solution is accepted when its relative residual ``|A x - b| / |b|`` is at most
:data:`RESIDUAL_ACCEPT`; otherwise the solve raises :class:`~springfem.errors.SolverError`
(a singular or ill-conditioned matrix). A failed factorisation of a definite matrix falls
back to AMG. A factorisation runs through :func:`~springfem.mechanics.limits.interruptible`
(a time cap or Ctrl-C stops a solve inside it).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> A = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(4, 4))
>>> x, name = solve_linear(A, np.ones(4))
>>> np.round(x, 12).tolist(), name
([2.0, 3.0, 3.0, 2.0], 'direct')
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Literal

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from springfem.errors import InputError, SolverError

from .amg import hierarchy, krylov
from .direct import DirectFactor, DirectSolver
from .limits import interruptible

__all__ = [
    "DIRECT_MAX_DOFS", "RESIDUAL_ACCEPT", "REUSE_GROWTH", "SUPERLU_MAX_DOFS", "SYMMETRY_TOL",
    "Factorization",
    "LinearSolver", "LinearSolverKind", "eliminate", "is_symmetric", "solve_linear",
]  # fmt: skip

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


def eliminate(K: sp.spmatrix, free: np.ndarray) -> sp.csr_matrix:
    """``P K P + (I - P)`` with ``P = diag(free)``: constrained DOFs decoupled, unit diagonal.

    Parameters
    ----------
    K
        Square matrix.
    free
        Boolean mask of the free DOFs.

    Returns
    -------
    scipy.sparse.csr_matrix
        The eliminated matrix.

    Examples
    --------
    >>> K = sp.csr_matrix(np.array([[2.0, -1.0], [-1.0, 2.0]]))
    >>> A = eliminate(K, np.array([True, False]))
    >>> A.toarray().tolist(), is_symmetric(A)
    ([[2.0, 0.0], [0.0, 1.0]], True)
    """
    d = sp.diags(free.astype(float))
    A = (d @ sp.csr_matrix(K) @ d + sp.diags((~free).astype(float))).tocsr()
    A.eliminate_zeros()
    return A


LinearSolverKind = Literal["auto", "direct", "amg"]

#: ``auto`` factorises up to this many unknowns and uses AMG above (see the module
#: docstring for the measurement); SuperLU's crossover is lower (:data:`SUPERLU_MAX_DOFS`).
DIRECT_MAX_DOFS = 20_000
#: The size rule of ``auto`` when the direct solver is SuperLU (no PARDISO installed).
SUPERLU_MAX_DOFS = 5_000
#: Largest accepted relative residual ``|A x - b| / |b|`` of a solution.
RESIDUAL_ACCEPT = 1e-6
#: The counters of :attr:`LinearSolver.stats`.
STATS = ("solves", "krylov_iterations", "factorizations", "analyses")
#: A reused AMG hierarchy is rebuilt past this growth of its Krylov iterations.
REUSE_GROWTH = 2.0


@dataclass
class LinearSolver:
    """The choice of linear solver and its settings.

    Parameters
    ----------
    method
        ``direct`` (:mod:`.direct`), ``amg`` (:mod:`.amg`) or ``auto`` (the size rule).
    near_nullspace
        ``(n, 6)`` rigid-body modes of the matrix's unknowns, for smoothed aggregation.
    rtol
        Relative residual tolerance of the Krylov methods.
    maxiter
        Krylov iterations at most.
    direct_max_dofs
        The size rule of ``auto`` (default: :data:`DIRECT_MAX_DOFS` with PARDISO,
        :data:`SUPERLU_MAX_DOFS` with SuperLU).
    saddle_point
        The matrices are saddle points (indefinite): always factorised.

    Attributes
    ----------
    stats
        ``solves``, ``krylov_iterations``, ``factorizations`` and ``analyses`` (symbolic
        analyses of the direct solver) so far.
    name
        The solver that produced the last solution (``direct``, ``cg+amg``, ``gmres+amg``).
    direct
        The :class:`~springfem.mechanics.direct.DirectSolver` (its backend and the analysis
        it keeps per pattern).
    """

    method: str = "auto"
    near_nullspace: np.ndarray | None = None
    rtol: float = 1e-10
    maxiter: int = 2000
    direct_max_dofs: int | None = None
    saddle_point: bool = False
    stats: dict = field(default_factory=lambda: dict.fromkeys(STATS, 0))
    name: str = "none"
    direct: DirectSolver = field(default_factory=DirectSolver, repr=False)

    def __post_init__(self):
        if self.method not in ("auto", "direct", "amg"):
            raise InputError(f"linear_solver {self.method!r} is not one of auto, direct, amg")
        if self.direct_max_dofs is None:
            pardiso = self.direct.backend == "pardiso"
            self.direct_max_dofs = DIRECT_MAX_DOFS if pardiso else SUPERLU_MAX_DOFS

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
        if self.saddle_point:
            return "direct"
        if self.method == "auto":
            limit = DIRECT_MAX_DOFS if self.direct_max_dofs is None else self.direct_max_dofs
            return "direct" if n_dofs <= limit else "amg"
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
        self._full = A
        self._given_symmetric = symmetric
        self.where = where
        self.n = A.shape[0]
        self.kind = solver.kind(self.n if self.free is None else int(self.free.sum()))
        self.name = "none"
        self._lu: DirectFactor | None = None
        self._residual = np.inf  # of the last direct solution that was not accepted
        self._ml = None
        self._coarse = "splu"  # pinv's dense SVD is slow with oversubscribed BLAS threads
        self._fresh_iterations: int | None = None  # Krylov iterations: of the fresh hierarchy
        self._last_iterations: int | None = None  # and of the last solve
        self._reused = reuse is not None and self.kind == "amg" and reuse._reusable(self)
        if self._reused:
            self._ml, self._coarse = reuse._ml, reuse._coarse
            self._fresh_iterations = reuse._fresh_iterations
        if self.kind == "direct":
            before = solver.direct.analyses
            try:
                self._lu = interruptible(solver.direct.factor, A, self.free)
            except RuntimeError as exc:  # an exactly singular factor: AMG reports it
                if solver.saddle_point:
                    raise SolverError(f"{where}singular saddle-point system ({exc})") from None
                self._lu = None
            solver.stats["factorizations"] += 1
            solver.stats["analyses"] += solver.direct.analyses - before

    @cached_property
    def A(self) -> sp.csr_matrix:
        """The matrix the Krylov methods solve (the symmetric elimination with ``free``)."""
        A = self._full
        return eliminate(A, self.free) if self.free is not None else sp.csr_matrix(A)

    @cached_property
    def symmetric(self) -> bool:
        """Whether :attr:`A` is symmetric (as given, or by :func:`is_symmetric`)."""
        given = self._given_symmetric
        return is_symmetric(self.A) if given is None else bool(given)

    @cached_property
    def _K(self) -> sp.csr_matrix:
        # CG needs an exactly symmetric matrix: a tangent symmetric to finite-difference
        # noise is symmetrised for the Krylov solve (and checked against that)
        if not self.symmetric or self._given_symmetric is not None:
            return self.A
        return (0.5 * (self.A + self.A.T)).tocsr()

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
            return np.zeros(self.n)
        if self._lu is not None:
            x = self._direct(b, bnorm)
            if x is not None:
                return x
        if self.solver.saddle_point:
            raise SolverError(
                f"{self.where}singular saddle-point system: linear solve failed with relative "
                f"residual {self._residual:.2e}"
            )
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

    def _direct(self, b: np.ndarray, bnorm: float) -> np.ndarray | None:
        """The direct solution, or ``None`` when its residual is not accepted."""
        lu, free = self._lu, self.free
        assert lu is not None  # a direct factor was made
        bf = b if free is None else b[free]
        xf = lu.solve(bf)
        if not self._accepted(lu.block, xf, bf, bnorm):
            finite = np.all(np.isfinite(xf))
            self._residual = float(np.linalg.norm(lu.block @ xf - bf) / bnorm) if finite else np.inf
            return None
        self.name = self.solver.name = "direct"
        if free is None:
            return xf
        x = np.zeros(self.n)
        x[free] = xf
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

    def _krylov(self, b: np.ndarray) -> np.ndarray:
        if self._ml is None:
            self._fresh_iterations = None
            S = self._K if self.symmetric else (0.5 * (self.A + self.A.T)).tocsr()
            blocks = self.free is not None
            self._ml = hierarchy(S, blocks, self.solver.near_nullspace, self._coarse)
        s = self.solver
        A = self._K if self.symmetric else self.A
        x, its, self.name = krylov(A, b, self._ml, self.symmetric, s.rtol, s.maxiter)
        s.stats["krylov_iterations"] += its
        self._last_iterations = its
        self._fresh_iterations = self._fresh_iterations or its
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
    A, b
        Square sparse matrix (all unknowns free) and right-hand side.
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
