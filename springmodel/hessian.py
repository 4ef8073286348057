"""Analytic tangent stiffness ``K = d^2 U / dx^2`` of the conservative spring variants.

For the energy forms (axial ``linear``/``quadratic``/``cubic``, torsion
``off``/``energy``/``shear``, volume ``gradient``; see
:func:`springmodel.springs.spring_energy`) the spring forces are ``-grad U`` and
``K = -d forces / dx`` is the Hessian of

    U = sum_k [ sum_l f_l(|zeta_l|) + sum_(l,m) k_lm/2 (c_lm - c0_lm)^2 + k_s/2 (L - L0)^2 ],

``zeta_l = sum_i G[k,i,l] x_i`` (the fast-kernel identity,
docs/theory.rst#the-fast-kernel-identity), ``c_lm = zh_l . zh_m``
and ``L = sum_j |x_j - x_b|``. Per element:

axial, ``a = zeta_l``, ``f'(L) = k (d + b2 d^2/l0 + b3 d^3/l0^2)`` (eq. 2.36)
    ``d^2 f / da^2 = f'' ah ah^T + f'/|a| (I - ah ah^T)``.
torsion, ``a = zeta_l``, ``b = zeta_m``, ``A = |a|``, ``B = |b|``
    ``dc/da = (bh - c ah)/A``, ``d^2c/da^2 = -(ah g_a^T + g_a ah^T)/A - c (I - ah ah^T)/A^2``,
    ``d^2c/da db = (I - ah ah^T - bh bh^T + c ah bh^T)/(A B)``;
    ``U'' = k (grad c grad c^T + (c - c0) grad^2 c)``; for the ``shear`` law
    ``U = k phi(c)`` (:mod:`springmodel.springs.shear`)
    ``U'' = k (phi'' grad c grad c^T + phi' grad^2 c)``.
volume, ``r_j = |xi_j|``, ``xi_j = x_j - x_b``, ``d xi_j / d x_i = (delta_ij - 1/4) I``
    ``grad_i L = xh_i - mean_j xh_j``; with ``H_j = (I - xh_j xh_j^T)/r_j``,
    ``grad^2_ik L = delta_ik H_i - (H_i + H_k)/4 + sum_j H_j / 16``;
    ``U'' = k_s (grad L grad L^T + (L - L0) grad^2 L)``.
axis volume, ``V0 U(J)``, ``J = det[zeta_0 zeta_1 zeta_2] / det0``
    ``V0 (U''(J) gJ gJ^T + U'(J) d^2J)``, ``gJ_0 = zeta_1 x zeta_2 / det0`` (cyclic),
    ``d^2J / d zeta_l d zeta_m = E(zeta_n) / det0`` for ``(l, m, n)`` cyclic
    (``E[a, b] = eps_abc z_c``), transposed for ``(m, l)``.
Poisson coupling, ``c s_l s_m``, ``s_l = |zeta_l| / l_l - 1``
    ``c s_m (I - zh_l zh_l^T) / (l_l |zeta_l|)`` on ``(l, l)``, ``c zh_l zh_m^T / (l_l l_m)``
    on ``(l, m)``.

The axial, torsion, coupling and axis-volume parts are assembled as one 9x9 Hessian in the
three axis vectors and mapped to the 12 vertex DOFs with ``G`` (``d zeta_l / d x_i = G[k,i,l] I``).

The sparsity pattern (:mod:`springmodel.hessian_pattern`) is built once;
each call only computes the element matrices and sums them into ``csr.data`` through a
precomputed index map (a compiled serial scatter: 2-3x faster than ``np.bincount``, which
converts the map and allocates per call). The element matrices come from a numba
kernel (:mod:`springmodel.hessian_numba`, one pass per element, parallel over elements) or
from the vectorised numpy reference (:mod:`springmodel.hessian_numpy`, about 20x slower); the
tests check both.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import scipy.sparse as sp

from .elements import SpringElements
from .hessian_numba import _element_matrices_numba, _element_matrices_serial, _scatter_add
from .hessian_numpy import (
    _element_matrices_numpy,
    axis_hessian,
    axis_parts_hessian,
    polynomial_coefficients,
    volume_hessian,
)
from .hessian_pattern import csr_pattern
from .options import SpringOptions
from .rest_geometry import TORSION_PAIRS
from .springs import is_conservative

#: ``parallel=None`` runs the element matrices on all threads from this many elements up
#: (the force kernels' rule; measurement in :mod:`springmodel.hessian_numba`).
PARALLEL_MIN_ELEMENTS = 20_000
#: Axis-volume codes of :mod:`springmodel.hessian_numba` by volumetric energy.
AXIS_VOLUME_CODES = {"quadratic": 3, "log": 4, "simo-taylor": 5}
#: Torsion codes of :mod:`springmodel.hessian_numba` by (conservative) torsion law.
TORSION_CODES = {"off": 0, "energy": 1, "shear": 2}

__all__ = [
    "SpringHessian",
    "axis_hessian",
    "axis_parts_hessian",
    "csr_pattern",
    "polynomial_coefficients",
    "volume_hessian",
]

Backend = Literal["numba", "numpy"]
_PAIR_L = np.array([p[0] for p in TORSION_PAIRS], dtype=np.int64)
_PAIR_M = np.array([p[1] for p in TORSION_PAIRS], dtype=np.int64)


class SpringHessian:
    """Analytic tangent stiffness of the conservative spring variants.

    Parameters
    ----------
    elements
        Spring rest data; ``k_volume`` is read at every call (LMS may change it).
    options
        Must be conservative (:func:`springmodel.springs.is_conservative`): axial
        ``linear``/``quadratic``/``cubic``, torsion ``off``/``energy``/``shear``, volume off,
        ``gradient`` or ``"axes"``, coupling on or off. Damping and LMS do not enter ``K``
        (they make the options non-conservative and are refused).
    backend
        ``numba`` (default) or ``numpy`` (the vectorised reference) for the element matrices.
    chunk
        Elements per block when summing into the matrix (bounds the memory of the element
        matrices to ``chunk * 1152`` bytes).
    parallel
        Element matrices on all threads (``None``: from :data:`PARALLEL_MIN_ELEMENTS` up).

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
        parallel: bool | None = None,
    ):
        if backend not in ("numba", "numpy"):
            raise ValueError(f"backend {backend!r} is not one of numba, numpy")
        if not is_conservative(options):
            raise ValueError(
                "SpringHessian needs conservative options (axial linear/quadratic/cubic, "
                "torsion off/energy/shear, volume off/gradient, no damping, no LMS), got "
                f"axial={options.axial}, torsion={options.torsion}, "
                f"volume={options.volume}, volume_form={options.volume_form}"
            )
        self.elements = elements
        self.options = options
        self.backend = backend
        self.chunk = max(int(chunk), 1)
        if parallel is None:
            parallel = elements.n_elements >= PARALLEL_MIN_ELEMENTS
        self.parallel = bool(parallel)
        n = int(elements.n_points)
        self.shape = (3 * n, 3 * n)
        self._indptr, self._indices, index_map = csr_pattern(elements.tets, n)
        self._map = index_map.astype(self._indices.dtype)  # int32 unless nnz >= 2^31
        self._nnz = int(self._indices.size)
        self._k_volume: np.ndarray | None = None

    def set_volume_stiffness(self, k_volume: np.ndarray | None) -> None:
        """Use these volume constants ``(m,)`` from now on (``None``: ``elements.k_volume``)."""
        self._k_volume = None if k_volume is None else np.asarray(k_volume, dtype=float)

    def element_matrices(
        self,
        x: np.ndarray,
        k_volume: np.ndarray | None = None,
        lo: int = 0,
        hi: int | None = None,
    ) -> np.ndarray:
        """Element stiffness matrices ``(hi - lo, 12, 12)`` at positions ``x`` ``(n, 3)``.

        Row/column ``3 i + a`` is component ``a`` of the element's vertex ``i``; ``lo:hi``
        selects elements (default all).
        """
        x = np.ascontiguousarray(x, dtype=float).reshape(-1, 3)
        hi = self.elements.n_elements if hi is None else hi
        return self._block(x, self._volume_constants(k_volume), lo, hi)

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
        data = np.zeros(self._nnz)
        for lo in range(0, m, self.chunk):  # bounded memory: element matrices chunk by chunk
            hi = min(lo + self.chunk, m)
            _scatter_add(data, self._map[lo:hi], self._block(x, kv, lo, hi))
        K = sp.csr_matrix(
            (data, self._indices.copy(), self._indptr.copy()), shape=self.shape, copy=False
        )
        K.has_sorted_indices = True
        return K

    def assemble(self, blocks) -> sp.csr_matrix:
        """Sum element matrices into the ``(3n, 3n)`` CSR matrix of this pattern.

        Parameters
        ----------
        blocks
            ``(m, 12, 12)`` matrices of all elements in their order (rows as
            :meth:`element_matrices`), or a list of ``(lo, Ke)``: the matrices of elements
            ``lo:lo + len(Ke)`` (chunks bound the memory).

        Returns
        -------
        scipy.sparse.csr_matrix
            ``sum_e`` of the element matrices on each element's 12 DOFs.
        """
        if isinstance(blocks, np.ndarray):
            blocks = [(0, blocks)]
        data = np.zeros(self._nnz)
        for lo, Ke in blocks:
            Ke = np.ascontiguousarray(Ke, dtype=float)
            _scatter_add(data, self._map[lo : lo + Ke.shape[0]], Ke)
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
        parts = (
            np.ascontiguousarray(el.k_coupling[sl]),
            np.ascontiguousarray(el.k_axis_volume[sl] * el.V0[sl]),
            np.ascontiguousarray(1.0 / el.det0[sl]),
        )
        if self.backend == "numpy":
            return _element_matrices_numpy(x, tets, G, l0, ka, kt, c0, kv, el.L0[sl], opts, parts)
        out = np.empty((hi - lo, 12, 12))
        b2, b3 = polynomial_coefficients(opts)
        axes = AXIS_VOLUME_CODES[opts.volumetric] if opts.axis_volume else 0
        kernel = _element_matrices_numba if self.parallel else _element_matrices_serial
        kernel(
            x, tets, G, l0, ka, kt, c0, kv, el.L0[sl], b2, b3, TORSION_CODES[opts.torsion],
            opts.barycentric_volume, _PAIR_L, _PAIR_M, bool(opts.coupling), axes, *parts, out,
        )  # fmt: skip
        return out

    def _volume_constants(self, k_volume: np.ndarray | None) -> np.ndarray:
        if not self.options.barycentric_volume:
            return np.zeros(self.elements.n_elements)
        if k_volume is not None:
            return np.asarray(k_volume, dtype=float)
        if self._k_volume is not None:
            return self._k_volume
        return np.asarray(self.elements.k_volume, dtype=float)
