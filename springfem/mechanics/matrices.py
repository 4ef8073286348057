"""Matrix forms of the linear solver (:mod:`springfem.mechanics.linsolve`): the symmetry
test of a tangent and the symmetric elimination of constrained DOFs.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> A = eliminate(sp.csr_matrix(np.array([[2.0, -1.0], [-1.0, 2.0]])), np.array([True, False]))
>>> A.toarray().tolist(), is_symmetric(A)
([[2.0, 0.0], [0.0, 1.0]], True)
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

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
    """
    d = sp.diags(free.astype(float))
    A = (d @ sp.csr_matrix(K) @ d + sp.diags((~free).astype(float))).tocsr()
    A.eliminate_zeros()
    return A
