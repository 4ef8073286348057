"""The one linear solver of both models: a sparse direct factorisation (MKL PARDISO, or
SuperLU without it: :mod:`.direct`), or CG / GMRES preconditioned by pyamg smoothed
aggregation with the rigid-body modes as near-nullspace.

A :class:`LinearSolver` holds the choice (``auto``, ``direct``, ``amg``), the settings and
the direct solver's per-pattern state (so the matrices of one solve reuse the symbolic
analysis); :meth:`LinearSolver.factorize` prepares one matrix for several right-hand sides,
:meth:`LinearSolver.solve` solves once. With ``free`` given the matrix is the full one: the
direct solver factorises its free block, AMG its symmetric elimination (constrained rows
and columns zeroed, unit diagonal: the 3x3 blocks smoothed aggregation works best with).

Size rule (``auto``): direct up to :data:`DIRECT_MAX_DOFS` unknowns, AMG above (SuperLU's
crossover with AMG-CG on a clamped box's P1 and P2 stiffness is at 4,000–6,000 DOFs,
PARDISO's at 25,000 (P1) and 35,000 (P2); on the slender P2 tangents of the bundled scenes
PARDISO is 15–35 times faster than AMG-CG, and exact, which suits small ill-conditioned
tests). A saddle point (``saddle_point``: mixed u–p, indefinite) is factorised unless that
takes more than :data:`DIRECT_MAX_FLOPS` (PARDISO's analysis counts them; about 55,000 DOFs
of a P2/P1 tangent) and the problem gave the Schur complement's diagonal
(:attr:`LinearSolver.schur`): then GMRES with the block preconditioner of :mod:`.saddle`
solves it. The organ's P2/P1 tangent at 30k tets (136,837 DOFs) takes 3.4e11 flops, 60 s
and 1.4 GB to factorise on one core.

Memory (:mod:`.memory`): a factorisation whose memory (PARDISO's analysis, or a measured
law) does not fit :func:`~.memory.memory_limit` beside what the process holds is not
started; the solve is iterative instead (AMG-CG, or the block preconditioner), and one that
does not fit either way raises :class:`~.memory.MemoryLimitExceeded` before it starts. A
solve may ask for a looser tolerance (``rtol`` of :meth:`Factorization.solve`: the forcing
term of an inexact Newton); a factorisation ignores it.

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

from . import memory as _memory
from .amg import hierarchy, krylov
from .direct import DirectFactor, DirectSolver, FactorRefused, flops_law
from .elimination import eliminate
from .limits import interruptible
from .memory import MemoryLimitExceeded, factor_bytes_law, memory_limit, resident_bytes
from .saddle import BlockPreconditioner

__all__ = [
    "DIRECT_MAX_DOFS", "DIRECT_MAX_FLOPS", "RESIDUAL_ACCEPT", "REUSE_GROWTH",
    "SUPERLU_MAX_DOFS", "SYMMETRY_TOL",
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
#: ``auto`` solves a saddle point iteratively when factorising it takes more flops (one
#: core does about 5e9 per second on these factors: about 10 s).
DIRECT_MAX_FLOPS = 5e10
#: The measured laws (:func:`~.direct.flops_law`, :func:`~.memory.factor_bytes_law`) skip
#: the analysis of a factorisation they predict this many times over a limit.
LAW_MARGIN = 3.0
#: Bytes per stored entry of the free block's copies a factorisation makes beside its factor.
COPY_BYTES_PER_NNZ = 24.0


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
        The matrices are saddle points (indefinite): factorised, or (with :attr:`schur`)
        solved by block-preconditioned GMRES when a factorisation is too large.
    schur
        Of a saddle point: the positive diagonal ``S_hat`` of the Schur complement's
        approximation (one entry per trailing unknown, :mod:`.saddle`), or ``None`` (no
        iterative solve).
    direct_max_flops
        ``auto``: a saddle point whose factorisation takes more flops is solved iteratively.

    Attributes
    ----------
    stats
        ``solves``, ``krylov_iterations``, ``factorizations`` and ``analyses`` (symbolic
        analyses of the direct solver) so far.
    name
        The solver that produced the last solution (``direct``, ``cg+amg``, ``gmres+amg``,
        ``gmres+block``).
    reason
        Why the last direct solve became iterative ("" when none did).
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
    schur: np.ndarray | None = field(default=None, repr=False)
    direct_max_flops: float = DIRECT_MAX_FLOPS
    reason: str = ""
    _iterative: tuple | None = field(default=None, repr=False)  # (shape, nnz) refused

    @property
    def iterative(self) -> str | None:
        """The iterative kind for these matrices (``amg``, ``block``), ``None`` if none."""
        if not self.saddle_point:
            return "amg"
        return "block" if self.schur is not None else None

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
            ``direct``, ``amg`` or ``block`` (a saddle point, :mod:`.saddle`).
        """
        if self.saddle_point:
            if self.iterative is None or self.method == "direct":
                return "direct"
            if self.method == "amg":
                return "block"
            laws = flops_law(n_dofs) > LAW_MARGIN * self.direct_max_flops
            return "block" if laws else "direct"
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
    A direct factorisation is admitted (:meth:`_admit`) when its memory fits and, for an
    ``auto`` saddle point, its flops are at most ``direct_max_flops``; else the matrix is
    solved iteratively. With ``reuse`` the previous hierarchy (costly to build; successive
    Newton tangents differ little) preconditions CG (or the block preconditioner) on the
    *new* matrix, whose solution it still is to ``rtol``. It is rebuilt when a solve with
    it fails or its iterations per decade of residual reduction exceed
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
        self._pre: BlockPreconditioner | None = None
        self._nnz = A.nnz
        if self.kind == "direct" and solver._iterative == (A.shape, A.nnz):
            self.kind = solver.iterative or "direct"  # this pattern was refused before
        if self.kind == "direct":
            self._factor(A)
        if self.kind != "direct":
            self._check_iterative()
        self._reused = (
            isinstance(reuse, Factorization) and self.kind != "direct" and reuse._reusable(self)
        )
        if self._reused:
            self._ml, self._coarse = reuse._ml, reuse._coarse
            self._fresh_iterations = reuse._fresh_iterations

    def _factor(self, A) -> None:
        solver, where = self.solver, self.where
        before = solver.direct.analyses
        n = self.n if self.free is None else int(self.free.sum())
        try:
            if self.solver.iterative is not None:
                self._admit(factor_bytes_law(n) / LAW_MARGIN, flops_law(n) / LAW_MARGIN)
            self._lu = interruptible(solver.direct.factor, A, self.free, self._admit)
        except FactorRefused as exc:
            if solver.iterative is None:
                raise MemoryLimitExceeded(
                    f"{where}{exc}, and this matrix has no iterative solver"
                ) from None
            solver.reason = str(exc)
            solver._iterative = (A.shape, A.nnz)
            self.kind = solver.iterative
            return
        except RuntimeError as exc:  # an exactly singular factor: AMG reports it
            if solver.saddle_point:
                raise SolverError(f"{where}singular saddle-point system ({exc})") from None
            self._lu = None
        solver.stats["factorizations"] += 1
        solver.stats["analyses"] += solver.direct.analyses - before

    def _admit(self, nbytes: float, flops: float) -> None:
        """Raise :class:`FactorRefused` for a factorisation too large (class Notes)."""
        need = resident_bytes() + nbytes + COPY_BYTES_PER_NNZ * self._nnz
        limit = memory_limit()
        if need > limit:
            raise FactorRefused(
                f"the direct factorisation needs {_memory.gb(nbytes)} (the process holds "
                f"{_memory.gb(need - nbytes)}), over the memory limit of {_memory.gb(limit)}"
            )
        s = self.solver
        if s.saddle_point and s.method == "auto" and flops > s.direct_max_flops:
            raise FactorRefused(
                f"the direct factorisation takes {flops:.2g} flops, over "
                f"{s.direct_max_flops:.2g} (direct_max_flops)"
            )

    def _check_iterative(self) -> None:
        """Raise :class:`MemoryLimitExceeded` when the iterative solve cannot fit either."""
        need = resident_bytes() + _memory.iterative_bytes(self.n, self._nnz)
        limit = memory_limit()
        if need > limit:
            why = f"; {self.solver.reason}" if self.solver.reason else ""
            raise MemoryLimitExceeded(
                f"{self.where}the iterative solve of {self.n} unknowns needs about "
                f"{_memory.gb(need)}, over the memory limit of {_memory.gb(limit)}{why}"
            )

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

    def solve(self, b: np.ndarray, rtol: float | None = None) -> np.ndarray:
        """Solve ``A x = b``.

        Parameters
        ----------
        b
            Right-hand side.
        rtol
            Relative residual an iterative solve may stop at (at least the solver's
            ``rtol``; ``None``: that). The accepted residual is the larger of it and
            :data:`RESIDUAL_ACCEPT`.

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
        tol = self.solver.rtol if rtol is None else max(rtol, self.solver.rtol)
        if self.kind == "block":
            return self._saddle(b, bnorm, tol)
        if self.solver.saddle_point:
            raise SolverError(
                f"{self.where}singular saddle-point system: linear solve failed with relative "
                f"residual {self._residual:.2e}"
            )
        A = self._K
        try:
            x = self._krylov(b, tol)
            if self._reused and not self._accepted(A, x, b, bnorm, tol):
                self._ml, self._reused = None, False  # stale hierarchy: rebuild once
                x = self._krylov(b, tol)
        except RuntimeError:
            # exactly singular coarsest level (a mechanism): its pseudo-inverse lets CG
            # solve a singular but consistent system; an inconsistent one is refused
            self._ml, self._coarse = None, "pinv"
            try:
                x = self._krylov(b, tol)
            except (RuntimeError, ValueError, np.linalg.LinAlgError):
                x = np.full(b.shape, np.nan)
        self.solver.name = self.name
        if self.free is not None:
            x[~self.free] = 0.0
        if not self._accepted(A, x, b, bnorm, tol):
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
    def _accepted(A, x: np.ndarray, b: np.ndarray, bnorm: float, rtol: float = 0.0) -> bool:
        if not np.all(np.isfinite(x)):
            return False
        return bool(np.linalg.norm(A @ x - b) <= max(RESIDUAL_ACCEPT, 1.5 * rtol) * bnorm)

    def _reusable(self, other: Factorization) -> bool:
        """Whether this hierarchy may precondition ``other`` (same form, not stale)."""
        fresh, last = self._fresh_iterations or 0, self._last_iterations or 0
        same = self.n == other.n and self.kind == other.kind
        if self.kind == "amg":  # the symmetry this hierarchy was used with
            same = same and self.__dict__.get("symmetric") == other.symmetric
        return self._ml is not None and same and last <= REUSE_GROWTH * fresh + 2

    def shed(self) -> None:
        """Free the matrices and the factor, keeping the AMG hierarchy for ``reuse``
        (before the next tangent is assembled: the two need not be held at once)."""
        self._full, self._lu, self._pre = None, None, None
        for name in ("A", "_K"):
            self.__dict__.pop(name, None)

    def _count(self, its: int, rtol: float) -> None:
        """Record ``its`` Krylov iterations (per decade of residual reduction, for reuse)."""
        self.solver.stats["krylov_iterations"] += its
        rate = int(np.ceil(its / max(1.0, -np.log10(max(rtol, 1e-16)))))
        self._last_iterations = rate
        self._fresh_iterations = self._fresh_iterations or rate

    def _saddle(self, b: np.ndarray, bnorm: float, rtol: float) -> np.ndarray:
        """Block-preconditioned GMRES on the saddle point (:mod:`.saddle`)."""
        s, A = self.solver, self.A
        nu = self.n - (0 if s.schur is None else len(s.schur))
        for attempt in (0, 1):
            if self._pre is None:
                ml = self._ml if self._reused else None
                if ml is None:
                    self._fresh_iterations = None
                nns = s.near_nullspace
                nns = nns[:nu] if nns is not None and nns.shape[0] >= nu else None
                self._pre = BlockPreconditioner(A, nu, s.schur, nns, self.free is not None, ml)
                self._ml = self._pre.ml
            x, its = self._pre.gmres(A, b, rtol, s.maxiter)
            self._count(its, rtol)
            if self.free is not None:
                x[~self.free] = 0.0
            if self._accepted(A, x, b, bnorm, rtol) or not self._reused or attempt:
                break
            self._pre, self._ml, self._reused = None, None, False  # stale: rebuild once
        self.name = s.name = "gmres+block"
        if not self._accepted(A, x, b, bnorm, rtol):
            r = np.linalg.norm(A @ x - b) / bnorm if np.all(np.isfinite(x)) else np.inf
            raise SolverError(
                f"{self.where}block-preconditioned GMRES failed with relative residual "
                f"{r:.2e} (a singular or unstable saddle point)"
            )
        return x

    def _krylov(self, b: np.ndarray, rtol: float | None = None) -> np.ndarray:
        if self._ml is None:
            self._fresh_iterations = None
            S = self._K if self.symmetric else (0.5 * (self.A + self.A.T)).tocsr()
            blocks = self.free is not None
            self._ml = hierarchy(S, blocks, self.solver.near_nullspace, self._coarse)
        s = self.solver
        A = self._K if self.symmetric else self.A
        tol = s.rtol if rtol is None else rtol
        x, its, self.name = krylov(A, b, self._ml, self.symmetric, tol, s.maxiter)
        self._count(its, tol)
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
