"""MKL PARDISO (Schenk & Gärtner 2004, Future Gener. Comput. Syst. 20) through the MKL
runtime that the ``pypardiso`` package installs, called with ``ctypes``.

:class:`Pardiso` keeps one handle per sparsity pattern: :meth:`Pardiso.analyse` (ordering
and symbolic factorisation, phase 11) once, :meth:`Pardiso.factor` (numeric, phase 22)
for every matrix of that pattern, :meth:`Pardiso.solve` (phase 33, with PARDISO's
iterative refinement) for every right-hand side. A symmetric matrix is given by its upper
triangle (matrix type -2, symmetric indefinite, Bunch–Kaufman pivoting with weighted
matching, which the saddle points of mixed u–p formulations need); an unsymmetric one in
full (type 11). ``ctypes`` releases the GIL during the call, so another thread (a
watchdog, :mod:`.limits`) keeps running while PARDISO works.

:func:`available` tells whether the runtime can be loaded; without it the one linear
solver (:mod:`.linsolve`) uses SuperLU.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> if available():
...     A = sp.csr_matrix(np.array([[4.0, 1.0, 0.0], [1.0, 0.0, 2.0], [0.0, 2.0, -3.0]]))
...     p = Pardiso(symmetric=True)
...     p.analyse(sp.triu(A, format="csr"))
...     p.factor(sp.triu(A, format="csr").data)
...     x = p.solve(np.array([1.0, 2.0, 3.0]))
...     ok = bool(np.allclose(A @ x, [1.0, 2.0, 3.0], rtol=0, atol=1e-12))
...     w = np.linalg.eigvalsh(A.toarray())
...     same = p.inertia == (int((w > 0).sum()), int((w < 0).sum()))  # (positive, negative)
... else:
...     ok, same = True, True
>>> ok, same
(True, True)
"""

from __future__ import annotations

import ctypes
import functools
import os
import sys
import threading
import weakref

import numpy as np
import scipy.sparse as sp

from .limits import abandoned_calls

__all__ = ["Pardiso", "PardisoError", "available", "set_threads"]

_I32 = ctypes.POINTER(ctypes.c_int32)
_F64 = ctypes.POINTER(ctypes.c_double)
#: PARDISO error codes (the reference manual's ``error`` argument).
_ERRORS = {
    -1: "input inconsistent", -2: "not enough memory", -3: "reordering problem",
    -4: "zero pivot, numerical factorization or iterative refinement problem",
    -5: "unclassified (internal) error", -6: "reordering failed",
    -7: "diagonal matrix is singular", -8: "32-bit integer overflow",
    -9: "not enough memory for OOC", -10: "error opening OOC files",
    -11: "read/write error with OOC files",
}  # fmt: skip
_LOCK = threading.Lock()  # the thread count is process-wide: set it and call under one lock


class PardisoError(RuntimeError):
    """A PARDISO call returned an error code (its message names it, :attr:`code` is it)."""

    def __init__(self, message: str, code: int = 0):
        super().__init__(message)
        self.code = code


@functools.cache
def _runtime():
    """The ``pardiso`` and ``MKL_Set_Num_Threads`` entry points, or ``None``."""
    if os.environ.get("SPRINGFEM_NO_PARDISO"):
        return None
    try:
        import pypardiso

        lib = pypardiso.PyPardisoSolver().libmkl
    except (ImportError, OSError, AttributeError):  # no package, or no MKL runtime
        print(
            "note: MKL PARDISO (pip install pypardiso) is not available: the direct solver "
            "falls back to SuperLU, several times slower on the FEM's systems",
            file=sys.stderr,
        )
        return None
    fn = lib.pardiso
    fn.restype = None
    fn.argtypes = [ctypes.POINTER(ctypes.c_int64)] + [_I32] * 5 + [_F64, _I32, _I32, _I32]
    fn.argtypes += [_I32, _I32, _I32, _F64, _F64, _I32]
    threads = lib.MKL_Set_Num_Threads
    threads.argtypes, threads.restype = [ctypes.c_int], None
    return fn, threads


def available() -> bool:
    """Whether MKL PARDISO can be called (``pypardiso`` and its MKL runtime installed).

    Returns
    -------
    bool
        ``False`` without the package, or with the environment variable
        ``SPRINGFEM_NO_PARDISO`` set (to run the SuperLU path on a machine that has it).
    """
    return _runtime() is not None


_THREADS = [1]


def set_threads(n: int) -> None:
    """Threads of the PARDISO calls that follow (MKL's thread count during each call).

    Parameters
    ----------
    n
        Number of threads, at least 1.
    """
    _THREADS[0] = max(1, int(n))


def _release(pt: np.ndarray, mtype: int, n: int) -> None:
    """Free PARDISO's memory of the handle ``pt`` (phase -1)."""
    rt = _runtime()
    if rt is None or not pt.any() or abandoned_calls():
        return  # an abandoned factorisation may still be using PARDISO's memory: keep it
    err = ctypes.c_int32(0)
    dummy_i, dummy_f = np.zeros(1, np.int32), np.zeros(1)
    iparm = np.zeros(64, np.int32)
    iparm[0], iparm[34] = 1, 1
    rt[0](
        pt.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)),
        *(ctypes.byref(ctypes.c_int32(v)) for v in (1, 1, mtype, -1, n)),
        dummy_f.ctypes.data_as(_F64), dummy_i.ctypes.data_as(_I32),
        dummy_i.ctypes.data_as(_I32), dummy_i.ctypes.data_as(_I32),
        ctypes.byref(ctypes.c_int32(1)), iparm.ctypes.data_as(_I32),
        ctypes.byref(ctypes.c_int32(0)), dummy_f.ctypes.data_as(_F64),
        dummy_f.ctypes.data_as(_F64), ctypes.byref(err),
    )  # fmt: skip
    pt[:] = 0


class Pardiso:
    """One PARDISO handle: a sparsity pattern analysed once, factorised many times.

    Parameters
    ----------
    symmetric
        Symmetric (give the upper triangle, matrix type -2) or unsymmetric (type 11).

    Attributes
    ----------
    n
        Order of the analysed matrix (0 before :meth:`analyse`).
    memory
        Bytes the numeric factorisation will need, from the analysis (:meth:`peak_kb`).
    perturbed
        Pivots PARDISO perturbed in the last factorisation (their effect is removed by the
        iterative refinement of :meth:`solve`, whose residual the caller checks).
    inertia
        ``(positive, negative)`` eigenvalue counts of the last symmetric factorisation.
    generation
        Factorisations done: a solve with an older factor (a :class:`DirectFactor
        <springfem.mechanics.direct.DirectFactor>` kept past the next :meth:`factor`) is
        refused.
    """

    def __init__(self, symmetric: bool):
        if _runtime() is None:
            raise PardisoError("MKL PARDISO is not available (pip install pypardiso)")
        self.symmetric = bool(symmetric)
        self.mtype = -2 if self.symmetric else 11
        self.pt = np.zeros(64, dtype=np.int64)
        self.iparm = np.zeros(64, dtype=np.int32)
        ip = self.iparm
        ip[0] = 1  # these settings, not the defaults
        ip[1] = 2  # METIS nested dissection
        ip[7] = 0  # PARDISO refines (two steps) only after perturbed pivots; the caller too
        ip[9] = 8 if self.symmetric else 13  # pivot perturbation 1e-8 / 1e-13
        ip[10] = 1  # symmetric scaling ...
        ip[12] = 1  # ... with weighted matching (saddle points)
        ip[34] = 1  # zero-based indices
        self.n = 0
        self.memory = 0  # bytes the factorisation needs (phase 11's report)
        self.perturbed = 0
        self.inertia = (0, 0)
        self.generation = 0
        self._ia = self._ja = np.zeros(0, np.int32)  # set by analyse
        self._data = np.zeros(0)
        self._factored = False
        self._finalizer = weakref.finalize(self, _release, self.pt, self.mtype, 0)

    def _call(self, phase: int, b: np.ndarray | None = None) -> np.ndarray:
        fn, set_threads_ = _runtime()
        n = self.n
        nrhs = 1 if b is None or b.ndim == 1 else b.shape[1]
        rhs = np.zeros(n) if b is None else np.asfortranarray(b, dtype=float)
        x = np.zeros_like(rhs)
        err = ctypes.c_int32(0)
        perm = np.zeros(1, np.int32)
        with _LOCK:
            set_threads_(_THREADS[0])
            fn(
                self.pt.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)),
                *(ctypes.byref(ctypes.c_int32(v)) for v in (1, 1, self.mtype, phase, n)),
                self._data.ctypes.data_as(_F64), self._ia.ctypes.data_as(_I32),
                self._ja.ctypes.data_as(_I32), perm.ctypes.data_as(_I32),
                ctypes.byref(ctypes.c_int32(nrhs)), self.iparm.ctypes.data_as(_I32),
                ctypes.byref(ctypes.c_int32(0)), rhs.ctypes.data_as(_F64),
                x.ctypes.data_as(_F64), ctypes.byref(err),
            )  # fmt: skip
        if err.value != 0:
            msg = f"PARDISO phase {phase}: {_ERRORS.get(err.value, err.value)}"
            raise PardisoError(msg, err.value)
        return np.ascontiguousarray(x)

    def analyse(self, A: sp.csr_matrix) -> None:
        """Ordering and symbolic factorisation of ``A``'s pattern (and its values, which
        the weighted matching reads).

        Parameters
        ----------
        A
            Square CSR matrix with sorted indices: the upper triangle (diagonal included,
            every diagonal entry stored) when ``symmetric``.
        """
        self.release()
        self.n = A.shape[0]
        self._ia = np.ascontiguousarray(A.indptr, dtype=np.int32)
        self._ja = np.ascontiguousarray(A.indices, dtype=np.int32)
        self._data = np.ascontiguousarray(A.data, dtype=float)
        self._finalizer.detach()
        self._finalizer = weakref.finalize(self, _release, self.pt, self.mtype, self.n)
        self.iparm[17] = -1  # report the factor's nonzeros ...
        self.iparm[18] = -1  # ... and its MFLOP
        self._call(11)
        self.memory = self.peak_kb() * 1024

    def peak_kb(self) -> int:
        """PARDISO's peak memory (KB) of the factorisation, ``max(iparm(15), iparm(16) +
        iparm(17))`` of the reference manual (symbolic phase, permanent, numeric)."""
        ip = self.iparm
        return int(max(int(ip[14]), int(ip[15]) + int(ip[16])))

    @property
    def factor_nnz(self) -> int:
        """Nonzeros of the factor (after :meth:`analyse`: predicted; after :meth:`factor`:
        actual)."""
        return int(self.iparm[17])

    @property
    def flops(self) -> float:
        """Floating-point operations of the numeric factorisation (after :meth:`analyse`)."""
        return 1e6 * float(self.iparm[18])

    def factor(self, data: np.ndarray) -> None:
        """Numeric factorisation of the analysed pattern with values ``data``.

        Parameters
        ----------
        data
            The matrix's values in the order of the analysed CSR pattern.

        Raises
        ------
        PardisoError
            A failed factorisation (e.g. a zero pivot).
        """
        self._factored = False
        self.generation += 1
        self._data = np.ascontiguousarray(data, dtype=float)
        self._call(22)
        self._factored = True
        self.perturbed = int(self.iparm[13])
        self.inertia = (int(self.iparm[21]), int(self.iparm[22]))

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Solve with the last factorisation (PARDISO's iterative refinement included).

        Parameters
        ----------
        b
            Right-hand side ``(n,)`` or ``(n, k)``.

        Returns
        -------
        numpy.ndarray
            The solution, shaped like ``b``.
        """
        if not self._factored:
            raise PardisoError("PARDISO solve before a successful factorisation")
        return self._call(33, np.asarray(b, dtype=float))

    def release(self) -> None:
        """Free PARDISO's memory (the handle can analyse a new pattern afterwards)."""
        _release(self.pt, self.mtype, self.n)
        self._factored = False
