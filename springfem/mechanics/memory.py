"""How much memory a solve may use, and what a sparse factorisation or an iterative solve
will need: the linear solver (:mod:`.linsolve`) factorises only what fits, solves
iteratively otherwise, and refuses (:class:`MemoryLimitExceeded`, exit code 3) a solve
that fits neither way before it starts.

The limit (:func:`memory_limit`) is the smallest of

- ``SPRINGFEM_MAX_MEMORY`` (bytes, or with a suffix ``K``, ``M``, ``G``: ``"8G"``);
- :func:`~springfem.mechanics.limits.solve_limits`'s ``max_memory``;
- :data:`AVAILABLE_SHARE` of the machine's available memory (``MemAvailable`` of
  ``/proc/meminfo``) plus what this process already holds (its resident set: the solve's
  own arrays are part of the budget, not a claim on it);
- the address-space limit (``ulimit -v``, ``prlimit --as``) less what is mapped already.

Estimates: a PARDISO factor's bytes are what its symbolic analysis (phase 11) reports
(:attr:`~springfem.mechanics.pardiso.Pardiso.memory`); before that analysis (and for
SuperLU) :func:`factor_bytes_law` gives a law measured on the Taylor–Hood tangents of the
liver-shaped organ (:mod:`springfem.mesh.organ`): 138 MB at 24,651 DOFs (4,781 tets) and
1.44 GB at 136,837 DOFs (30k tets), so ``bytes ~ n^1.37`` (nested dissection in 3-D
predicts ``n^{4/3}``). An iterative solve keeps the matrix, its symmetric elimination, a
smoothed-aggregation hierarchy and the Krylov basis: :func:`iterative_bytes`.

Examples
--------
>>> parse_bytes("8G"), parse_bytes("512M"), parse_bytes("1000")
(8589934592, 536870912, 1000)
>>> factor_bytes_law(24_651) / 1e6  # the measured point
138.0
"""

from __future__ import annotations

import os
import resource

from springfem.errors import InputError, SpringFemError

from .limits import LIMITS

__all__ = [
    "AVAILABLE_SHARE", "MemoryLimitExceeded", "factor_bytes_law", "gb", "iterative_bytes",
    "memory_limit", "parse_bytes", "resident_bytes",
]  # fmt: skip

#: Share of the machine's available memory a solve may take (others run beside it).
AVAILABLE_SHARE = 0.8
#: The factor law: bytes at :data:`LAW_DOFS` unknowns and its exponent (module docstring).
LAW_BYTES, LAW_DOFS, LAW_EXPONENT = 138e6, 24_651, 1.37
#: Bytes per stored matrix entry an iterative solve holds (matrix copies, hierarchy, the
#: elimination): measured peak of the Krylov phase over the tangent's nonzeros.
ITERATIVE_BYTES_PER_NNZ = 60.0
#: Krylov basis vectors kept (GMRES restart length), each ``8 n`` bytes.
KRYLOV_VECTORS = 100


class MemoryLimitExceeded(SpringFemError):
    """A solve that does not fit the memory limit either way (exit code 3).

    Raised before the solve (or the factorisation) starts; not a
    :class:`~springfem.errors.SolverError`, so Newton does not retry it with a smaller
    load step.
    """

    exit_code = 3


_SUFFIX = {"K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}


def parse_bytes(text: str | float | int) -> int:
    """Bytes from ``"8G"``, ``"512M"``, ``"1.5G"`` or a number.

    Raises
    ------
    InputError
        Not a size.
    """
    s = str(text).strip().upper().removesuffix("B").removesuffix("I")
    scale = 1
    if s and s[-1] in _SUFFIX:
        s, scale = s[:-1], _SUFFIX[s[-1]]
    try:
        value = float(s) * scale
    except ValueError:
        raise InputError(f"not a memory size: {text!r} (e.g. 8G, 512M, bytes)") from None
    if not value > 0:
        raise InputError(f"not a memory size: {text!r} (must be positive)")
    return int(value)


def _meminfo() -> dict[str, int]:
    out: dict[str, int] = {}
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                key, _, rest = line.partition(":")
                out[key] = int(rest.split()[0]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return out


def _self_status() -> dict[str, int]:
    out: dict[str, int] = {}
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                key, _, rest = line.partition(":")
                if key in ("VmRSS", "VmSize"):
                    out[key] = int(rest.split()[0]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return out


def memory_limit() -> float:
    """Bytes the solve may hold at its peak (``inf`` when nothing can be read).

    Returns
    -------
    float
        The smallest of the limits of the module docstring.
    """
    limits = [float("inf")]
    env = os.environ.get("SPRINGFEM_MAX_MEMORY")
    if env:
        limits.append(float(parse_bytes(env)))
    if LIMITS.get("max_memory") is not None:
        limits.append(float(LIMITS["max_memory"]))  # type: ignore[arg-type]
    info, status = _meminfo(), _self_status()
    if "MemAvailable" in info:
        limits.append(AVAILABLE_SHARE * info["MemAvailable"] + status.get("VmRSS", 0))
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft != resource.RLIM_INFINITY and soft > 0:
        room = soft - status.get("VmSize", 0)
        limits.append(status.get("VmRSS", 0) + AVAILABLE_SHARE * max(room, 0))
    return min(limits)


def gb(nbytes: float) -> str:
    """``"1.23 GB"``: bytes for messages."""
    return f"{nbytes / 1e9:.2f} GB"


def resident_bytes() -> int:
    """This process's resident set now (bytes; 0 when it cannot be read)."""
    return _self_status().get("VmRSS", 0)


def factor_bytes_law(n: int) -> float:
    """The measured law of a sparse LDL^T factor's bytes for ``n`` unknowns (3-D FEM).

    Parameters
    ----------
    n
        Order of the matrix.

    Returns
    -------
    float
        Bytes (the module docstring).
    """
    return LAW_BYTES * (max(n, 1) / LAW_DOFS) ** LAW_EXPONENT


def iterative_bytes(n: int, nnz: int) -> float:
    """Bytes an AMG-preconditioned Krylov solve holds beside the assembled matrix.

    Parameters
    ----------
    n, nnz
        Order and stored entries of the matrix.

    Returns
    -------
    float
        Bytes.
    """
    return ITERATIVE_BYTES_PER_NNZ * nnz + 8.0 * KRYLOV_VECTORS * n
