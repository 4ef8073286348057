"""Wall time per phase of a solve (assembly, factorisation, solve, line search, ...).

:class:`PhaseTimes` adds up the seconds spent inside each named phase; a solver times its
phases with it and reports :meth:`PhaseTimes.summary` in its result's ``info`` and, with
``-v``, :meth:`PhaseTimes.table` at the end.

Examples
--------
>>> times = PhaseTimes()
>>> with times("assembly"):
...     pass
>>> with times("assembly"):
...     pass
>>> times.counts["assembly"], sorted(times.summary())
(2, ['assembly', 'cpu_total', 'total'])
"""

from __future__ import annotations

import contextlib
import time
from collections import defaultdict
from collections.abc import Iterator

__all__ = ["PhaseTimes"]


class PhaseTimes:
    """Seconds and counts per phase; phases do not nest (an inner one is not subtracted).

    Attributes
    ----------
    seconds, cpu, counts
        Per phase name: wall seconds, CPU seconds of the process (all its threads: on a
        busy machine the steadier measure of work) and how often it ran.
    start, cpu_start
        ``time.perf_counter()`` and ``time.process_time()`` when created (for the totals).
    """

    def __init__(self) -> None:
        self.seconds: dict[str, float] = defaultdict(float)
        self.cpu: dict[str, float] = defaultdict(float)
        self.counts: dict[str, int] = defaultdict(int)
        self.start, self.cpu_start = time.perf_counter(), time.process_time()

    @contextlib.contextmanager
    def __call__(self, name: str) -> Iterator[None]:
        t0, c0 = time.perf_counter(), time.process_time()
        try:
            yield
        finally:
            self.seconds[name] += time.perf_counter() - t0
            self.cpu[name] += time.process_time() - c0
            self.counts[name] += 1

    def summary(self) -> dict[str, float]:
        """Wall seconds per phase, ``total`` (since creation) and ``cpu_total``."""
        out = {k: round(v, 4) for k, v in self.seconds.items()}
        out["total"] = round(time.perf_counter() - self.start, 4)
        out["cpu_total"] = round(time.process_time() - self.cpu_start, 4)
        return out

    def table(self) -> str:
        """One line per phase: wall and CPU seconds, share of the wall total, count."""
        total = time.perf_counter() - self.start
        cpu_total = time.process_time() - self.cpu_start
        lines = [f"{'phase':<14}{'wall s':>9}{'cpu s':>9}{'share':>8}{'count':>7}"]
        for name, sec in sorted(self.seconds.items(), key=lambda kv: -kv[1]):
            share = sec / total if total > 0 else 0.0
            row = f"{name:<14}{sec:9.3f}{self.cpu[name]:9.3f}{share:8.1%}"
            lines.append(row + f"{self.counts[name]:7d}")
        other, other_cpu = total - sum(self.seconds.values()), cpu_total - sum(self.cpu.values())
        lines.append(
            f"{'other':<14}{other:9.3f}{other_cpu:9.3f}{other / total if total else 0:8.1%}"
        )
        lines.append(f"{'total':<14}{total:9.3f}{cpu_total:9.3f}")
        return "\n".join(lines)
