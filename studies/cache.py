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
from pathlib import Path
from typing import Any

from springfem.files import atomic_write_text, remove_stale_temp_files
from springfem.files import jsonable as _jsonable

from .executor import run_tasks

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

    Parameters
    ----------
    root, study
        Cases live in ``root/study``.
    fingerprint
        Code fingerprint mixed into every key (see :func:`source_fingerprint`).
    workers, scheduler
        Run the missing cases on a local cluster of ``workers`` processes (0: one per core)
        or on the cluster of ``scheduler`` (neither: in-process, one after another).
    """

    def __init__(
        self,
        root: str | os.PathLike,
        study: str,
        fingerprint: str = "",
        workers: int | None = None,
        scheduler: str | None = None,
    ):
        self.dir = Path(root) / study
        self.dir.mkdir(parents=True, exist_ok=True)
        self.fingerprint = fingerprint
        self.workers, self.scheduler = workers, scheduler
        remove_stale_temp_files(self.dir)  # left by a run killed mid-write

    def path(self, case: dict[str, Any]) -> Path:
        return self.dir / f"{case_key(case, self.fingerprint)}.json"

    def get(self, case: dict[str, Any]) -> dict[str, Any] | None:
        """The stored result of ``case``, or ``None`` when it is missing or damaged.

        A file that does not parse, or whose result does not match its checksum (a
        truncated or corrupted file), is set aside as ``<name>.json.damaged`` with a note
        on stderr, and the case is computed again.
        """
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
        return result

    def put(self, case: dict[str, Any], result: dict[str, Any]) -> None:
        """Store ``result`` of ``case`` atomically, with the checksum of the result."""
        result = _jsonable(result)
        entry = {"case": case, "result": result, "sha256": checksum(result)}
        atomic_write_text(self.path(case), json.dumps(_jsonable(entry), indent=1))

    def run(
        self,
        cases: Iterable[dict[str, Any]],
        work: Callable[[dict[str, Any]], dict[str, Any]],
        progress: bool = True,
        desc: str | None = None,
    ) -> list[dict[str, Any]]:
        """Results of ``work(case)`` for each case, computing only the missing ones.

        ``work`` must be importable by the workers when the cases run on a cluster.
        """
        cases = list(cases)
        results: list[dict[str, Any] | None] = [self.get(c) for c in cases]
        todo = [i for i, r in enumerate(results) if r is None]
        bar = None
        if progress and todo:
            from tqdm import tqdm

            bar = tqdm(total=len(todo), desc=desc or self.dir.name, unit="case", leave=False)

        def finished(j: int, res: dict[str, Any]) -> None:
            res = _jsonable(res)
            self.put(cases[todo[j]], res)  # atomically, as it arrives
            results[todo[j]] = res
            if bar is not None:
                bar.update(1)

        try:
            run_tasks(
                [cases[i] for i in todo],
                work,
                finished,
                workers=self.workers,
                scheduler=self.scheduler,
                keys=[f"{self.dir.name}-{case_key(cases[i], self.fingerprint)}" for i in todo],
            )
        finally:
            if bar is not None:
                bar.close()
        return results  # type: ignore[return-value]
