"""Timing rules of the benchmarks: interleaved rounds, medians, per-round ratios, limits.

A shared, noisy machine changes speed from second to second, so cases timed in separate
blocks compare different machines. Here every case runs once in every round, in a shuffled
order; a case's figure is the median over rounds of its wall and CPU time, and a ratio of
two cases is the median of their per-round ratios (both measured within seconds of each
other). The bandwidth-bound limit of a kernel is a measured stream bandwidth divided by
the bytes it must read per element.

Examples
--------
>>> fake = iter([0.0, 1.0, 1.0, 3.0] * 4)  # case times 1 and 2 in every round
>>> res = interleaved({"a": lambda: None, "b": lambda: None}, rounds=2,
...                   clock=lambda: next(fake), cpu_clock=lambda: 0.0, seed=None)
>>> res["a"]["wall"], res["b"]["wall"]
([1.0, 1.0], [2.0, 2.0])
>>> median_ratio(res, "b", "a")
2.0
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable

import numpy as np


def interleaved(
    cases: dict[str, Callable[[], object]],
    rounds: int = 7,
    count: int = 1,
    warmup: int = 1,
    seed: int | None = 0,
    clock: Callable[[], float] = time.perf_counter,
    cpu_clock: Callable[[], float] = time.process_time,
) -> dict[str, dict[str, list[float]]]:
    """Time every case once per round, rounds in shuffled order.

    Parameters
    ----------
    cases
        Name -> function to time.
    rounds
        Number of rounds (each case is timed once in each).
    count
        Calls per timing (the time is divided by it).
    warmup
        Untimed calls of every case first (compilation, caches).
    seed
        Seed of the order shuffle; ``None`` keeps the given order (tests).
    clock, cpu_clock
        Wall and CPU clocks (injectable for tests).

    Returns
    -------
    dict
        ``{name: {"wall": [...], "cpu": [...], "order": [...]}}`` per round; ``order`` is the
        case's position in each round.
    """
    names = list(cases)
    for _ in range(warmup):
        for name in names:
            cases[name]()
    rng = np.random.default_rng(seed) if seed is not None else None
    out = {n: {"wall": [], "cpu": [], "order": []} for n in names}
    for _ in range(rounds):
        order = list(rng.permutation(names)) if rng is not None else names
        for pos, name in enumerate(order):
            fn = cases[name]
            w0, c0 = clock(), cpu_clock()
            for _ in range(count):
                fn()
            w1, c1 = clock(), cpu_clock()
            out[name]["wall"].append((w1 - w0) / count)
            out[name]["cpu"].append((c1 - c0) / count)
            out[name]["order"].append(pos)
    return out


def timed(cases: dict[str, Callable[[], object]], rounds: int = 7, warmup: int = 1):
    """:func:`interleaved` timings of ``cases`` and the :func:`machine` they ran on (the load
    average before and after): every benchmark's one timing path.

    Returns
    -------
    tuple
        The samples and the machine.
    """
    before = load_average()
    samples = interleaved(cases, rounds=rounds, warmup=warmup)
    return samples, machine(before)


def median(samples: dict, name: str, kind: str = "wall") -> float:
    """Median over rounds of one case's ``wall`` or ``cpu`` time."""
    return float(np.median(samples[name][kind]))


def median_ratio(samples: dict, num: str, den: str, kind: str = "wall") -> float:
    """Median over rounds of ``time(num) / time(den)`` (both timed in the same round)."""
    a = np.asarray(samples[num][kind], dtype=float)
    b = np.asarray(samples[den][kind], dtype=float)
    return float(np.median(a / b))


def median_difference(samples: dict, a: str, b: str, kind: str = "wall") -> float:
    """Median over rounds of ``time(a) - time(b)`` (both timed in the same round)."""
    x = np.asarray(samples[a][kind], dtype=float) - np.asarray(samples[b][kind], dtype=float)
    return float(np.median(x))


def stream_bandwidth(megabytes: int = 256, repeats: int = 5) -> float:
    """Read bandwidth in bytes/s: the best of ``repeats`` numpy reductions of a large array.

    A sum reads every byte once and writes nothing, as a force kernel streams its constants.
    """
    a = np.ones(megabytes * (1 << 20) // 8)
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        a.sum()
        best = min(best, time.perf_counter() - t0)
    return a.nbytes / best


def load_average() -> list[float]:
    """The machine's 1, 5 and 15 minute load averages (``os.getloadavg``)."""
    return [round(v, 2) for v in os.getloadavg()]


def machine(load_before: list[float] | None = None) -> dict:
    """Threads, numba threading layer and load average: the context of every timing (with
    ``load_before``, also the load averages before and after the timing)."""
    import numba

    try:
        layer = numba.threading_layer()
    except ValueError:  # no parallel function has run yet
        layer = "not initialised"
    out = {
        "cpus": os.cpu_count(),
        "numba_threads": numba.get_num_threads(),
        "threading_layer": layer,
        "omp_wait_policy": os.environ.get("OMP_WAIT_POLICY", "default"),
        "load_average": load_average(),
    }
    if load_before is not None:
        out["load_average_before"], out["load_average_after"] = load_before, load_average()
    return out


def deformed_state(points: np.ndarray, seed: int = 0) -> np.ndarray:
    """A deformed state to time force passes at: a smooth stretch plus noise of 1 % of the
    mesh spacing."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    h = float(np.min(hi - lo)) / max(2.0, round((points.shape[0]) ** (1 / 3)))
    rng = np.random.default_rng(seed)
    x = points * np.array([1.02, 0.99, 0.995])
    return x + 0.01 * h * rng.standard_normal(points.shape)
