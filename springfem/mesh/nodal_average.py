"""The nodal averaging operator of linear tets and its two-ring tangent, built once.

Nodal-strain tetrahedra (docs/fem.rst#nodal-strain-tetrahedra, docs/volumetric.rst) measure
their law on the deformation gradient averaged over each node's patch,

    Fbar_a = sum_{e ni a} w_ea F_e,   w_ea = V_e / sum_{e' ni a} V_e',
    F_e = sum_i x_i (x) grad N_i^e,

a linear map ``Fbar = B x`` whose transpose sends nodal stresses ``T_a`` to nodal forces
``B^T T`` and whose tangent ``B^T diag(A_a) B`` couples the nodes of two rings. This module
holds ``B`` as the element data ``(tets, grad N, w)`` and runs both products as one pass over
the elements (no sparse matrix, no temporaries); the tangent's CSR pattern (node pairs that
share a patch, dense ``3 x 3`` blocks) and the position of every term in it are computed
once, so a Newton step only sums numbers into a fixed ``data`` array. Element matrices
(``12 x 12``) sum into the same pattern (:meth:`NodalAverage.add_elements`): the spring model
and the FEM add their element and nodal-volume parts there and build one matrix.

``B x`` and ``B^T T`` run row by row over the nodes (each row writes only its own node: no
races, so the parallel variant gives bitwise the serial sums); the tangent and element sums
run serially in a fixed order (deterministic). The pattern is the canonical CSR (sorted, no
duplicates) of the ``3n x 3n`` matrix.

Examples
--------
>>> import numpy as np
>>> from springfem.mesh import box_mesh
>>> mesh = box_mesh((2.0, 1.0, 1.0), (2, 1, 1))
>>> op = NodalAverage.of(mesh.points, mesh.tets)
>>> F = np.array([[1.1, 0.2, 0.0], [0.0, 0.9, 0.0], [0.1, 0.0, 1.0]])
>>> bool(np.allclose(op.gradients(mesh.points @ F.T), F))  # exact for affine maps
True
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numba import njit, prange

__all__ = ["NodalAverage", "shape_gradients"]
#: Whether :class:`NodalAverage` runs its products on all threads by default: off.
#: ``springfem bench lockfree`` on the shared 2-core machine under a load average of 8-13:
#: at 4,781 organ tets the spring-stabilised step took 1.3 ms on two threads against 1.0 ms
#: on one; at 29,291 tets 9.9 against 37 ms, in a run where P1-NH's own step varied 2.4x
#: between its thread counts. Measure on an idle machine before turning it on.
PARALLEL_BY_DEFAULT = False


def shape_gradients(X: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """``grad N_i`` of the four vertices of every tet at rest, ``(m, 4, 3)``.

    Parameters
    ----------
    X
        Rest positions ``(n, 3)``.
    tets
        Connectivity ``(m, 4)``.

    Returns
    -------
    numpy.ndarray
        ``(m, 4, 3)``; they sum to zero over the vertices.
    """
    p = np.asarray(X, float)[tets]
    D = (p[:, 1:] - p[:, :1]).transpose(0, 2, 1)  # columns: edges
    g = np.empty(p.shape)
    g[:, 1:] = np.linalg.inv(D)  # rows of D^-1 are grad N_1..3
    g[:, 0] = -g[:, 1:].sum(axis=1)
    return g


class NodalAverage:
    """``Fbar = B x``, ``B^T T`` and ``B^T diag(A) B`` of a tet mesh (module text).

    Parameters
    ----------
    tets
        Connectivity ``(m, 4)``.
    grads
        Rest shape gradients ``(m, 4, 3)`` (:func:`shape_gradients`).
    volumes
        Rest volumes ``(m,)`` (positive): the averaging weights.
    n
        Number of nodes.
    """

    def __init__(self, tets: np.ndarray, grads: np.ndarray, volumes: np.ndarray, n: int):
        self.tets = np.ascontiguousarray(tets, dtype=np.int64)
        self.grads = np.ascontiguousarray(grads, dtype=float)
        V = np.asarray(volumes, dtype=float)
        self.n = int(n)
        self.patch = np.bincount(self.tets.ravel(), np.repeat(V, 4), minlength=self.n)
        safe = np.where(self.patch > 0, self.patch, 1.0)
        self.weights = np.ascontiguousarray(V[:, None] / safe[self.tets])  # (m, 4)
        self._rows: tuple | None = None  # B by node rows (the products), on first use
        self._pattern: tuple | None = None  # the tangent's (a superset), on first use
        #: Run the products on all numba threads (rows are independent: no races, the same
        #: sums in the same order as serially). Default :data:`PARALLEL_BY_DEFAULT`.
        self.parallel = PARALLEL_BY_DEFAULT

    @classmethod
    def of(cls, X: np.ndarray, tets: np.ndarray) -> NodalAverage:
        """The operator of rest positions ``X`` ``(n, 3)`` and connectivity ``tets``."""
        X = np.asarray(X, dtype=float)
        g = shape_gradients(X, tets)
        p = X[np.asarray(tets)]
        V = (
            np.abs(
                np.einsum(
                    "ka,ka->k", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0])
                )
            )
            / 6.0
        )
        return cls(tets, g, V, X.shape[0])

    # -- products -----------------------------------------------------------------------------
    def gradients(self, x: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """``Fbar_a`` ``(n, 3, 3)`` of positions (or displacements) ``x`` ``(n, 3)``."""
        x = np.ascontiguousarray(x, dtype=float).reshape(self.n, 3)
        out = np.empty((self.n, 3, 3)) if out is None else out
        rowptr, cols, gb = self.rows
        kernel = _row_gradients_parallel if self.parallel else _row_gradients
        kernel(x, rowptr, cols, gb, out)
        return out

    def transpose(self, T: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """``B^T T``: nodal forces ``(n, 3)`` of nodal stresses ``T`` ``(n, 3, 3)`` (``out``
        is added to when given)."""
        T = np.ascontiguousarray(T, dtype=float).reshape(self.n, 3, 3)
        out = np.zeros((self.n, 3)) if out is None else out
        rowptr, cols, gb = self.rows
        kernel = _row_transpose_parallel if self.parallel else _row_transpose
        kernel(T, rowptr, cols, gb, self.transposed, out)
        return out

    @property
    def rows(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``B`` by node rows: ``(rowptr, cols, gb)``, ``gb[k]`` the ``3``-vector of node
        ``cols[k]`` in the average of node ``a`` (``rowptr[a] <= k < rowptr[a + 1]``)."""
        if self._rows is None:
            self._rows = _row_structure(self.tets, self.grads, self.weights, self.n)
        return self._rows[0], self._rows[1], self._rows[2]

    @property
    def transposed(self) -> np.ndarray:
        """``transposed[k]``: the entry ``(c, a)`` of the entry ``k = (a, c)`` (the node
        structure is symmetric)."""
        self.rows  # noqa: B018 - builds them
        assert self._rows is not None
        return self._rows[4]

    # -- the two-ring tangent ------------------------------------------------------------------
    @property
    def pattern(self) -> tuple:
        """``(indptr, indices, rowptr, cols, gb, term_base, block_rows, element_map,
        copy_index)``, built once; ``copy_index[16 e + 4 p + q]`` is the entry of node
        ``tets[e, q]`` in the row of node ``tets[e, p]`` (``rowptr``, ``cols``)."""
        if self._pattern is None:
            self.rows  # noqa: B018 - builds them
            self._pattern = _two_ring_pattern(self.tets, self._rows, self.n)
        return self._pattern

    @property
    def nnz(self) -> int:
        """Stored entries of the tangent's pattern."""
        return int(self.pattern[1].size)

    def zeros(self) -> np.ndarray:
        """A zero ``data`` array of the pattern."""
        return np.zeros(self.nnz)

    def add_tangent(self, A: np.ndarray, data: np.ndarray) -> np.ndarray:
        """``data += B^T diag(A_a) B`` for nodal moduli ``A`` ``(n, 9, 9)`` (rows ``3 alpha +
        beta`` of ``Fbar[alpha, beta]``)."""
        _, _, rowptr, cols, gb, base, brow = self.pattern[:7]
        _two_ring_add(np.ascontiguousarray(A, dtype=float).reshape(self.n, 9, 9), rowptr, cols,
                      gb, base, brow, data)  # fmt: skip
        return data

    def add_outer(self, w: np.ndarray, G: np.ndarray, data: np.ndarray) -> np.ndarray:
        """``data += sum_a w_a g_a g_a^T`` for the rows ``g_a`` of a matrix with ``B``'s node
        structure: ``G`` ``(nnz, 3)`` holds its ``3``-vector entries in the order of ``cols``
        (:meth:`row_entries` builds it from element vectors)."""
        _, _, rowptr, cols, _, base, brow = self.pattern[:7]
        _two_ring_outer(np.ascontiguousarray(w, dtype=float), rowptr, cols,
                        np.ascontiguousarray(G, dtype=float), base, brow, data)  # fmt: skip
        return data

    def row_entries(self, ge: np.ndarray, scale: float = 1.0) -> np.ndarray:
        """The node rows ``g_a = scale sum_{e ni a} ge_e`` of element vectors ``ge``
        ``(m, 4, 3)`` (each element's vector counted in the row of each of its vertices),
        ``(nnz, 3)`` in the order of ``cols``."""
        cols, copy = self.pattern[3], self.pattern[8]
        G = np.zeros((cols.size, 3))
        _row_entries(np.ascontiguousarray(ge, dtype=float), copy, scale, G)
        return G

    def add_elements(self, Ke: np.ndarray, data: np.ndarray, lo: int = 0) -> np.ndarray:
        """``data +=`` the element matrices ``Ke`` ``(k, 12, 12)`` of elements ``lo:lo + k``
        (rows ``3 i + a``, vertex ``i`` of the element, component ``a``)."""
        emap = self.pattern[7]
        Ke = np.ascontiguousarray(Ke, dtype=float)
        _element_add(data, emap[lo : lo + Ke.shape[0]], Ke)
        return data

    def matrix(self, data: np.ndarray) -> sp.csr_matrix:
        """The ``(3n, 3n)`` CSR matrix of ``data`` on the pattern (sorted indices)."""
        indptr, indices = self.pattern[:2]
        K = sp.csr_matrix((data, indices, indptr), shape=(3 * self.n, 3 * self.n), copy=False)
        K.has_sorted_indices = True
        return K

    def tangent(self, A: np.ndarray) -> sp.csr_matrix:
        """``B^T diag(A_a) B`` as a CSR matrix (:meth:`add_tangent` on zeros)."""
        return self.matrix(self.add_tangent(A, self.zeros()))


def _row_structure(tets, grads, weights, n):
    """``B`` by node rows: ``(rowptr, cols, gb, copy_index, transposed)``."""
    m = tets.shape[0]
    # B's node rows: a -> the nodes c of its patch, gb[a, c] = sum_e w_ea grad N_c^e
    a_idx = np.repeat(tets, 4, axis=1).ravel()  # (e, p, q): a = tets[e, p]
    c_idx = np.tile(tets, (1, 4)).ravel()  # c = tets[e, q]
    keys, inv = np.unique(a_idx * n + c_idx, return_inverse=True)
    vals = (weights[:, :, None, None] * grads[:, None, :, :]).reshape(m * 16, 3)
    gb = np.stack([np.bincount(inv.ravel(), vals[:, b], keys.size) for b in range(3)], axis=1)
    rows, cols = keys // n, keys % n
    rowptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows, minlength=n), out=rowptr[1:])
    return (rowptr, cols.astype(np.int64), np.ascontiguousarray(gb), inv.astype(np.int64).ravel(),
            np.searchsorted(keys, cols * n + rows))  # fmt: skip


def _two_ring_pattern(tets, row_structure, n):
    """The CSR pattern of ``B^T B`` and where every term of the tangent goes."""
    m = tets.shape[0]
    rowptr, cols, gb, inv, tpos = row_structure
    # every term (a; c, d) of the tangent: c, d in the patch of a
    deg = np.diff(rowptr)
    term_ptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(deg * deg, out=term_ptr[1:])
    owner = np.repeat(np.arange(n), deg * deg)
    local = np.arange(term_ptr[-1]) - term_ptr[owner]
    ci = rowptr[owner] + local // deg[owner]
    di = rowptr[owner] + local % deg[owner]
    tkey = cols[ci] * n + cols[di]
    pairs, tinv = np.unique(tkey, return_inverse=True)
    prow, pcol = pairs // n, pairs % n
    nodeptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(prow, minlength=n), out=nodeptr[1:])
    bdeg = np.diff(nodeptr)  # blocks in each node row
    rank = np.arange(pairs.size) - nodeptr[prow]
    a3 = np.arange(3)
    row_start = 9 * nodeptr[:-1, None] + 3 * a3[None, :] * bdeg[:, None]  # (n, 3)
    indptr = np.empty(3 * n + 1, dtype=np.int64)
    indptr[:-1] = row_start.ravel()
    indptr[-1] = 9 * pairs.size
    pos = row_start[prow][:, :, None] + 3 * rank[:, None, None] + a3[None, None, :]
    indices = np.empty(9 * pairs.size, dtype=np.int64)
    indices[pos.ravel()] = np.broadcast_to(3 * pcol[:, None, None] + a3, pos.shape).ravel()
    block_base = 9 * nodeptr[prow] + 3 * rank  # entry (alpha, gamma) at + 3 alpha bdeg + gamma
    term_base = block_base[tinv]
    # element entries (e, i, a, j, b) -> data position
    ekey = (tets[:, :, None] * n + tets[:, None, :]).ravel()
    epair = np.searchsorted(pairs, ekey)
    epos = pos[epair].reshape(m, 4, 4, 3, 3).transpose(0, 1, 3, 2, 4).reshape(m, 144)
    return (indptr, indices, rowptr, cols, gb, term_base.astype(np.int64),
            3 * bdeg.astype(np.int64), np.ascontiguousarray(epos), inv, tpos)  # fmt: skip


@njit(cache=True, fastmath=False)
def _row_gradients(x, rowptr, cols, gb, out):  # pragma: no cover - compiled; vs B x
    """``out[a] = sum_c x_c (x) gb_ac`` over the row of node ``a`` (rows are independent)."""
    for a in range(rowptr.size - 1):
        f00 = f01 = f02 = f10 = f11 = f12 = f20 = f21 = f22 = 0.0
        for k in range(rowptr[a], rowptr[a + 1]):
            c = cols[k]
            g0, g1, g2 = gb[k, 0], gb[k, 1], gb[k, 2]
            x0, x1, x2 = x[c, 0], x[c, 1], x[c, 2]
            f00 += x0 * g0
            f01 += x0 * g1
            f02 += x0 * g2
            f10 += x1 * g0
            f11 += x1 * g1
            f12 += x1 * g2
            f20 += x2 * g0
            f21 += x2 * g1
            f22 += x2 * g2
        out[a, 0, 0], out[a, 0, 1], out[a, 0, 2] = f00, f01, f02
        out[a, 1, 0], out[a, 1, 1], out[a, 1, 2] = f10, f11, f12
        out[a, 2, 0], out[a, 2, 1], out[a, 2, 2] = f20, f21, f22


@njit(cache=True, fastmath=False, parallel=True)
def _row_gradients_parallel(x, rowptr, cols, gb, out):  # pragma: no cover - compiled; vs B x
    """``out[a] = sum_c x_c (x) gb_ac`` over the row of node ``a`` (rows are independent)."""
    for a in prange(rowptr.size - 1):
        f00 = f01 = f02 = f10 = f11 = f12 = f20 = f21 = f22 = 0.0
        for k in range(rowptr[a], rowptr[a + 1]):
            c = cols[k]
            g0, g1, g2 = gb[k, 0], gb[k, 1], gb[k, 2]
            x0, x1, x2 = x[c, 0], x[c, 1], x[c, 2]
            f00 += x0 * g0
            f01 += x0 * g1
            f02 += x0 * g2
            f10 += x1 * g0
            f11 += x1 * g1
            f12 += x1 * g2
            f20 += x2 * g0
            f21 += x2 * g1
            f22 += x2 * g2
        out[a, 0, 0], out[a, 0, 1], out[a, 0, 2] = f00, f01, f02
        out[a, 1, 0], out[a, 1, 1], out[a, 1, 2] = f10, f11, f12
        out[a, 2, 0], out[a, 2, 1], out[a, 2, 2] = f20, f21, f22


@njit(cache=True, fastmath=False)
def _row_transpose(T, rowptr, cols, gb, tpos, out):  # pragma: no cover - compiled
    """``out[c] += sum_a T_a gb_ac`` over the row of node ``c`` (``a`` in its patch; rows
    are independent)."""
    for c in range(rowptr.size - 1):
        v0 = v1 = v2 = 0.0
        for k in range(rowptr[c], rowptr[c + 1]):
            a = cols[k]
            t = tpos[k]
            g0, g1, g2 = gb[t, 0], gb[t, 1], gb[t, 2]
            v0 += T[a, 0, 0] * g0 + T[a, 0, 1] * g1 + T[a, 0, 2] * g2
            v1 += T[a, 1, 0] * g0 + T[a, 1, 1] * g1 + T[a, 1, 2] * g2
            v2 += T[a, 2, 0] * g0 + T[a, 2, 1] * g1 + T[a, 2, 2] * g2
        out[c, 0] += v0
        out[c, 1] += v1
        out[c, 2] += v2


@njit(cache=True, fastmath=False, parallel=True)
def _row_transpose_parallel(T, rowptr, cols, gb, tpos, out):  # pragma: no cover - compiled
    """``out[c] += sum_a T_a gb_ac`` over the row of node ``c`` (``a`` in its patch; rows
    are independent)."""
    for c in prange(rowptr.size - 1):
        v0 = v1 = v2 = 0.0
        for k in range(rowptr[c], rowptr[c + 1]):
            a = cols[k]
            t = tpos[k]
            g0, g1, g2 = gb[t, 0], gb[t, 1], gb[t, 2]
            v0 += T[a, 0, 0] * g0 + T[a, 0, 1] * g1 + T[a, 0, 2] * g2
            v1 += T[a, 1, 0] * g0 + T[a, 1, 1] * g1 + T[a, 1, 2] * g2
            v2 += T[a, 2, 0] * g0 + T[a, 2, 1] * g1 + T[a, 2, 2] * g2
        out[c, 0] += v0
        out[c, 1] += v1
        out[c, 2] += v2


@njit(cache=True, fastmath=False)
def _two_ring_add(A, rowptr, cols, gb, base, brow, data):  # pragma: no cover - compiled
    """``data += B^T diag(A) B``: ``K_cd[al, ga] += sum gb_ac[be] A_a[al be, ga de] gb_ad[de]``."""
    M = np.empty((3, 3, 3))
    t = 0
    for a in range(A.shape[0]):
        lo, hi = rowptr[a], rowptr[a + 1]
        for ci in range(lo, hi):
            c = cols[ci]
            for al in range(3):
                for ga in range(3):
                    for de in range(3):
                        v = 0.0
                        for be in range(3):
                            v += gb[ci, be] * A[a, 3 * al + be, 3 * ga + de]
                        M[al, ga, de] = v
            stride = brow[c]
            for di in range(lo, hi):
                b0 = base[t]
                t += 1
                g0, g1, g2 = gb[di, 0], gb[di, 1], gb[di, 2]
                for al in range(3):
                    r = b0 + al * stride
                    for ga in range(3):
                        data[r + ga] += M[al, ga, 0] * g0 + M[al, ga, 1] * g1 + M[al, ga, 2] * g2


@njit(cache=True, fastmath=False)
def _two_ring_outer(w, rowptr, cols, G, base, brow, data):  # pragma: no cover - compiled
    """``data += sum_a w_a G_a G_a^T``: ``K_cd[al, ga] += w_a G_ac[al] G_ad[ga]``."""
    t = 0
    for a in range(w.shape[0]):
        lo, hi = rowptr[a], rowptr[a + 1]
        wa = w[a]
        for ci in range(lo, hi):
            stride = brow[cols[ci]]
            u0, u1, u2 = wa * G[ci, 0], wa * G[ci, 1], wa * G[ci, 2]
            for di in range(lo, hi):
                b0 = base[t]
                t += 1
                v0, v1, v2 = G[di, 0], G[di, 1], G[di, 2]
                data[b0] += u0 * v0
                data[b0 + 1] += u0 * v1
                data[b0 + 2] += u0 * v2
                data[b0 + stride] += u1 * v0
                data[b0 + stride + 1] += u1 * v1
                data[b0 + stride + 2] += u1 * v2
                data[b0 + 2 * stride] += u2 * v0
                data[b0 + 2 * stride + 1] += u2 * v1
                data[b0 + 2 * stride + 2] += u2 * v2


@njit(cache=True, fastmath=False)
def _row_entries(ge, copy, scale, G):  # pragma: no cover - compiled
    """``G[copy[16 e + 4 p + q]] += scale ge[e, q]`` for every vertex ``p``."""
    for e in range(ge.shape[0]):
        for p in range(4):
            for q in range(4):
                r = copy[16 * e + 4 * p + q]
                for al in range(3):
                    G[r, al] += scale * ge[e, q, al]


@njit(cache=True, fastmath=False)
def _element_add(data, emap, Ke):  # pragma: no cover - compiled; tested against scipy sums
    """``data[emap[k, e]] += Ke[k].flat[e]`` in element order."""
    for k in range(Ke.shape[0]):
        e = 0
        for r in range(12):
            for c in range(12):
                data[emap[k, e]] += Ke[k, r, c]
                e += 1
