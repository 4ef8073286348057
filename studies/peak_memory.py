"""The peak resident memory of one piece of work in this process, beside its wall time.

A process's high-water mark (``ru_maxrss``) only grows, so it tells one solve's peak only
when that solve set a new mark. :class:`PeakMemory` therefore reads both: the high-water mark
before and after, and the resident size sampled every :data:`INTERVAL` seconds by a thread
in between (the solvers' compiled code and PARDISO release the interpreter's lock, so the
sampler runs while they work). The peak is the new high-water mark when the work set one,
else the largest sample.

Examples
--------
>>> import numpy as np
>>> with PeakMemory() as pm:
...     a = np.ones(40_000_000)  # 320 MB, touched
...     del a
>>> pm.peak > 300e6, pm.grew > 250e6
(True, True)
"""

from __future__ import annotations

import resource
import threading
import time

from springfem.mechanics.memory import resident_bytes

#: Seconds between samples of the resident size.
INTERVAL = 0.02


def high_water_bytes() -> int:
    """The process's peak resident size so far (bytes)."""
    return int(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss) * 1024


class PeakMemory:
    """Context manager: the peak resident size while its block runs.

    Attributes
    ----------
    start
        Resident bytes when the block started.
    peak
        Peak resident bytes during the block.
    grew
        ``peak - start``: what the block added at its peak.
    """

    def __init__(self, interval: float = INTERVAL) -> None:
        self.interval = interval
        self.start = self.peak = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def _sample(self) -> None:
        while not self._stop.wait(self.interval):
            self.peak = max(self.peak, resident_bytes())

    def __enter__(self) -> PeakMemory:
        self.start = self.peak = resident_bytes()
        self._mark = high_water_bytes()
        self._thread = threading.Thread(target=self._sample, daemon=True)
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        self.peak = max(self.peak, resident_bytes())
        mark = high_water_bytes()
        if mark > self._mark:  # this block set a new high-water mark: that is its peak
            self.peak = max(self.peak, mark)

    @property
    def grew(self) -> int:
        return max(self.peak - self.start, 0)


def measure(fn, *args, **kwargs):
    """``(fn(*args, **kwargs), seconds, peak bytes)``.

    Parameters
    ----------
    fn
        The work.
    *args, **kwargs
        Its arguments.

    Returns
    -------
    tuple
    """
    with PeakMemory() as pm:
        t = time.perf_counter()
        out = fn(*args, **kwargs)
        seconds = time.perf_counter() - t
    return out, seconds, pm.peak
