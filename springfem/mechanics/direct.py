"""Direct factorisation of the free-DOF block for the one linear solver (:mod:`.linsolve`).

:class:`DirectSolver` keeps, per sparsity pattern of the full matrix, the index maps from
its CSR values to the free block (whole, and upper triangle with every diagonal entry, as
symmetric PARDISO needs) and the PARDISO handles whose symbolic analysis (ordering,
elimination tree) it reuses for every later matrix of that pattern: Newton tangents of one
solve, across iterations and load steps, differ only in their values. A new pattern
(entries that cancel exactly, a new set of free DOFs) is analysed anew.

The factorisation (:meth:`DirectSolver.factor`) follows one rule:

- MKL PARDISO (:mod:`.pardiso`) when it is installed, else SuperLU (scipy);
- a symmetric or nearly symmetric matrix (relative asymmetry ``max |A - A^T| / max |A|`` at
  most :data:`NEAR_SYMMETRIC`: the tangents of follower pressure on a surface whose rim is
  not fixed) is factorised as its symmetric part ``(A + A^T) / 2`` by the symmetric
  indefinite LDL^T (one triangle: half the work of LU), and each solve is refined against
  ``A`` itself until ``|A x - b| <= REFINE_TOL |b|`` (at most :data:`REFINE_STEPS`
  refinements; the error shrinks by about the relative asymmetry per step). A matrix whose
  refinement does not converge is factorised by LU (PARDISO type 11), and so are later
  matrices of its pattern;
- an unsymmetric matrix: LU (PARDISO type 11, or SuperLU with minimum degree on
  ``A^T + A``, or COLAMD for a saddle point: see below).

Why (the tangents of the bundled scenes, one thread, CPU time, the same residuals of
1e-14–1e-10): on the symmetric ones (P2 displacement of the cantilever and the sag, 2k–20k
DOFs; the ventricle's Taylor–Hood saddle points, 4k–14k DOFs) PARDISO's LDL^T factorises
6–11 times faster than SuperLU and twice as fast as PARDISO's own LU; reusing the analysis
takes the ordering (more than the numeric factorisation itself on the saddle points) out of
every later factorisation. CHOLMOD (SPD only) was 2–10 times and MUMPS 1.5–2 times slower
than PARDISO's LDL^T. On the unsymmetric saddle point of Land's beam PARDISO's LU is a
little faster than SuperLU with COLAMD, and refining a symmetric-part factor does not
converge (hence the LU fallback). SuperLU orders a matrix with zero diagonal entries (a
saddle point) by COLAMD, others by minimum degree on ``A^T + A``: each has 3–40 times less
fill than the other ordering on its kind of matrix.

Before a numeric factorisation, ``admit(bytes, flops)`` (given by :mod:`.linsolve`) sees
what it will cost: PARDISO's analysis reports both (:class:`~.pardiso.Pardiso`), for
SuperLU :mod:`.memory`'s measured laws stand in. A factorisation it refuses, or one PARDISO
runs out of memory for, raises :class:`FactorRefused` (the caller solves iteratively).

A PARDISO factor lives in its pattern's handle: it solves until the next factorisation of
that pattern (a later solve with it raises ``RuntimeError``).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> A = sp.csr_matrix(np.array([[4.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 2.0]]))
>>> free = np.array([True, True, False])
>>> solver = DirectSolver()
>>> f = solver.factor(A, free)
>>> x = f.solve(np.array([5.0, 4.0]))  # the free block [[4, 1], [1, 3]]
>>> np.round(x, 12).tolist(), f.symmetric
([1.0, 1.0], True)
>>> solver.factor(2.0 * A, free) is not None and solver.analyses  # same pattern: reused
1
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from . import pardiso as _pardiso

__all__ = [
    "NEAR_SYMMETRIC", "REFINE_STEPS", "REFINE_TOL", "DirectFactor", "DirectSolver",
    "FactorRefused", "flops_law",
]  # fmt: skip

#: Largest relative asymmetry factorised as the symmetric part (with refinement).
NEAR_SYMMETRIC = 1e-2
#: Relative residual a refined solve reaches (the solver's own accuracy is ~1e-14).
REFINE_TOL = 1e-11
#: Refinements at most before the matrix is factorised by LU.
REFINE_STEPS = 4
#: The factorisation's flops at :data:`FLOPS_DOFS` unknowns and the exponent of ``n``
#: (PARDISO's analysis of the organ's P2/P1 tangents: 7.25e8 at 7,444 DOFs, 9.14e9 at
#: 24,651, 3.4e11 at 136,837).
FLOPS_LAW, FLOPS_DOFS, FLOPS_EXPONENT = 9.14e9, 24_651, 2.1


def flops_law(n: int) -> float:
    """The measured law of a sparse LDL^T factorisation's flops for ``n`` unknowns.

    Examples
    --------
    >>> flops_law(24_651) / 1e9
    9.14
    """
    return FLOPS_LAW * (max(n, 1) / FLOPS_DOFS) ** FLOPS_EXPONENT


class FactorRefused(RuntimeError):
    """A factorisation not started (or out of memory): too large for the limits.

    Parameters
    ----------
    message
        Why (bytes and flops against the limits).
    """


class FreeBlock:
    """Index maps from a CSR matrix's values to its free block, for one pattern.

    Parameters
    ----------
    K
        Square CSR matrix in canonical form (sorted indices, no duplicates).
    free
        Boolean mask of the free DOFs (``None``: all).
    """

    def __init__(self, K: sp.csr_matrix, free: np.ndarray | None):
        nnz = K.nnz
        self.shape, self.nnz = K.shape, nnz
        self.indptr, self.indices = K.indptr.copy(), K.indices.copy()
        self.free = None if free is None else free.copy()
        # value j + 1 marks the full matrix's j-th stored entry (0 cannot be told from a
        # dropped entry); nnz + 1 marks a diagonal entry the block lacks (value zero)
        P = sp.csr_matrix((np.arange(1.0, nnz + 1.0), K.indices, K.indptr), shape=K.shape)
        B = P if free is None else P[free][:, free]
        B = sp.csr_matrix(B)
        B.sort_indices()
        self.block_pattern = sp.csr_matrix(
            (np.ones(B.nnz), B.indices, B.indptr), shape=B.shape
        )  # fmt: skip
        self.block_map = B.data.astype(np.int64) - 1
        self.n = B.shape[0]
        U = self._upper(B, nnz)
        self.upper_pattern = sp.csr_matrix((np.ones(U.nnz), U.indices, U.indptr), shape=U.shape)
        self.upper_map = U.data.astype(np.int64) - 1
        L = self._upper(sp.csr_matrix(B.T), nnz)  # the lower triangle, transposed
        same = np.array_equal(L.indptr, U.indptr) and np.array_equal(L.indices, U.indices)
        self.lower_map = L.data.astype(np.int64) - 1 if same else None

    @staticmethod
    def _upper(B: sp.csr_matrix, nnz: int) -> sp.csr_matrix:
        U = sp.triu(B, format="csr")
        missing = U.diagonal() == 0
        if missing.any():
            U = (U + sp.diags(missing * float(nnz + 1))).tocsr()
        U.sort_indices()
        return U

    def matches(self, K: sp.csr_matrix, free: np.ndarray | None) -> bool:
        """Whether ``K`` and ``free`` have this pattern."""
        if K.shape != self.shape or K.nnz != self.nnz:
            return False
        if (free is None) != (self.free is None):
            return False
        if free is not None and self.free is not None and not np.array_equal(free, self.free):
            return False
        return np.array_equal(K.indptr, self.indptr) and np.array_equal(K.indices, self.indices)

    def block(self, K: sp.csr_matrix) -> sp.csr_matrix:
        """The free block of ``K`` (CSR)."""
        B = self.block_pattern.copy()
        B.data = K.data[self.block_map]
        return B

    def upper(self, data: np.ndarray, symmetrise: bool) -> np.ndarray:
        """Values of the upper triangle of the block (of its symmetric part)."""
        ext = np.append(data, 0.0)
        up = ext[self.upper_map]
        if symmetrise and self.lower_map is not None:
            up = 0.5 * (up + ext[self.lower_map])
        return up

    def asymmetry(self, data: np.ndarray) -> float:
        """``max |A - A^T| / max |A|`` of the block (``inf`` when not structurally symmetric)."""
        if self.lower_map is None:
            return np.inf
        ext = np.append(data, 0.0)
        scale = float(np.abs(data).max(initial=0.0))
        diff = float(np.abs(ext[self.upper_map] - ext[self.lower_map]).max(initial=0.0))
        return diff / scale if scale > 0 else 0.0


class DirectFactor:
    """A factorised free block; :meth:`solve` solves with it (refined against the block).

    Attributes
    ----------
    block
        The free block (CSR) the solutions are refined against.
    symmetric
        Factorised as (the symmetric part of) a symmetric matrix.
    name
        ``pardiso-ldlt``, ``pardiso-lu`` or ``superlu``.
    refinements
        Refinement steps of the last solve.
    inertia
        ``(positive, negative)`` eigenvalue counts of the factorised symmetric part
        (PARDISO's LDL^T), else ``None``: a stable saddle point has exactly as many
        negative eigenvalues as constraints, a stable displacement tangent none.
    """

    def __init__(self, block: sp.csr_matrix, solve, symmetric: bool, name: str, lu=None):
        self.block, self._solve = block, solve
        self.symmetric, self.name = symmetric, name
        self.refinements = 0
        self.converged = True
        self._lu = lu  # () -> DirectFactor by LU, for a refinement that does not converge
        self.inertia: tuple[int, int] | None = None

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Solve ``block x = b``, refining until :data:`REFINE_TOL` (or the step cap).

        Parameters
        ----------
        b
            Right-hand side on the free DOFs.

        Returns
        -------
        numpy.ndarray
            The solution (its residual is the caller's to judge).
        """
        x = self._solve(b)
        bnorm = float(np.linalg.norm(b))
        self.refinements, self.converged = 0, True
        if bnorm == 0 or not np.all(np.isfinite(x)):
            return x
        for step in range(REFINE_STEPS + 1):
            r = b - self.block @ x
            rn = float(np.linalg.norm(r))
            if rn <= REFINE_TOL * bnorm:
                return x
            if step == REFINE_STEPS or not np.isfinite(rn):
                break
            x = x + self._solve(r)
            self.refinements += 1
        if self._lu is not None:  # the symmetric part is too far from the block: LU
            lu, self._lu = self._lu(), None
            self._solve, self.symmetric, self.name = lu._solve, False, lu.name
            return self.solve(b)
        self.converged = False
        return x


class DirectSolver:
    """Direct factorisations of one problem's matrices, with the analysis kept per pattern.

    Parameters
    ----------
    backend
        ``auto`` (PARDISO when available, else SuperLU), ``pardiso`` or ``superlu``.

    Attributes
    ----------
    analyses
        Symbolic analyses done (one per pattern and factorisation kind).
    """

    def __init__(self, backend: str = "auto"):
        if backend == "auto":
            backend = "pardiso" if _pardiso.available() else "superlu"
        self.backend = backend
        self.analyses = 0
        self._blocks: FreeBlock | None = None
        self._handles: dict[bool, _pardiso.Pardiso] = {}
        self._lu_only = False  # the pattern's refinement failed once: LU from then on

    def release(self) -> None:
        """Forget the pattern and free PARDISO's memory."""
        for h in self._handles.values():
            h.release()
        self._handles, self._blocks, self._lu_only = {}, None, False

    def _pattern(self, K: sp.csr_matrix, free: np.ndarray | None) -> FreeBlock:
        if self._blocks is None or not self._blocks.matches(K, free):
            for h in self._handles.values():
                h.release()
            self._handles, self._lu_only = {}, False
            self._blocks = FreeBlock(K, free)
        return self._blocks

    def factor(self, K: sp.spmatrix, free: np.ndarray | None = None, admit=None) -> DirectFactor:
        """Factorise the free block of ``K``.

        Parameters
        ----------
        K
            The full square matrix.
        free
            Boolean mask of the free DOFs (``None``: all).
        admit
            ``admit(bytes, flops)`` raises :class:`FactorRefused` for a factorisation too
            large (``None``: any).

        Returns
        -------
        DirectFactor
            The factor.

        Raises
        ------
        RuntimeError
            An exactly singular matrix (or a PARDISO error).
        FactorRefused
            ``admit`` refused it, or PARDISO ran out of memory.
        """
        K = sp.csr_matrix(K)
        K.sum_duplicates()  # canonical form: sorted indices, no duplicates
        fb = self._pattern(K, None if free is None else np.asarray(free, dtype=bool))
        block = fb.block(K)
        sym = not self._lu_only and fb.asymmetry(K.data) <= NEAR_SYMMETRIC
        if self.backend == "superlu":
            if admit is not None:
                from .memory import factor_bytes_law

                admit(2.0 * factor_bytes_law(fb.n), flops_law(fb.n))  # LU: both triangles
            return self._superlu(block)
        f = self._pardiso(fb, K.data, block, sym, admit)
        if sym:
            f._lu = lambda: self._fall_back(fb, K.data, block)
        return f

    def _fall_back(self, fb: FreeBlock, data, block) -> DirectFactor:
        self._lu_only = True  # this pattern's matrices are factorised by LU from now on
        return self._pardiso(fb, data, block, False)  # refined LU: admitted already

    def _pardiso(self, fb: FreeBlock, data, block, sym: bool, admit=None) -> DirectFactor:
        handle = self._handles.get(sym)
        values = fb.upper(data, True) if sym else block.data
        if handle is None:
            handle = _pardiso.Pardiso(symmetric=sym)
            pattern = fb.upper_pattern if sym else fb.block_pattern
            A = sp.csr_matrix((values, pattern.indices, pattern.indptr), shape=pattern.shape)
            handle.analyse(A)
            self.analyses += 1
            self._handles[sym] = handle
        if admit is not None:
            try:
                admit(handle.memory, handle.flops)
            except FactorRefused:
                self.release()
                raise
        try:
            handle.factor(values)
        except _pardiso.PardisoError as exc:
            if exc.code in (-2, -9):  # not enough memory
                self.release()
                raise FactorRefused(str(exc)) from None
            raise RuntimeError(str(exc)) from None
        name = "pardiso-ldlt" if sym else "pardiso-lu"
        generation = handle.generation

        def solve(b: np.ndarray) -> np.ndarray:
            if handle.generation != generation:  # the handle holds a newer matrix's factor
                raise RuntimeError("solve with a factor replaced by a later factorisation")
            return handle.solve(b)

        f = DirectFactor(block, solve, sym, name)
        f.inertia = handle.inertia if sym else None
        return f

    @staticmethod
    def _superlu(block: sp.csr_matrix) -> DirectFactor:
        saddle = bool((block.diagonal() == 0).any())
        with warnings.catch_warnings():
            # a rank-deficient factor is judged by the residual of its solutions (a
            # singular but consistent system, e.g. a mechanism the load does not move)
            warnings.simplefilter("ignore", spla.MatrixRankWarning)
            spec = "COLAMD" if saddle else "MMD_AT_PLUS_A"  # the orderings' fill: above
            lu = spla.splu(block.tocsc(), permc_spec=spec)
        return DirectFactor(block, lu.solve, False, "superlu")
