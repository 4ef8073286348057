"""The symmetric elimination of constrained unknowns from a sparse matrix, in place of one
copy (no products of the matrix, which is large: 53M entries for the organ's P2/P1 tangent
at 120k tets).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> K = sp.csr_matrix(np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 2.0], [0.0, 2.0, 3.0]]))
>>> eliminate(K, np.array([True, False, True])).toarray().tolist()  # a missing diagonal
[[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 3.0]]
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["eliminate"]


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
    >>> A.toarray().tolist(), bool(abs(A - A.T).max() == 0)
    ([[2.0, 0.0], [0.0, 1.0]], True)
    """
    free = np.asarray(free, dtype=bool)
    A = sp.csr_matrix(K, copy=True)
    A.sum_duplicates()
    rows = np.repeat(np.arange(A.shape[0], dtype=A.indices.dtype), np.diff(A.indptr))
    A.data[~(free[rows] & free[A.indices])] = 0.0  # in place: no products of the matrix
    unit = (rows == A.indices) & ~free[rows]  # the constrained rows' stored diagonals
    A.data[unit] = 1.0
    missing = np.setdiff1d(np.flatnonzero(~free), rows[unit])
    del rows, unit
    A.eliminate_zeros()
    if missing.size:
        A = A + sp.csr_matrix((np.ones(missing.size), (missing, missing)), shape=A.shape)
    return sp.csr_matrix(A)
