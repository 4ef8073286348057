"""Analytic tangent stiffness ``K = d^2 U / dx^2`` of the conservative spring variants.

For the energy forms (axial ``linear``/``quadratic``/``cubic``, torsion ``off``/``energy``,
volume ``gradient``; see :func:`springmodel.springs.spring_energy`) the spring forces are
``-grad U`` and ``K = -d forces / dx`` is the Hessian of

    U = sum_k [ sum_l f_l(|zeta_l|) + sum_(l,m) k_lm/2 (c_lm - c0_lm)^2 + k_s/2 (L - L0)^2 ],

``zeta_l = sum_i G[k,i,l] x_i`` (the fast-kernel identity, DESIGN §4), ``c_lm = zh_l . zh_m``
and ``L = sum_j |x_j - x_b|``. Per element:

axial, ``a = zeta_l``, ``f'(L) = k (d + b2 d^2/l0 + b3 d^3/l0^2)`` (eq. 2.36)
    ``d^2 f / da^2 = f'' ah ah^T + f'/|a| (I - ah ah^T)``.
torsion, ``a = zeta_l``, ``b = zeta_m``, ``A = |a|``, ``B = |b|``
    ``dc/da = (bh - c ah)/A``, ``d^2c/da^2 = -(ah g_a^T + g_a ah^T)/A - c (I - ah ah^T)/A^2``,
    ``d^2c/da db = (I - ah ah^T - bh bh^T + c ah bh^T)/(A B)``;
    ``U'' = k (grad c grad c^T + (c - c0) grad^2 c)``.
volume, ``r_j = |xi_j|``, ``xi_j = x_j - x_b``, ``d xi_j / d x_i = (delta_ij - 1/4) I``
    ``grad_i L = xh_i - mean_j xh_j``; with ``H_j = (I - xh_j xh_j^T)/r_j``,
    ``grad^2_ik L = delta_ik H_i - (H_i + H_k)/4 + sum_j H_j / 16``;
    ``U'' = k_s (grad L grad L^T + (L - L0) grad^2 L)``.

The axial and torsion parts are assembled as one 9x9 Hessian in the three axis vectors
and mapped to the 12 vertex DOFs with ``G`` (``d zeta_l / d x_i = G[k,i,l] I``).

The sparsity pattern (the 12x12 element blocks summed into a CSR matrix) is built once;
each call only computes the element matrices and sums them into ``csr.data`` with one
``np.bincount`` through a precomputed index map. The element matrices come from a numba
kernel (``backend="numba"``, one pass per element, parallel over elements) or from the
vectorised numpy reference (``backend="numpy"``, about 20x slower); the tests check both.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import scipy.sparse as sp
from numba import njit, prange

from .calibration import TORSION_PAIRS
from .elements import SpringElements
from .options import SpringOptions
from .springs import is_conservative

Backend = Literal["numba", "numpy"]
_PAIR_L = np.array([p[0] for p in TORSION_PAIRS], dtype=np.int64)
_PAIR_M = np.array([p[1] for p in TORSION_PAIRS], dtype=np.int64)


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


def polynomial_coefficients(options: SpringOptions) -> tuple[float, float]:
    """``(b2, b3)`` of the axial law (zero for ``linear``, ``b3 = 0`` for ``quadratic``)."""
    if options.axial in ("quadratic", "cubic"):
        b2, b3 = options.axial_coefficients
        return float(b2), float(b3) if options.axial == "cubic" else 0.0
    return 0.0, 0.0


@njit(cache=True, parallel=True, fastmath=False)
def _element_matrices_numba(
    x, tets, G, l0, ka, kt, c0, kv, L0, b2, b3, torsion, volume, pair_l, pair_m, out
):  # pragma: no cover - compiled; checked against the numpy reference in the tests
    m = tets.shape[0]
    for k in prange(m):
        X = np.empty((4, 3))
        for i in range(4):
            for c in range(3):
                X[i, c] = x[tets[k, i], c]
        U = np.zeros((3, 3))
        Ls = np.empty(3)
        H = np.zeros((9, 9))
        # axial: f'' uu^T + f'/L (I - uu^T), eqs. 2.35-2.36
        for l in range(3):
            for c in range(3):
                z = 0.0
                for i in range(4):
                    z += G[k, i, l] * X[i, c]
                U[l, c] = z
            L = np.sqrt(U[l, 0] ** 2 + U[l, 1] ** 2 + U[l, 2] ** 2)
            Ls[l] = L
            for c in range(3):
                U[l, c] /= L
            r = (L - l0[k, l]) / l0[k, l]
            f1 = ka[k, l] * (L - l0[k, l]) * (1.0 + b2 * r + b3 * r * r)
            f2 = ka[k, l] * (1.0 + 2.0 * b2 * r + 3.0 * b3 * r * r)
            s = f1 / L
            for a in range(3):
                for b in range(3):
                    v = (f2 - s) * U[l, a] * U[l, b]
                    if a == b:
                        v += s
                    H[3 * l + a, 3 * l + b] += v
        # torsion (energy law): k (grad c grad c^T + (c - c0) grad^2 c)
        if torsion:
            ga = np.empty(3)
            gb = np.empty(3)
            for p in range(3):
                l = pair_l[p]
                q = pair_m[p]
                A = Ls[l]
                B = Ls[q]
                c = U[l, 0] * U[q, 0] + U[l, 1] * U[q, 1] + U[l, 2] * U[q, 2]
                dc = c - c0[k, p]
                kk = kt[k, p]
                for a in range(3):
                    ga[a] = (U[q, a] - c * U[l, a]) / A
                    gb[a] = (U[l, a] - c * U[q, a]) / B
                for a in range(3):
                    for b in range(3):
                        dab = 1.0 if a == b else 0.0
                        pa = dab - U[l, a] * U[l, b]
                        pb = dab - U[q, a] * U[q, b]
                        haa = -(U[l, a] * ga[b] + ga[a] * U[l, b]) / A - c * pa / (A * A)
                        hbb = -(U[q, a] * gb[b] + gb[a] * U[q, b]) / B - c * pb / (B * B)
                        hab = (pa - U[q, a] * U[q, b] + c * U[l, a] * U[q, b]) / (A * B)
                        H[3 * l + a, 3 * l + b] += kk * (ga[a] * ga[b] + dc * haa)
                        H[3 * q + a, 3 * q + b] += kk * (gb[a] * gb[b] + dc * hbb)
                        v = kk * (ga[a] * gb[b] + dc * hab)
                        H[3 * l + a, 3 * q + b] += v
                        H[3 * q + b, 3 * l + a] += v
        # K[3i+a, 3j+b] = sum_{l,q} G[i,l] H[3l+a, 3q+b] G[j,q]
        T = np.zeros((12, 9))
        for i in range(4):
            for a in range(3):
                for col in range(9):
                    t = 0.0
                    for l in range(3):
                        t += G[k, i, l] * H[3 * l + a, col]
                    T[3 * i + a, col] = t
        K = out[k]
        for row in range(12):
            for j in range(4):
                for b in range(3):
                    t = 0.0
                    for q in range(3):
                        t += T[row, 3 * q + b] * G[k, j, q]
                    K[row, 3 * j + b] = t
        # volume (gradient form): k_s (grad L grad L^T + dL grad^2 L)
        if volume:
            xb = np.zeros(3)
            for i in range(4):
                for c in range(3):
                    xb[c] += 0.25 * X[i, c]
            xh = np.empty((4, 3))
            rr = np.empty(4)
            dL = -L0[k]
            for i in range(4):
                for c in range(3):
                    xh[i, c] = X[i, c] - xb[c]
                rr[i] = np.sqrt(xh[i, 0] ** 2 + xh[i, 1] ** 2 + xh[i, 2] ** 2)
                dL += rr[i]
                for c in range(3):
                    xh[i, c] /= rr[i]
            gL = np.empty((4, 3))
            for c in range(3):
                mean = 0.25 * (xh[0, c] + xh[1, c] + xh[2, c] + xh[3, c])
                for i in range(4):
                    gL[i, c] = xh[i, c] - mean
            Hr = np.empty((4, 3, 3))
            S = np.zeros((3, 3))
            for i in range(4):
                for a in range(3):
                    for b in range(3):
                        v = -xh[i, a] * xh[i, b]
                        if a == b:
                            v += 1.0
                        Hr[i, a, b] = v / rr[i]
                        S[a, b] += Hr[i, a, b] / 16.0
            ks = kv[k]
            for i in range(4):
                for j in range(4):
                    for a in range(3):
                        for b in range(3):
                            h2 = S[a, b] - 0.25 * (Hr[i, a, b] + Hr[j, a, b])
                            if i == j:
                                h2 += Hr[i, a, b]
                            K[3 * i + a, 3 * j + b] += ks * (gL[i, a] * gL[j, b] + dL * h2)
        for row in range(12):
            for col in range(row + 1, 12):
                v = 0.5 * (K[row, col] + K[col, row])
                K[row, col] = v
                K[col, row] = v


def _outer(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return u[..., :, None] * v[..., None, :]


def axis_hessian(
    zeta: np.ndarray,
    l0: np.ndarray,
    k_axial: np.ndarray,
    k_torsion: np.ndarray,
    c0: np.ndarray,
    options: SpringOptions,
) -> np.ndarray:
    """Hessian of the axial + torsion energy in the axis vectors, ``(m, 3, 3, 3, 3)``.

    Index order ``[k, l, a, m, b]``: ``d^2 U / d zeta_l[a] d zeta_m[b]``. ``zeta (m, 3, 3)``
    are the current axes, the other arrays the elements' rest lengths, constants and cosines.
    """
    m = zeta.shape[0]
    eye = np.eye(3)
    L = np.linalg.norm(zeta, axis=-1)  # (m, 3)
    u = zeta / L[..., None]
    uu = _outer(u, u)  # (m, 3, 3, 3)
    H = np.zeros((m, 3, 3, 3, 3))

    # axial: f'' uu^T + f'/L (I - uu^T), eqs. 2.35–2.36
    k = k_axial
    d = L - l0
    b2, b3 = polynomial_coefficients(options)
    f1 = k * (d + b2 * d**2 / l0 + b3 * d**3 / l0**2)
    f2 = k * (1.0 + 2.0 * b2 * d / l0 + 3.0 * b3 * d**2 / l0**2)
    for l in range(3):
        s = (f1[:, l] / L[:, l])[:, None, None]
        H[:, l, :, l, :] = f2[:, l, None, None] * uu[:, l] + s * (eye - uu[:, l])

    # torsion (energy law): k (grad c grad c^T + (c - c0) grad^2 c)
    if options.torsion == "energy":
        for p, (l, q) in enumerate(TORSION_PAIRS):
            A, B = L[:, l, None], L[:, q, None]
            ua, ub = u[:, l], u[:, q]
            c = np.einsum("kc,kc->k", ua, ub)
            dc = (c - c0[:, p])[:, None, None]
            kt = k_torsion[:, p, None, None]
            cc = c[:, None, None]
            ga = (ub - c[:, None] * ua) / A  # dc/da
            gb = (ua - c[:, None] * ub) / B  # dc/db
            Pa, Pb = eye - uu[:, l], eye - uu[:, q]
            A2, B2 = A[..., None], B[..., None]
            haa = -(_outer(ua, ga) + _outer(ga, ua)) / A2 - cc * Pa / A2**2
            hbb = -(_outer(ub, gb) + _outer(gb, ub)) / B2 - cc * Pb / B2**2
            hab = (Pa - uu[:, q] + cc * _outer(ua, ub)) / (A2 * B2)
            H[:, l, :, l, :] += kt * (_outer(ga, ga) + dc * haa)
            H[:, q, :, q, :] += kt * (_outer(gb, gb) + dc * hbb)
            Kab = kt * (_outer(ga, gb) + dc * hab)
            H[:, l, :, q, :] += Kab
            H[:, q, :, l, :] += Kab.transpose(0, 2, 1)
    return H


def volume_hessian(X: np.ndarray, L0: np.ndarray, k_volume: np.ndarray) -> np.ndarray:
    """Hessian of ``k_s/2 (sum_j |x_j - x_b| - L0)^2`` in the vertices, ``(m, 4, 3, 4, 3)``."""
    xi = X - X.mean(axis=1, keepdims=True)  # restoring sign, barycenter -> vertex
    r = np.linalg.norm(xi, axis=-1)
    xh = xi / r[..., None]
    dL = r.sum(axis=1) - L0
    gL = xh - xh.mean(axis=1, keepdims=True)  # (m, 4, 3)
    Hr = (np.eye(3) - _outer(xh, xh)) / r[..., None, None]  # (m, 4, 3, 3)
    S = Hr.sum(axis=1) / 16.0  # (m, 3, 3)
    H2 = -0.25 * (Hr[:, :, None] + Hr[:, None, :]) + S[:, None, None]  # (m, i, k, a, b)
    H2[:, np.arange(4), np.arange(4)] += Hr
    K = _outer(gL.reshape(-1, 12), gL.reshape(-1, 12)).reshape(-1, 4, 3, 4, 3)
    K += dL[:, None, None, None, None] * H2.transpose(0, 1, 3, 2, 4)
    return k_volume[:, None, None, None, None] * K


class SpringHessian:
    """Analytic tangent stiffness of the conservative spring variants.

    Parameters
    ----------
    elements
        Spring rest data; ``k_volume`` is read at every call (LMS may change it).
    options
        Must be conservative (:func:`springmodel.springs.is_conservative`): axial
        ``linear``/``quadratic``/``cubic``, torsion ``off``/``energy``, volume off or
        ``gradient``. Damping and LMS do not enter ``K`` (they make the options
        non-conservative and are refused).
    backend
        ``numba`` (default) or ``numpy`` (the vectorised reference) for the element matrices.
    chunk
        Elements per block when summing into the matrix (bounds the memory of the element
        matrices to ``chunk * 1152`` bytes).

    Examples
    --------
    >>> from springfem.mesh import box_mesh
    >>> from springmodel.elements import build_spring_elements
    >>> mesh = box_mesh((1.0, 1.0, 1.0), (1, 1, 1))
    >>> frames = np.broadcast_to(np.eye(3), (mesh.n_tets, 3, 3))
    >>> opts = SpringOptions(torsion="energy")
    >>> el = build_spring_elements(mesh.points, mesh.tets, frames, opts, {"E": 1.0, "nu": 0.3})
    >>> K = SpringHessian(el, opts).matrix(mesh.points)
    >>> K.shape, bool(abs(K - K.T).max() == 0)
    ((24, 24), True)
    """

    def __init__(
        self,
        elements: SpringElements,
        options: SpringOptions,
        backend: Backend = "numba",
        chunk: int = 65536,
    ):
        if backend not in ("numba", "numpy"):
            raise ValueError(f"backend {backend!r} is not one of numba, numpy")
        if not is_conservative(options):
            raise ValueError(
                "SpringHessian needs conservative options (axial linear/quadratic/cubic, "
                "torsion off/energy, volume off/gradient, no damping, no LMS), got "
                f"axial={options.axial}, torsion={options.torsion}, "
                f"volume_form={options.volume_form if options.volume else 'off'}"
            )
        self.elements = elements
        self.options = options
        self.backend = backend
        self.chunk = max(int(chunk), 1)
        n = int(elements.n_points)
        self.shape = (3 * n, 3 * n)
        self._indptr, self._indices, index_map = csr_pattern(elements.tets, n)
        self._map = index_map.astype(self._indices.dtype)  # int32 unless nnz >= 2^31
        self._nnz = int(self._indices.size)
        self._k_volume: np.ndarray | None = None

    def set_volume_stiffness(self, k_volume: np.ndarray | None) -> None:
        """Use these volume constants ``(m,)`` from now on (``None``: ``elements.k_volume``)."""
        self._k_volume = None if k_volume is None else np.asarray(k_volume, dtype=float)

    def element_matrices(self, x: np.ndarray, k_volume: np.ndarray | None = None) -> np.ndarray:
        """Element stiffness matrices ``(m, 12, 12)`` at positions ``x`` ``(n, 3)``.

        Row/column ``3 i + a`` is component ``a`` of the element's vertex ``i``.
        """
        x = np.ascontiguousarray(x, dtype=float).reshape(-1, 3)
        return self._block(x, self._volume_constants(k_volume), 0, self.elements.n_elements)

    def matrix(self, x: np.ndarray, k_volume: np.ndarray | None = None) -> sp.csr_matrix:
        """Tangent stiffness ``K = -d forces / dx`` at ``x``, ``(3n, 3n)`` CSR, symmetric.

        Parameters
        ----------
        x
            Positions ``(n, 3)`` (or flat ``(3n,)``).
        k_volume
            Volume constants ``(m,)`` to use instead of the current ones.
        """
        x = np.ascontiguousarray(x, dtype=float).reshape(-1, 3)
        kv = self._volume_constants(k_volume)
        m = self.elements.n_elements
        data = None
        for lo in range(0, m, self.chunk):  # bounded memory: element matrices chunk by chunk
            hi = min(lo + self.chunk, m)
            Ke = self._block(x, kv, lo, hi)
            part = np.bincount(self._map[lo:hi].ravel(), weights=Ke.ravel(), minlength=self._nnz)
            data = part if data is None else data + part
        if data is None:
            data = np.zeros(self._nnz)
        K = sp.csr_matrix(
            (data, self._indices.copy(), self._indptr.copy()), shape=self.shape, copy=False
        )
        K.has_sorted_indices = True
        return K

    def _block(self, x: np.ndarray, kv: np.ndarray, lo: int, hi: int) -> np.ndarray:
        """Element matrices of elements ``lo:hi``, ``(hi - lo, 12, 12)``."""
        el, opts = self.elements, self.options
        sl = slice(lo, hi)
        tets, G, l0, c0 = el.tets[sl], np.ascontiguousarray(el.G[sl]), el.l0[sl], el.c0[sl]
        ka, kt, kv = el.k_axial[sl], el.k_torsion[sl], np.ascontiguousarray(kv[sl])
        if self.backend == "numpy":
            return _element_matrices_numpy(x, tets, G, l0, ka, kt, c0, kv, el.L0[sl], opts)
        out = np.empty((hi - lo, 12, 12))
        b2, b3 = polynomial_coefficients(opts)
        _element_matrices_numba(
            x, tets, G, l0, ka, kt, c0, kv, el.L0[sl], b2, b3, opts.torsion == "energy",
            bool(opts.volume), _PAIR_L, _PAIR_M, out,
        )  # fmt: skip
        return out

    def _volume_constants(self, k_volume: np.ndarray | None) -> np.ndarray:
        if not self.options.volume:
            return np.zeros(self.elements.n_elements)
        if k_volume is not None:
            return np.asarray(k_volume, dtype=float)
        if self._k_volume is not None:
            return self._k_volume
        return np.asarray(self.elements.k_volume, dtype=float)


def _element_matrices_numpy(
    x: np.ndarray,
    tets: np.ndarray,
    G: np.ndarray,
    l0: np.ndarray,
    ka: np.ndarray,
    kt: np.ndarray,
    c0: np.ndarray,
    kv: np.ndarray,
    L0: np.ndarray,
    options: SpringOptions,
) -> np.ndarray:
    """Vectorised reference for the element matrices ``(m, 12, 12)``."""
    X = x[tets]  # (m, 4, 3)
    m = X.shape[0]
    zeta = np.einsum("kil,kic->klc", G, X)  # zeta_l = sum_i G[k,i,l] x_i
    H = axis_hessian(zeta, l0, ka, kt, c0, options).reshape(m, 3, 27)  # [k, l, (a, q, b)]
    # K[i,a,j,b] = sum_{l,q} G[i,l] H[l,a,q,b] G[j,q]
    T = (G @ H).reshape(m, 4, 3, 3, 3)  # [k, i, a, q, b]
    T = T.transpose(0, 1, 2, 4, 3).reshape(m, 36, 3)  # [k, (i, a, b), q]
    K = (T @ G.transpose(0, 2, 1)).reshape(m, 4, 3, 3, 4)  # [k, i, a, b, j]
    K = K.transpose(0, 1, 2, 4, 3)  # [k, i, a, j, b]
    if options.volume:
        K = K + volume_hessian(X, L0, kv)
    K = K.reshape(m, 12, 12)
    return 0.5 * (K + K.transpose(0, 2, 1))  # exact symmetry despite rounding
