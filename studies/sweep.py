"""``springfem sweep SWEEP.toml``: a scene over a grid of values, every case × model in a table.

Each finished case is written atomically to ``<out>/cases/<hash>.json`` (the study case
cache, :class:`studies.cache.CaseCache`) the moment it arrives, in-process or from a Dask
worker (:mod:`studies.executor`); a rerun computes only cases without a file, and the
table ``results.parquet``/``results.csv`` and the figures are assembled from the case files.
The hash covers the case's scene table, models, reference and the code, so editing the
scene or the models recomputes what changed.

Examples
--------
>>> import tempfile
>>> from studies.sweep_file import parse_sweep
>>> spec = parse_sweep({"scene": "cantilever", "models": ["fem-p1", "fem-p2"],
...                     "grid": {"mesh.divisions": [[4, 1, 1], [8, 1, 1]]}})
>>> out = tempfile.mkdtemp()
>>> run = run_sweep(spec, out, progress=False, figures=False)
>>> run.computed, len(run.table), sorted(set(run.table["status"]))
(2, 4, ['ok'])
>>> run_sweep(spec, out, progress=False, figures=False).computed  # all cached
0
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from springfem.files import folder_lock, output_folder, remove_stale_temp_files
from springfem.files import jsonable as _jsonable

from .cache import CaseCache, case_key, source_fingerprint
from .executor import run_tasks
from .sweep_case import run_case
from .sweep_file import SweepSpec
from .sweep_resolve import difference, duplicates
from .sweep_table import sweep_figures, sweep_table, write_tables


@dataclass
class SweepRun:
    """What :func:`run_sweep` did.

    Attributes
    ----------
    spec
        The sweep.
    out
        Its output folder.
    table
        One row per case × model (:func:`studies.sweep_table.sweep_table`).
    computed, cached
        Cases computed in this run, and taken from their case files.
    errors
        Case index -> message of cases that could not be computed (not cached: a rerun
        tries them again).
    files
        The table and figure files written.
    seconds
        Wall time of the run.
    notes
        One line per case solved as another (:mod:`studies.sweep_resolve`).
    """

    spec: SweepSpec
    out: Path
    table: pd.DataFrame
    computed: int
    cached: int
    errors: dict[int, str] = field(default_factory=dict)
    files: list[Path] = field(default_factory=list)
    seconds: float = 0.0
    notes: list[str] = field(default_factory=list)

    @property
    def failed(self) -> pd.DataFrame:
        """Rows that failed (not ``ok`` and not ``implausible``)."""
        return self.table[~self.table["status"].isin(("ok", "implausible"))]

    @property
    def implausible(self) -> pd.DataFrame:
        """Rows whose solution is implausible (:mod:`springfem.plausibility`)."""
        return self.table[self.table["status"] == "implausible"]


def default_out(spec: SweepSpec) -> Path:
    """``out/sweep-<name>`` (:func:`springfem.files.output_folder`; the sweep file's name)."""
    return output_folder("sweep", spec.name)


def code_fingerprint() -> str:
    """Hash of the sources a case's result depends on (part of every case file's key)."""
    import reference_fem
    import springfem
    import springmodel

    from .models import plugin_sources

    here = Path(__file__).parent
    return source_fingerprint(
        *(Path(list(m.__path__)[0]) for m in (springfem, springmodel, reference_fem)),
        *(here / f for f in ("sweep_case.py", "overrides.py", "compare.py", "metrics.py")),
        *plugin_sources(),  # the plug-in models' packages (springfem.model_api)
    )


def run_sweep(
    spec: SweepSpec,
    out: str | Path | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
    figures: bool = True,
    work: Callable[[dict[str, Any]], dict[str, Any]] = run_case,
) -> SweepRun:
    """Run the missing cases of ``spec``, then write its table and figures.

    Parameters
    ----------
    spec
        The sweep (:func:`studies.sweep_file.load_sweep`).
    out
        Output folder (default :func:`default_out`).
    workers, scheduler
        In-process (neither), a local cluster of ``workers`` processes (0: one per core)
        or an existing Dask scheduler (see :mod:`studies.executor`).
    progress
        Show a progress bar over the cases.
    figures
        Write the default figures.
    work
        The case function (:func:`studies.sweep_case.run_case`; tests substitute one).

    Returns
    -------
    SweepRun

    Raises
    ------
    InputError
        Another process is running a sweep into ``out`` (:func:`springfem.files.folder_lock`).
    """
    out = Path(out) if out is not None else default_out(spec)
    with folder_lock(out, "sweep"):
        return _run_in(spec, out, workers, scheduler, progress, figures, work)


def _run_in(spec, out, workers, scheduler, progress, figures, work) -> SweepRun:
    """:func:`run_sweep` with ``out`` locked."""
    t0 = time.perf_counter()
    remove_stale_temp_files(out)  # tables of a run killed mid-write
    cache = CaseCache(out, "cases", fingerprint=code_fingerprint())
    tasks = [spec.task(i) for i in range(len(spec.cases))]
    results: list[dict[str, Any] | None] = [cache.get(t) for t in tasks]
    missing = [i for i, r in enumerate(results) if r is None]
    same = duplicates(tasks) if len(missing) > 0 and len(tasks) > 1 else {}
    todo = [i for i in missing if i not in same]  # a duplicate takes its first case's result
    errors: dict[int, str] = {}
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(tasks), initial=len(tasks) - len(todo), desc=spec.name, unit="case")

    def finished(j: int, res: dict[str, Any]) -> None:
        i = todo[j]
        res = _jsonable(res)
        cache.put(tasks[i], res)  # atomically, as it arrives
        results[i] = res
        if bar is not None:
            bar.update(1)

    def failed(j: int, exc: BaseException) -> None:
        errors[todo[j]] = f"{type(exc).__name__}: {exc}"
        if bar is not None:
            bar.update(1)

    try:
        run_tasks(
            [tasks[i] for i in todo],
            work,
            finished,
            workers=workers,
            scheduler=scheduler,
            on_error=failed if workers is not None or scheduler is not None else None,
            keys=[f"sweep-case-{case_key(tasks[i], cache.fingerprint)}" for i in todo],
        )
    finally:
        if bar is not None:
            bar.close()
    for i in (i for i in missing if i in same):
        src = results[same[i]]
        if src is None:  # its first case failed
            errors[i] = errors.get(same[i], "its first case was not computed")
            continue
        res = {**src, "values": spec.cases[i]}
        res["rows"] = [{**row, "same_as": same[i]} for row in src["rows"]]
        cache.put(tasks[i], res)
        results[i] = res
    for i, msg in errors.items():  # in the table, not in the cache
        results[i] = {
            "values": spec.cases[i],
            "rows": [{"model": m, "status": "failed", "message": msg} for m in spec.models],
        }
    table = sweep_table(results, spec.keys)  # type: ignore[arg-type]
    files = list(write_tables(table, out))
    if figures:
        files += sweep_figures(table, spec.keys, spec.reference, out)
    computed = len(todo) - len([i for i in errors if i in todo])
    notes = [
        f"case {i} is the same computation as case {j} "
        f"({difference(spec.cases[i], spec.cases[j])}): solved once"
        for i, j in same.items()
        if i in missing
    ]
    return SweepRun(spec, out, table, computed, len(tasks) - len(missing), errors, files,
                    time.perf_counter() - t0, notes)  # fmt: skip


def summary_lines(run: SweepRun) -> list[str]:
    """Median error and wall time per model, one line each."""
    t = run.table[run.table["status"] == "ok"]
    lines = []
    for m in run.spec.models:
        d = t[t["model"] == m]
        if len(d) == 0:
            lines.append(f"  {m:<10} no successful case")
            continue
        what = (
            "reference"
            if m == run.spec.reference
            else f"median rel. L2 error {d['rel_l2'].median():.3g}"
        )
        lines.append(
            f"  {m:<10} {what}; median solve {d['wall_time'].median():.3g} s ({len(d)} ok)"
        )
    return lines
