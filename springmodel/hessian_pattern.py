"""CSR structure of a stiffness matrix summed from 12x12 tet blocks, built once.

The pattern is node-pair blocks of 3x3 DOFs; ``index_map`` sends every element entry to its
position in ``csr.data``, so assembling is one scatter-add (:mod:`springmodel.hessian`).

Examples
--------
>>> import numpy as np
>>> indptr, indices, index_map = csr_pattern(np.array([[0, 1, 2, 3]]), 4)
>>> int(indptr[-1]), index_map.shape
(144, (1, 144))
"""

from __future__ import annotations

import numpy as np


def csr_pattern(tets: np.ndarray, n_points: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """CSR structure of the ``3n x 3n`` matrix summed from ``12x12`` element blocks.

    Parameters
    ----------
    tets
        ``(m, 4)`` node indices.
    n_points
        Number of nodes ``n``.

    Returns
    -------
    indptr, indices
        Canonical CSR structure (sorted, no duplicates) of the DOF matrix.
    index_map
        ``(m, 144)`` position in ``data`` of each element entry ``(i, a, j, b)`` (C order,
        element row DOF ``3 tets[k, i] + a``, column DOF ``3 tets[k, j] + b``).
    """
    tets = np.asarray(tets, dtype=np.int64)
    m, n = tets.shape[0], int(n_points)
    # node-pair pattern: CSR of the node adjacency, each entry a dense 3x3 block
    key = (tets[:, :, None] * n + tets[:, None, :]).ravel()
    pairs, inverse = np.unique(key, return_inverse=True)
    prow, pcol = pairs // n, pairs % n
    nodeptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(prow, minlength=n), out=nodeptr[1:])
    deg = np.diff(nodeptr)
    rank = np.arange(pairs.size) - nodeptr[prow]  # position of the block within its node row
    a = np.arange(3)
    # DOF row 3I + a starts at 9 nodeptr[I] + 3 a deg[I]; block J sits at 3 rank .. 3 rank + 2
    row_start = 9 * nodeptr[:-1, None] + 3 * a[None, :] * deg[:, None]  # (n, 3)
    indptr = np.empty(3 * n + 1, dtype=np.int64)
    indptr[:-1] = row_start.ravel()
    indptr[-1] = 9 * pairs.size
    pos = row_start[prow][:, :, None] + 3 * rank[:, None, None] + a[None, None, :]  # (P, a, b)
    indices = np.empty(9 * pairs.size, dtype=np.int64)
    indices[pos.ravel()] = np.broadcast_to(3 * pcol[:, None, None] + a, pos.shape).ravel()
    # element entry (k, i, a, j, b) -> data position of pair (tets[k,i], tets[k,j]), (a, b)
    pos_e = pos[inverse.reshape(m, 4, 4)]  # (m, i, j, a, b)
    index_map = pos_e.transpose(0, 1, 3, 2, 4).reshape(m, 144)
    itype = np.int32 if 9 * pairs.size < np.iinfo(np.int32).max else np.int64
    return indptr.astype(itype), indices.astype(itype), np.ascontiguousarray(index_map)
