"""A study's time budget, its plan line, and each case run with its cap and its warnings counted.

A study runs its cases through :meth:`studies.cache.CaseCache.run`; this module is what that
call does around each case:

- :class:`Budget`: the whole study's time (``--budget SECONDS``) and the cap of every case
  (``--max-time SECONDS``, the reference's too). A case that no longer fits in the time left
  is not started: it is listed as skipped with the reason (``skipped_result``), and the
  study still writes its tables. A case that starts gets the smaller of its cap and the
  time left, so that it stops (a ``partial`` or stopped row) instead of holding the study.
- :class:`CaseRun`: the picklable wrapper a case runs in, in-process or on a Dask worker:
  it sets the case's cap, times the case and collects what it printed on stderr and the
  warnings it raised, handed back with the result so that the caller prints each distinct
  line once per study, with its count, after the progress bar (:func:`warning_lines`).
- :func:`plan_line`: the line a study prints before its first solve: the number of cases,
  the largest mesh, an estimated time from the measured cost of each method
  (:class:`CostModel`) and the number of worker processes.

Examples
--------
>>> b = Budget(seconds=60.0, case_cap=20.0)
>>> b.cap(), b.fits(10.0), b.fits(90.0)
(20.0, True, False)
>>> Budget().cap() is None
True
>>> warning_lines({"springfem: warning: mismatch 5.2% (a)": 3}, {})
['springfem: warning: mismatch 5.2% (a) (3 times)']
"""

from __future__ import annotations

import contextlib
import io
import math
import re
import time
import warnings
from collections import Counter
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

#: A case that starts with less than this many seconds left is skipped instead (it could
#: not do more than build its scene).
MIN_START = 1.0


@dataclass
class Budget:
    """The time of a whole study and the cap of each of its cases.

    Parameters
    ----------
    seconds
        The whole study's time (``None``: unbounded).
    case_cap
        Every case's cap, the reference's included (``None``: the case's own).
    start
        ``time.monotonic()`` when the study started.
    """

    seconds: float | None = None
    case_cap: float | None = None
    start: float = field(default_factory=time.monotonic)

    def left(self) -> float:
        """Seconds left of the study's budget (``inf`` without one)."""
        if self.seconds is None:
            return math.inf
        return self.seconds - (time.monotonic() - self.start)

    def cap(self, own: float | None = None) -> float | None:
        """The cap of a case starting now: the smallest of its own cap, the user's and the
        time left (``None``: uncapped)."""
        caps = [c for c in (own, self.case_cap, self.left()) if c is not None and c < math.inf]
        return min(caps) if caps else None

    def fits(self, predicted: float | None, spent: float = 0.0) -> bool:
        """Whether a case predicted to take ``predicted`` s fits in the time left after
        ``spent`` more seconds (an unknown prediction fits while any time is left)."""
        left = self.left() - spent
        if left < MIN_START:
            return False
        return predicted is None or not math.isfinite(predicted) or predicted <= left

    def why_skipped(self, predicted: float | None) -> str:
        """The reason of a skipped case, for its row."""
        total = f"{self.seconds:g} s" if self.seconds is not None else "no"
        if predicted is not None and math.isfinite(predicted):
            left = max(self.left(), 0.0)
            return (f"skipped: predicted {predicted:.3g} s, more than the {left:.3g} s left "
                    f"of the study's budget of {total}")  # fmt: skip
        return f"skipped: the study's budget of {total} is spent"


def skipped_result(reason: str) -> dict[str, Any]:
    """The result of a case that was not run: ``status`` ``skipped`` and the reason.

    Parameters
    ----------
    reason
        Why (:meth:`Budget.why_skipped`).

    Returns
    -------
    dict
    """
    return {"status": "skipped", "message": reason, "skipped": True}


@dataclass(frozen=True)
class CaseRun:
    """Run ``work(case)`` under a cap, timed, with its stderr lines and warnings counted.

    Picklable (a Dask worker runs it): ``work`` must be importable there.

    Parameters
    ----------
    work
        The study's case function.
    cap
        The solve cap inside the case (:func:`springfem.mechanics.limits.solve_limits`;
        ``None``: the caller's).
    why
        What the cap is, for the message of a stopped solve (``None``: the ``--max-time``
        cap).

    Notes
    -----
    Called with a case, it returns ``(result, seconds, lines)``: ``lines`` maps a stderr
    line or warning message to how many times it came.
    """

    work: Callable[[dict[str, Any]], dict[str, Any]]
    cap: float | None = None
    why: str | None = None

    def __call__(self, case: dict[str, Any]) -> tuple[dict[str, Any], float, dict[str, int]]:
        from springfem.mechanics.limits import CAP_REASON, LIMITS, solve_limits

        lines: Counter = Counter()
        buffer = io.StringIO()
        t0 = time.perf_counter()
        cap = self.cap if self.cap is not None else LIMITS["max_time"]
        why = self.why if self.cap is not None else CAP_REASON["why"]
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            with solve_limits(max_time=cap, why=why), contextlib.redirect_stderr(buffer):
                result = self.work(case)
        seconds = time.perf_counter() - t0
        for w in caught:
            lines[f"{w.category.__name__}: {w.message}"] += 1
        for line in buffer.getvalue().splitlines():
            if line.strip():
                lines[line.rstrip()] += 1
        return result, seconds, dict(lines)


def _shape(line: str) -> str:
    """A line with its numbers replaced: lines that differ only in numbers are one kind."""
    return re.sub(r"\d+(\.\d+)?(e[-+]?\d+)?", "N", line)


def warning_lines(new: Mapping[str, int], seen: dict[str, list]) -> list[str]:
    """The lines to print once for the counted stderr lines ``new`` of a study.

    Lines that differ only in their numbers count as one kind, shown by its first line.

    Parameters
    ----------
    new
        Line -> count (:class:`CaseRun`'s ``lines``, summed over cases).
    seen
        Kind -> ``[first line, count]``; updated (pass the same dict for the whole study).

    Returns
    -------
    list of str
        One line per kind of ``seen``, with the count when above one.
    """
    for line, n in new.items():
        entry = seen.setdefault(_shape(line), [line, 0])
        entry[1] += n
    out = []
    for first, n in seen.values():
        out.append(first if n == 1 else f"{first} ({n} times)")
    return out


# ----------------------------------------------------------------------------- cost model


@dataclass
class CostModel:
    """Seconds a case will take, from what the same kind of case took.

    A case has a kind (its method: ``case["method"]``, ``case["model"]`` ...) and a size
    (its DOFs or tets, as the study estimates them). A kind's measured ``(size, seconds)``
    pairs predict a larger case as the time of the largest measured ones scaled by
    ``(size / measured size) ** exponent`` (small solves are dominated by fixed costs, so
    their time grows more slowly than their size; measured over the locking study's levels
    the exponent was 0.4-1.4, mostly below 1). A kind without a measurement uses ``priors``
    (seconds per unit size) × size, else the median cost per unit of every kind measured.

    Parameters
    ----------
    priors
        Kind -> seconds per unit of size when nothing of that kind is measured yet.
    exponent
        Growth of a measured time with size above the measured range.

    Examples
    --------
    >>> m = CostModel()
    >>> m.add("P1", 1000, 2.0)
    >>> round(m.predict("P1", 8000), 2)  # 2 s at 1000, times 8 ** 1.0
    16.0
    >>> m.predict("P2", 1000)  # nothing measured of P2: the median of what was
    2.0
    """

    priors: dict[str, float] = field(default_factory=dict)
    exponent: float = 1.0
    measured: dict[str, list[tuple[float, float]]] = field(default_factory=dict)

    def add(self, kind: str, size: float, seconds: float) -> None:
        """Record that a case of ``kind`` and ``size`` took ``seconds``."""
        if size > 0 and math.isfinite(seconds) and seconds >= 0:
            self.measured.setdefault(kind, []).append((float(size), float(seconds)))

    def per_unit(self, kind: str) -> tuple[float, float] | None:
        """``(seconds per unit size, the largest size measured)`` of ``kind``.

        A kind may name its parts from general to particular, ``"P2@beam@0.49"``: without a
        measurement of the kind itself, the measurements of its most particular measured
        prefix (``"P2@beam"``, then ``"P2"``) are used, then the prior of its first part.
        """
        parts = kind.split("@")
        for n in range(len(parts), 0, -1):
            prefix = "@".join(parts[:n])
            pairs = [p for k, v in self.measured.items()
                     if k == prefix or k.startswith(prefix + "@") for p in v]  # fmt: skip
            if pairs:
                big = max(s for s, _ in pairs)
                top = [t / s for s, t in pairs if s >= 0.5 * big]  # the largest: least overhead
                return float(sorted(top)[len(top) // 2]), big
        if parts[0] in self.priors:
            return float(self.priors[parts[0]]), 0.0
        every = [t / s for pairs in self.measured.values() for s, t in pairs]
        return (float(sorted(every)[len(every) // 2]), 0.0) if every else None

    def predict(self, kind: str, size: float) -> float | None:
        """Predicted seconds of a case (``None``: nothing to predict from)."""
        got = self.per_unit(kind)
        if got is None:
            return None
        cost, big = got
        if big and size > big:
            return cost * big * (size / big) ** self.exponent
        return cost * size


def plan_line(
    study: str,
    n_cases: int,
    n_cached: int,
    largest: int | None,
    estimate: float | None,
    workers: int,
    budget: Budget,
) -> str:
    """The line a study prints before its first solve.

    Parameters
    ----------
    study
        Its name (and the group of cases, if any).
    n_cases, n_cached
        Its cases and how many of them are already in the cache.
    largest
        Tets of its largest mesh (``None``: not known).
    estimate
        Predicted seconds of the cases to compute (``None``: not known).
    workers
        Processes the cases run on.
    budget
        The study's budget.

    Returns
    -------
    str

    Examples
    --------
    >>> for part in plan_line("locking", 12, 2, 3000, 40.0, 2, Budget(120.0)).split(", "):
    ...     print(part)
    plan: locking: 12 cases (2 cached)
    largest mesh 3,000 tets
    estimated 40 s on 2 workers (budget 120 s)
    """
    parts = [f"plan: {study}: {n_cases} cases ({n_cached} cached)"]
    if largest:
        parts.append(f"largest mesh {largest:,} tets")
    est = "estimated time unknown" if estimate is None else f"estimated {estimate:.0f} s"
    who = {0: "on the cluster", 1: "in this process"}.get(workers, f"on {workers} workers")
    parts.append(f"{est} {who}")
    text = ", ".join(parts)
    if budget.seconds is not None:
        text += f" (budget {budget.seconds:g} s)"
    return text


def total(values: Iterable[float | None]) -> float | None:
    """The sum of the known predictions (``None`` when none is known)."""
    known = [v for v in values if v is not None and math.isfinite(v)]
    return float(sum(known)) if known else None


#: Case keys shown in the table of skipped cases (those a case has).
SKIPPED_KEYS = ("scene", "method", "model", "nu", "factor", "size", "kind", "solution")


def skipped_table(ctx, skipped: list[tuple[dict[str, Any], str]]):
    """Write ``skipped.csv`` / ``.md``: each case the budget left out, and why.

    Parameters
    ----------
    ctx
        The study's context (:class:`studies.registry.StudyContext`).
    skipped
        ``(case, reason)`` pairs.

    Returns
    -------
    studies.registry.Table
    """
    import pandas as pd

    rows = [{**{k: c[k] for k in SKIPPED_KEYS if k in c}, "reason": why} for c, why in skipped]
    caption = "The cases not run: they did not fit in the study's budget (--budget)."
    return ctx.table(pd.DataFrame(rows), "skipped", caption)


def skipped_finding(skipped: list[tuple[dict[str, Any], str]], budget: Budget) -> str:
    """One sentence: how many cases the budget left out (the table lists them)."""
    total_s = f"{budget.seconds:g} s" if budget.seconds is not None else "the budget"
    return (f"{len(skipped)} cases did not fit in the study's budget of {total_s} and were "
            "not run (skipped.csv lists them with the reason); the numbers above are those "
            "of the cases that ran.")  # fmt: skip
