"""Blocked structure-of-arrays element layout and the drivers that run a block kernel.

Both models' force kernels (the spring kernels of :mod:`springmodel.fastkernels` and the
explicit FEM's of :mod:`reference_fem.explicit_kernels`) use this layout and these drivers.
Elements are stored in blocks of :data:`BLOCK`: connectivity ``T (nb, 4 B)`` int32 and
constants ``K (nb, ncol B)``, row ``b`` holding block ``b`` lane-major (``K[b, c B + j]``).
A kernel's block loop gathers a block's edge vectors
``x_i - x_0`` (differences taken in float64, then stored in the arithmetic type) into a flat
``9 B`` scratch, computes the lanes in one loop with no gathers and no branches (LLVM
vectorises it), and adds the ``12 B`` vertex forces into the nodal array (the only scattered
writes, in a scalar loop: two lanes may share a node). The last block is padded with copies
of the last element; its padded lanes are computed but never scattered.

Parallel passes split the blocks into one static contiguous chunk per thread, each adding
into its own force buffer, summed in chunk order (deterministic for a given number of
threads; equal to the serial pass to round-off).

Examples
--------
>>> T, K = block_layout(np.array([[0, 1, 2, 3]]), np.ones((2, 1)), np.float64)
>>> T.shape, K.shape, T.dtype.name
((1, 64), (1, 32), 'int32')
"""

from __future__ import annotations

import hashlib
from typing import Any

import numba
import numpy as np
from numba import njit, prange

#: Elements per block (two AVX-512 vectors of float64).
BLOCK = 16
_FLAGS: dict[str, Any] = {"error_model": "numpy", "fastmath": {"contract"}}


def block_layout(tets: np.ndarray, columns: np.ndarray, dtype) -> tuple[np.ndarray, np.ndarray]:
    """Blocked connectivity ``(nb, 4 B)`` int32 and constants ``(nb, ncol B)`` of ``dtype``.

    Parameters
    ----------
    tets
        ``(m, 4)`` node ids (``m >= 1``).
    columns
        ``(ncol, m)`` per-element constants.
    dtype
        Storage type of the constants (``float64`` or ``float32``).

    Returns
    -------
    T, K
        ``T[b, i B + j]`` is vertex ``i`` of lane ``j`` of block ``b``; ``K[b, c B + j]``
        its constant ``c``. The last block is padded with copies of the last element.
    """
    tets = np.asarray(tets)
    m = tets.shape[0]
    nb = -(-m // BLOCK)
    idx = np.minimum(np.arange(nb * BLOCK), m - 1)  # pad with the last element
    T = tets[idx].reshape(nb, BLOCK, 4).transpose(0, 2, 1).reshape(nb, 4 * BLOCK)
    cols = np.asarray(columns)[:, idx].reshape(-1, nb, BLOCK).transpose(1, 0, 2)
    K = np.ascontiguousarray(cols.reshape(nb, -1), dtype=dtype)
    return np.ascontiguousarray(T, dtype=np.int32), K


def set_column(K: np.ndarray, col: int, values: np.ndarray) -> None:
    """Overwrite constant ``col`` of every element, padded lanes included, in place.

    Parameters
    ----------
    K
        Blocked constants ``(nb, ncol B)`` (:func:`block_layout`).
    col
        The constant's column.
    values
        One value per element ``(m,)``, in element order; the padded lanes of the last
        block get the last element's value.

    Returns
    -------
    None

    Examples
    --------
    >>> T, K = block_layout(np.array([[0, 1, 2, 3]] * 2), np.zeros((1, 2)), np.float64)
    >>> set_column(K, 0, np.array([1.0, 2.0]))
    >>> K[0, :4].tolist()  # element 0, element 1, then padding copies of element 1
    [1.0, 2.0, 2.0, 2.0]
    """
    m = values.shape[0]
    nb = K.shape[0]
    idx = np.minimum(np.arange(nb * BLOCK), m - 1)
    K[:, col * BLOCK : (col + 1) * BLOCK] = np.asarray(values)[idx].reshape(nb, BLOCK)


def chunks(n_blocks: int, n_threads: int | None = None) -> np.ndarray:
    """Static contiguous block ranges, one per thread.

    Parameters
    ----------
    n_blocks
        Number of element blocks.
    n_threads
        Threads to split over (default: numba's thread count); at most ``n_blocks`` chunks.

    Returns
    -------
    ndarray
        ``ptr`` ``(n_chunks + 1,)`` int64: chunk ``c`` runs over blocks
        ``ptr[c]:ptr[c+1]``.

    Examples
    --------
    >>> chunks(10, 3).tolist()
    [0, 3, 7, 10]
    """
    n = max(1, min(n_threads or numba.get_num_threads(), n_blocks))
    return np.linspace(0, n_blocks, n + 1).round().astype(np.int64)


def variant_id(variant) -> str:
    """A short stable id of a kernel variant (its repr hashed), for symbol and cache names.

    Parameters
    ----------
    variant
        Any object whose ``repr`` names every compile-time choice (a frozen dataclass).

    Returns
    -------
    str
        12 hex digits.
    """
    return hashlib.sha256(repr(variant).encode()).hexdigest()[:12]


def compile_named(py_func, name: str, cache: bool = True):
    """``njit(cache=cache)`` of a kernel closure under its own unique name.

    Every variant's block loop is a closure of the same factory, so all would share one
    qualified name. numba names a compiled function's symbol by its qualified name, a
    counter of the functions compiled so far *in the process that compiled it*, and the
    argument types; a cached entry keeps the counter of the process that wrote it, so two
    variants cached by two processes that had compiled the same number of functions (two
    pytest-xdist workers, say) carry the same symbol. A process that loads both and then
    compiles a parallel driver (never cached) links the block loop by that symbol and gets
    the definition loaded last: the driver runs another variant's code, reading its
    constant columns (wrong forces; past the end of ``K`` in the last block: garbage in the
    last rows), while the serial driver, which calls its own dispatcher, stays right. A
    name per variant keeps the symbols (and cache files) apart; reusing a name for other
    code is refused.

    Parameters
    ----------
    py_func
        The Python function of the block loop.
    name
        A valid identifier unique to the variant (the same name may be compiled again only
        for the same code and captured values).
    cache
        Cache the compiled code on disk (numba's ``cache``).

    Returns
    -------
    numba dispatcher

    Raises
    ------
    ValueError
        If ``name`` was already given to a function of other code or captured values.

    Examples
    --------
    >>> def factory(c):
    ...     def run(a):
    ...         return c * a
    ...     return run
    >>> compile_named(factory(2.0), "doubled", cache=False)(3.0)
    6.0
    >>> compile_named(factory(3.0), "doubled", cache=False)
    Traceback (most recent call last):
    ...
    ValueError: kernel name 'doubled' is already used by other code or captured values
    """
    key = _fingerprint(py_func)
    if _NAMES.setdefault(name, key) != key:
        raise ValueError(f"kernel name {name!r} is already used by other code or captured values")
    py_func.__name__ = py_func.__qualname__ = name
    return njit(cache=cache, **_FLAGS)(py_func)


#: name -> fingerprint of the code and captured values compiled under it (:func:`compile_named`)
_NAMES: dict[str, str] = {}


def _fingerprint(py_func) -> str:
    """Hash of a function's code and of its captured values (their ``repr``)."""
    code = py_func.__code__
    cells = tuple(c.cell_contents for c in py_func.__closure__ or ())
    text = repr((code.co_code, code.co_consts, code.co_names, cells))
    return hashlib.sha256(text.encode()).hexdigest()


def block_drivers(run):
    """Serial and parallel drivers around a variant's block loop.

    Parameters
    ----------
    run
        numba function ``run(lo, hi, x, w, T, K, m, p, q, out) -> int`` adding the forces of
        blocks ``lo..hi`` into ``out`` and returning a count (e.g. of inverted elements);
        ``w`` (velocities) and the scalars ``p``, ``q`` are the kernel's own inputs.

    Returns
    -------
    serial, parallel
        ``serial(x, w, T, K, m, p, q, out)`` and
        ``parallel(x, w, T, K, m, p, q, ptr, buf, out)``; both overwrite ``out (n, 3)``
        float64 with the nodal forces and return the summed count.
    """

    def serial(x, w, T, K, m, p, q, out):
        out[:] = 0.0
        return run(0, T.shape[0], x, w, T, K, m, p, q, out)

    def parallel(x, w, T, K, m, p, q, ptr, buf, out):
        nchunk = ptr.shape[0] - 1
        count = 0
        for t in prange(nchunk):  # one buffer per static chunk: deterministic
            bt = buf[t]
            bt[:] = 0.0
            count += run(ptr[t], ptr[t + 1], x, w, T, K, m, p, q, bt)
        n = out.shape[0]
        for i in prange(n):
            for d in range(3):
                s = 0.0
                for t in range(nchunk):
                    s += buf[t, i, d]
                out[i, d] = s
        return count

    parallel.__name__ = parallel.__qualname__ = f"parallel_{run.__name__}"
    return serial, njit(parallel=True, **_FLAGS)(parallel)
