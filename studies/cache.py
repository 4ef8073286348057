"""Case cache for studies: each case is stored under a hash of its settings.

An interrupted study resumes without redoing finished cases: every finished case is
written atomically to ``<cache>/<study>/<hash>.json`` before the next one starts, so a
rerun computes only what is missing or what changed. Each file carries the checksum of its
result; a truncated or corrupted one is set aside and recomputed.

Examples
--------
>>> import tempfile
>>> cache = CaseCache(tempfile.mkdtemp(), "demo")
>>> calls = []
>>> def work(case):
...     calls.append(case["n"])
...     return {"square": case["n"] ** 2}
>>> [r["square"] for r in cache.run([{"n": 2}, {"n": 3}], work, progress=False)]
[4, 9]
>>> [r["square"] for r in cache.run([{"n": 2}, {"n": 3}], work, progress=False)]
[4, 9]
>>> calls
[2, 3]
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from springfem.files import atomic_write_text, remove_stale_temp_files
from springfem.files import jsonable as _jsonable

from .budget import Budget, CaseRun, CostModel, plan_line, skipped_result, total, warning_lines
from .executor import run_tasks, worker_count

#: What a study's ``estimate(case)`` returns: ``(kind, size, tets)`` (a method's name, the
#: case's DOFs or another measure of its cost, its mesh's tets; ``None`` where unknown).
Estimate = tuple[str, float | None, int | None]

CACHE_VERSION = "1"


def case_key(case: dict[str, Any], fingerprint: str = "") -> str:
    """Stable hash of a case's settings (JSON with sorted keys) and a code fingerprint."""
    text = json.dumps(_jsonable(case), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256((CACHE_VERSION + fingerprint + text).encode()).hexdigest()[:20]


def checksum(result: Any) -> str:
    """SHA-256 of a result's canonical JSON (sorted keys, NaN written as JSON writes it)."""
    text = json.dumps(_jsonable(result), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def source_fingerprint(*paths: str | os.PathLike) -> str:
    """Hash of the Python sources under ``paths`` (files or folders).

    Part of every case key, so a change to the models or the study recomputes its cases
    instead of reusing results of the old code.
    """
    h = hashlib.sha256()
    for p in paths:
        p = Path(p)
        files = sorted(p.rglob("*.py")) if p.is_dir() else [p]
        for f in files:
            h.update(f.name.encode())
            h.update(f.read_bytes())
    return h.hexdigest()[:16]


class CaseCache:
    """A folder of finished cases of one study, computed in-process or on a Dask cluster.

    Each finished case is written atomically as it arrives (from this process or from a
    worker, :mod:`studies.executor`), so a killed worker or client loses no finished case
    and a rerun computes only what is missing.

    Every case runs in a :class:`~studies.budget.CaseRun`: with the cap of the study's
    :class:`~studies.budget.Budget` (the user's ``--max-time``, and the time left of
    ``--budget``), timed, and with what it printed on stderr collected, so that each distinct
    line is printed once per study (:meth:`print_warnings`) instead of once per case. A case
    that does not fit in the time left is not run: with ``skippable`` its result is
    :func:`~studies.budget.skipped_result`, otherwise it runs with no time (its solve stops at
    once and the study records that as it records any stopped solve). Neither is stored, nor
    is a case the budget stopped: a rerun with more time computes them.

    Parameters
    ----------
    root, study
        Cases live in ``root/study``.
    fingerprint
        Code fingerprint mixed into every key (see :func:`source_fingerprint`).
    workers, scheduler
        Run the missing cases on a local cluster of ``workers`` processes (0: one per core)
        or on the cluster of ``scheduler`` (neither: in-process, one after another).
    budget
        The study's budget (default: none).
    quiet
        Print no plan line (tests, doctests).
    """

    def __init__(
        self,
        root: str | os.PathLike,
        study: str,
        fingerprint: str = "",
        workers: int | None = None,
        scheduler: str | None = None,
        budget: Budget | None = None,
        quiet: bool = False,
    ):
        self.dir = Path(root) / study
        self.dir.mkdir(parents=True, exist_ok=True)
        self.fingerprint = fingerprint
        self.workers, self.scheduler = workers, scheduler
        self.budget = budget if budget is not None else Budget()
        self.quiet = quiet
        self.costs = CostModel()
        self.lines: dict[str, list] = {}
        self.skipped: list[tuple[dict[str, Any], str]] = []
        remove_stale_temp_files(self.dir)  # left by a run killed mid-write

    def path(self, case: dict[str, Any]) -> Path:
        return self.dir / f"{case_key(case, self.fingerprint)}.json"

    def get(self, case: dict[str, Any]) -> dict[str, Any] | None:
        """The stored result of ``case``, or ``None`` when it is missing or damaged.

        A file that does not parse, or whose result does not match its checksum (a
        truncated or corrupted file), is set aside as ``<name>.json.damaged`` with a note
        on stderr, and the case is computed again.
        """
        entry = self._entry(case)
        return None if entry is None else entry["result"]

    def _entry(self, case: dict[str, Any]) -> dict[str, Any] | None:
        p = self.path(case)
        if not p.is_file():
            return None
        try:
            entry = json.loads(p.read_text(encoding="utf-8"))
            result = entry["result"]
            ok = entry["sha256"] == checksum(result)
        except (ValueError, KeyError, TypeError, UnicodeDecodeError):
            ok = False
        if not ok:
            os.replace(p, p.with_name(p.name + ".damaged"))
            print(f"note: {p} is damaged (checksum); the case is computed again",
                  file=sys.stderr)  # fmt: skip
            return None
        return entry

    def put(
        self, case: dict[str, Any], result: dict[str, Any], seconds: float | None = None
    ) -> None:
        """Store ``result`` of ``case`` atomically, with the checksum of the result (and the
        case's wall time ``seconds``, for the cost model)."""
        result = _jsonable(result)
        entry = {"case": case, "result": result, "sha256": checksum(result)}
        if seconds is not None:
            entry["seconds"] = float(seconds)
        atomic_write_text(self.path(case), json.dumps(_jsonable(entry), indent=1))

    def run(
        self,
        cases: Iterable[dict[str, Any]],
        work: Callable[[dict[str, Any]], dict[str, Any]],
        progress: bool = True,
        desc: str | None = None,
        estimate: Callable[[dict[str, Any]], Estimate] | None = None,
        skippable: bool = False,
        priors: dict[str, float] | None = None,
    ) -> list[dict[str, Any]]:
        """Results of ``work(case)`` for each case, computing only the missing ones.

        ``work`` must be importable by the workers when the cases run on a cluster.

        Parameters
        ----------
        cases
            The cases, in the order to compute them (what matters most first: a budget
            leaves out the last).
        work
            The case function.
        progress
            Show a progress bar.
        desc
            The bar's label (default: the study's name).
        estimate
            ``estimate(case) -> (kind, size, tets)`` for the plan line and the budget (see
            :class:`~studies.budget.CostModel`); default: the case's ``method`` or ``model``,
            sizes unknown.
        skippable
            The study's tables take :func:`~studies.budget.skipped_result` rows.
        priors
            Kind -> seconds per unit of size, until the kind is measured.

        Returns
        -------
        list of dict
            One result per case, in order.
        """
        cases = list(cases)
        guess = estimate or _default_estimate
        self.costs.priors.update(priors or {})
        entries = [self._entry(c) for c in cases]
        results: list[dict[str, Any] | None] = [None if e is None else e["result"] for e in entries]
        sizes = [guess(c) for c in cases]
        for e, (kind, size, _) in zip(entries, sizes, strict=True):
            if e is not None and "seconds" in e:
                self.costs.add(kind, size or 1.0, _solve_seconds(e["result"], e["seconds"]))
        todo = [i for i, r in enumerate(results) if r is None]
        if not todo:
            return results  # type: ignore[return-value]
        predicted = [self.costs.predict(sizes[i][0], sizes[i][1] or 1.0) for i in todo]
        n_workers = worker_count(self.workers, self.scheduler)
        if not self.quiet:
            tets = [t for _, _, t in sizes if t]
            est = total(predicted)
            line = plan_line(desc or self.dir.name, len(cases), len(cases) - len(todo),
                             max(tets) if tets else None,
                             None if est is None else est / max(n_workers, 1), n_workers,
                             self.budget)  # fmt: skip
            print(line, file=sys.stderr, flush=True)
        bar = None
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=len(todo), desc=desc or self.dir.name, unit="case", leave=False)

        def finished(j: int, got: tuple[dict[str, Any], float, dict[str, int], bool]) -> None:
            res, seconds, lines, keep = got
            i = todo[j]
            res = _jsonable(res)
            self._count(lines)
            if res.get("skipped"):
                self.skipped.append((cases[i], str(res.get("message", ""))))
            elif keep:
                self.put(cases[i], res, seconds)  # atomically, as it arrives
                self.costs.add(sizes[i][0], sizes[i][1] or 1.0, _solve_seconds(res, seconds))
            results[i] = res
            if bar is not None:
                bar.update(1)

        deadline = None if self.budget.seconds is None else time_now() + self.budget.left()
        tasks = [
            BudgetedCase(cases[i], predicted[j], deadline, self.budget.case_cap, skippable,
                         self.budget.seconds)
            for j, i in enumerate(todo)
        ]  # fmt: skip
        try:
            run_tasks(
                tasks,
                Budgeted(work),
                finished,
                workers=self.workers,
                scheduler=self.scheduler,
                keys=[f"{self.dir.name}-{case_key(cases[i], self.fingerprint)}" for i in todo],
            )
        finally:
            if bar is not None:
                bar.close()
        return results  # type: ignore[return-value]

    def _count(self, lines: dict[str, int]) -> None:
        warning_lines(lines, self.lines)

    def print_warnings(self) -> list[str]:
        """Print each distinct stderr line and warning of the study's cases once, with its
        count (lines differing only in numbers are one), and forget them.

        Returns
        -------
        list of str
            The lines printed.
        """
        out = warning_lines({}, self.lines)
        for line in out:
            print(line, file=sys.stderr)
        self.lines = {}
        return out


def _solve_seconds(result: dict[str, Any], elapsed: float) -> float:
    """The time a case's solve took: its own ``seconds`` (a study's timed solve, without
    warm-up and compilation), else the whole case's ``elapsed``."""
    own = result.get("seconds") if isinstance(result, dict) else None
    if isinstance(own, int | float) and own == own and 0 < own <= elapsed:
        return float(own)
    return float(elapsed)


def time_now() -> float:
    """Wall-clock seconds (the same clock on every process of the machine)."""
    import time

    return time.time()


def _default_estimate(case: dict[str, Any]) -> Estimate:
    kind = case.get("method") or case.get("model") or case.get("kind") or "case"
    return str(kind), None, None


@dataclass(frozen=True)
class BudgetedCase:
    """A case with what its run needs to know of the budget (see :class:`Budgeted`)."""

    case: dict[str, Any]
    predicted: float | None
    deadline: float | None
    case_cap: float | None
    skippable: bool
    budget: float | None = None
    extra: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Budgeted:
    """Run a :class:`BudgetedCase` where it lands (this process or a worker).

    The time left is read when the case starts: a case that no longer fits (its predicted
    time, or :data:`~studies.budget.MIN_START`) is skipped (``skippable``), or run with no
    time so that its solve stops at once; a case that runs is capped at the smaller of the
    user's cap and the time left. Returns ``(result, seconds, lines, keep)``: ``keep`` is
    false when the budget, not the case, decided how it ended (not stored).
    """

    work: Callable[[dict[str, Any]], dict[str, Any]]

    def __call__(self, task: BudgetedCase) -> tuple[dict[str, Any], float, dict[str, int], bool]:
        left = None if task.deadline is None else task.deadline - time_now()
        b = Budget(seconds=task.budget, case_cap=task.case_cap)
        if left is not None:
            b.start -= (task.budget or 0.0) - left  # the same time left as the caller's
            if not b.fits(task.predicted):
                if task.skippable:
                    return skipped_result(b.why_skipped(task.predicted)), 0.0, {}, False
                why = b.why_skipped(task.predicted)
                res, seconds, lines = CaseRun(self.work, 1e-3, why)(task.case)
                return res, seconds, lines, False
        cap = b.cap()
        limited = left is not None and cap is not None and cap >= left - 1e-9
        why = f"the study's budget of {task.budget:g} s" if limited else None
        res, seconds, lines = CaseRun(self.work, cap, why)(task.case)
        keep = not (limited and seconds >= 0.9 * cap)
        return res, seconds, lines, keep
