"""``springfem bench scale``: every model of the verdict on a family of organ meshes.

For each size of the family (:data:`DEFAULT_SIZES`; ``--quick``: :data:`QUICK_SIZES`) the
liver-shaped organ of :func:`springfem.mesh.organ.organ_scene` (neo-Hookean, ν = 0.49,
hanging under gravity from its flat cut) is solved by each model the verdict weighs on it
(:func:`scale_models`), and three things are measured:

- the wall time of the static solve (warm: the case's process solves a small organ with the
  model first, so imports and compiled kernels are not timed);
- for a model with an explicit form, one explicit force pass, as the verdict times its
  explicit step (:mod:`studies.bench_scale_case`);
- the peak resident memory (RSS) of the case.

Each case runs in its own process (:func:`studies.bench_scale_run.run_case`), so its peak
RSS is its own (``os.wait4`` reads it), under a time cap (``--max-time``, per static solve)
and a memory cap (``--max-memory``: ``RLIMIT_AS``, the address space, which is a little
above the RSS). The cases run one at a time, smallest size first, every model at a size
before the next size. A model's static solve stops at the first size it does not fit or
fails; the larger sizes say so. A case whose predicted time or memory (:func:`predict`, from
the model's smaller sizes) is far over a cap (:data:`FAR`) is not tried and is recorded as
not fitting, with the prediction. A model with an explicit form whose static solve no longer
fits in time still has its explicit step timed at the larger sizes, in a case of its own
(``--step-only``). ``--budget`` bounds the whole run: a case whose predicted time does not
fit in what is left is not started; ``--resume`` keeps the cases of an earlier run in the
same output folder.

The laws, tables, figure and JSON are written by :mod:`studies.bench_scale_output` after
every size, so a run stopped part way leaves what it measured.
"""

from __future__ import annotations

import os
import signal
import subprocess
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .bench_scale_fit import ASSUMED, SOLVED, power_law
from .bench_scale_run import DID_NOT_FIT, CaseResult, classify, organ_scene_file, run_case

#: The organ family (tets) of the full benchmark and of ``--quick``.
DEFAULT_SIZES = (5_000, 30_000, 120_000, 500_000)
QUICK_SIZES = (2_000, 8_000)
#: Tets of the warm-up organ every case solves first (not timed).
WARMUP_TETS = 300
#: Default caps of one case: seconds of its static solve, bytes of its address space.
DEFAULT_MAX_TIME = 120.0
DEFAULT_MAX_MEMORY = 14e9
#: Exponents a prediction from one size assumes (time of a static solve, memory above
#: the baseline); a fitted exponent below 1 is raised to 1 (no cost grows slower than the
#: mesh it reads).
ONE_SIZE_TIME_EXPONENT = ASSUMED["time"]
MIN_EXPONENT = 1.0
#: A case is not tried when its predicted static time is over this many times the time cap
#: ("far too big": between the cap and this the cap itself stops it) or its predicted
#: memory over the memory cap (a case over it would take the machine's memory from others).
FAR = 2.0
#: The reference's time cap against the others' (:attr:`ScaleSettings.reference_time`).
REFERENCE_TIME_FACTOR = 3.0
#: The default output folder and meshes folder.
DEFAULT_OUT = Path("reports") / "scale"
DEFAULT_MESHES = Path("out") / "organ-meshes"


@dataclass
class ScaleSettings:
    """What ``springfem bench scale`` runs.

    Attributes
    ----------
    sizes
        Tets of the organ family (increasing).
    models
        Models (default :func:`scale_models` of the first organ).
    max_time
        Seconds a static solve may take.
    reference_time
        Seconds the reference's static solve may take (the verdict's reference on the
        organ, P2/P1 mixed; default :data:`REFERENCE_TIME_FACTOR` times ``max_time``): the
        solve a distributed solver would take over is the one to follow furthest.
    max_memory
        Bytes of address space a case may use.
    budget
        Seconds for the whole run (``None``: no bound).
    meshes
        Folder of the organ meshes (made once, reused).
    out
        Output folder.
    cost_laws
        Also write the cost laws here (:func:`studies.bench_scale_fit.cost_laws_document`).
    resume
        Keep the cases ``out/cases.json`` holds (those the budget left out are run again).
    notes
        Lines for the findings (which models are the same solve, e.g.).
    aliases
        Models left out as the same solve as a measured one (:func:`scale_models`).
    reference
        The verdict's reference on the organ (set by :func:`bench_scale`).
    """

    sizes: Sequence[int] = DEFAULT_SIZES
    models: Sequence[str] | None = None
    max_time: float = DEFAULT_MAX_TIME
    reference_time: float | None = None
    reference: str | None = None
    max_memory: float = DEFAULT_MAX_MEMORY
    budget: float | None = None
    meshes: Path = DEFAULT_MESHES
    out: Path = DEFAULT_OUT
    cost_laws: Path | None = None
    resume: bool = False
    notes: list[str] = field(default_factory=list)
    aliases: dict[str, str] = field(default_factory=dict)

    @property
    def reference_cap(self) -> float:
        """Seconds the reference's static solve may take."""
        return self.reference_time or REFERENCE_TIME_FACTOR * self.max_time


def scale_models(scene) -> tuple[list[str], dict[str, str]]:
    """The models the verdict weighs on ``scene`` and its reference
    (:func:`studies.verdict.candidate_models`), each solve once: a model that is the same
    solve as another (:func:`studies.models.same_solves`) is left out, the named one
    kept; and the models left out, each with the one it is the same solve as.

    Parameters
    ----------
    scene
        The scene.

    Returns
    -------
    tuple of (list of str, dict)
    """
    from . import models
    from .verdict import candidate_models

    names = candidate_models(scene)
    mixed = models.mixed_reference(scene)
    if mixed and mixed not in names:
        names.append(mixed)
    # the scene's own spring model last, so that a named variant of the same solve is kept
    names = [n for n in names if n != "spring"] + (["spring"] if "spring" in names else [])
    alias = models.same_solves(scene, names)
    return [n for n in names if n not in alias], alias


def predict(rows: list[dict], tets: float) -> tuple[float, float]:
    """The static time (s) and peak memory (bytes) of a model at ``tets`` from its solved
    smaller sizes (``nan``: none solved).

    Time: the power law of the sizes solved (:func:`~studies.bench_scale_fit.power_law`),
    its exponent at least :data:`MIN_EXPONENT`; from one size, exponent
    :data:`ONE_SIZE_TIME_EXPONENT`. Memory: the last size's baseline plus the power law of
    the memory above it, exponent at least :data:`MIN_EXPONENT` (one size: that).

    Parameters
    ----------
    rows
        The model's cases so far (``tets``, ``status``, ``static (s)``,
        ``peak memory (bytes)``, ``baseline (bytes)``).
    tets
        The size.

    Returns
    -------
    tuple of float

    Examples
    --------
    >>> rows = [{"tets": 1e4, "status": "ok", "static (s)": 2.0,
    ...          "peak memory (bytes)": 3e8, "baseline (bytes)": 2e8}]
    >>> t, m = predict(rows, 4e4)
    >>> round(t, 6), round(m / 1e8, 6)  # 2 * 4^1.5, 2e8 + 1e8 * 4
    (16.0, 6.0)
    """
    solved = [r for r in rows if r["status"] in SOLVED]
    if not solved:
        return float("nan"), float("nan")
    last = max(solved, key=lambda r: r["tets"])
    n = np.array([r["tets"] for r in solved], dtype=float)
    t = np.array([r["static (s)"] for r in solved], dtype=float)
    base = float(last["baseline (bytes)"])
    above = np.array([r["peak memory (bytes)"] for r in solved], dtype=float) - base
    if len(np.unique(n)) >= 2 and np.all(t > 0):
        b = max(power_law(n, t)[1], MIN_EXPONENT)
    else:
        b = ONE_SIZE_TIME_EXPONENT
    time_at = float(last["static (s)"]) * (tets / last["tets"]) ** b
    ok = above > 0
    d = MIN_EXPONENT
    if len(np.unique(n[ok])) >= 2:
        d = max(power_law(n[ok], above[ok])[1], MIN_EXPONENT)
    top = max(float(last["peak memory (bytes)"]) - base, 0.0)
    return time_at, base + top * (tets / last["tets"]) ** d


def _row(model: str, size: int, tets: float, status: str, message: str, **values) -> dict:
    row = {"model": model, "size": size, "tets": tets, "status": status,
           "static (s)": np.nan, "step (s)": np.nan, "peak memory (bytes)": np.nan,
           "baseline (bytes)": np.nan, "predicted static (s)": np.nan,
           "predicted memory (bytes)": np.nan, "load average": np.nan,
           "case wall (s)": np.nan, "message": message}  # fmt: skip
    row.update(values)
    return row


def measured_row(model: str, size: int, res: CaseResult, max_time: float,
                 max_memory: float, predicted: tuple[float, float]) -> dict:  # fmt: skip
    """The table row of a case that ran."""
    status, message = classify(res, max_time, max_memory)
    ready = res.stages.get("ready", {})
    static = res.stages.get("static", {})
    step = res.stages.get("step", {})
    load = static.get("load_average") or ready.get("load_average") or [np.nan]
    return _row(
        model, size, float(ready.get("tets", size)), status, message,
        **{"static (s)": static.get("seconds", np.nan) if status in SOLVED else np.nan,
           "step (s)": step.get("seconds", np.nan), "peak memory (bytes)": res.peak_rss,
           "baseline (bytes)": res.stages.get("warmup", ready).get("rss", np.nan),
           "predicted static (s)": predicted[0], "predicted memory (bytes)": predicted[1],
           "load average": load[0], "case wall (s)": res.wall},
    )  # fmt: skip


def bench_scale(settings: ScaleSettings, log: Callable[[str], None] = print) -> pd.DataFrame:
    """Run the benchmark (see the module docstring) and write its outputs.

    Parameters
    ----------
    settings
        What to run.
    log
        Called with one line per case.

    Returns
    -------
    pandas.DataFrame
        One row per model and size (:func:`measured_row`, or a case not run and why).
    """
    from springfem.scene import load_scene

    from .bench_scale_output import read_cases, write_outputs

    t0 = time.perf_counter()
    sizes = sorted(int(s) for s in settings.sizes)
    log(f"bench scale: sizes {sizes}, cap {settings.max_time:g} s (the reference "
        f"{settings.reference_cap:g} s) and {settings.max_memory / 1e9:g} GB per case, "
        f"load average {_load()}")  # fmt: skip
    warmup = organ_scene_file(settings.meshes, WARMUP_TETS, settings.max_memory)
    names = list(settings.models or [])
    notes = settings.notes
    from . import models

    small = load_scene(warmup) if not names or models.MIXED in names else None
    if small is not None and settings.reference is None:
        settings.reference = models.mixed_reference(small)
    if not names:
        names, aliases = scale_models(small)
        settings.aliases.update(aliases)
        notes += [
            f"{n} is the same solve as {first} on the organ: measured once as {first}, "
            "and the cost laws give it that model's laws"
            for n, first in aliases.items()
        ]
    done = (
        {(r["model"], int(r["size"])): r for r in read_cases(settings.out)}
        if settings.resume
        else {}
    )
    rows: list[dict] = []
    states = {name: _ModelState() for name in names}
    scenes: dict[int, Path | None] = {}

    def scene_of(size: int) -> Path | None:
        if size not in scenes:
            try:
                scenes[size] = organ_scene_file(settings.meshes, size, settings.max_memory)
            except (subprocess.SubprocessError, OSError) as exc:
                log(f"  {size:>8} no mesh: {exc}")
                scenes[size] = None
        return scenes[size]

    previous = signal.signal(signal.SIGTERM, _stop)  # a timeout's SIGTERM: stop cleanly
    try:
        _run_sizes(sizes, names, states, done, rows, settings, t0, scene_of, warmup, log)
    except KeyboardInterrupt:
        log("bench scale: stopped; writing what was measured")
        write_outputs(pd.DataFrame(rows), settings, time.perf_counter() - t0, command(settings))
        raise
    finally:
        signal.signal(signal.SIGTERM, previous)
    log(f"bench scale: {time.perf_counter() - t0:.0f} s, load average {_load()}")
    return pd.DataFrame(rows)


def command(settings) -> str:
    """The ``springfem bench scale`` command line of ``settings`` (the report names it).

    Examples
    --------
    >>> command(ScaleSettings(budget=1380, cost_laws=Path("studies/cost_laws.json")))
    'springfem bench scale --budget 1380 --cost-laws studies/cost_laws.json'
    """
    parts = ["springfem bench scale"]
    if tuple(settings.sizes) != DEFAULT_SIZES:
        parts.append("--sizes " + ",".join(str(int(n)) for n in settings.sizes))
    if settings.models:
        parts.append("--models " + ",".join(settings.models))
    if settings.max_time != DEFAULT_MAX_TIME:
        parts.append(f"--max-time {settings.max_time:g}")
    if settings.reference_time is not None:
        parts.append(f"--reference-time {settings.reference_time:g}")
    if settings.max_memory != DEFAULT_MAX_MEMORY:
        parts.append(f"--max-memory {settings.max_memory / 1e9:g}")
    if settings.budget is not None:
        parts.append(f"--budget {settings.budget:g}")
    if Path(settings.out) != DEFAULT_OUT:
        parts.append(f"--out {settings.out}")
    if Path(settings.meshes) != DEFAULT_MESHES:
        parts.append(f"--meshes {settings.meshes}")
    if settings.cost_laws is not None:
        parts.append(f"--cost-laws {settings.cost_laws}")
    return " ".join(parts)


def _stop(signum, frame) -> None:
    raise KeyboardInterrupt(f"signal {signum}")


def _run_sizes(sizes, names, states, done, rows, settings, t0, scene_of, warmup, log) -> None:
    """The cases of every size, smallest first (:func:`bench_scale`); outputs after each."""
    from .bench_scale_output import write_outputs

    for size in sizes:
        for name in names:
            state = states[name]
            old = done.get((name, size))
            if old is not None and not str(old["status"]).startswith("not run: budget"):
                rows.append(old)
                state.update(old)
                log(_case_line(old) + "  (kept)")
                continue
            mine = [r for r in rows if r["model"] == name]
            row = _next_case(name, size, mine, state, settings, t0, scene_of, warmup)
            rows.append(row)
            state.update(row)
            log(_case_line(row))
        write_outputs(pd.DataFrame(rows), settings, time.perf_counter() - t0, command(settings))


@dataclass
class _ModelState:
    """Where a model is in the run: why its static solve is no longer tried (``""``: it
    is), and whether its explicit step still is (a step-only case at the sizes its static
    solve does not fit in time)."""

    static_stop: str = ""
    step: bool = True
    step_only_ok: bool = True

    def update(self, row: dict) -> None:
        status = str(row["status"])
        if status.startswith("not run: budget"):
            return
        if "case wall (s)" in row and np.isfinite(row["case wall (s)"]):  # a case that ran
            self.step = self.step and bool(np.isfinite(row["step (s)"]))
        if not self.static_stop and status not in SOLVED:
            self.static_stop = status
            # the step is still worth its own case when the static solve ran out of time
            self.step_only_ok = status.startswith(DID_NOT_FIT) and "memory" not in status
            if "predicted" in status and "GB" in str(row["message"]):
                self.step_only_ok = False


def _next_case(name: str, size: int, mine: list[dict], state: _ModelState,
               settings: ScaleSettings, t0: float, scene_of, warmup: Path) -> dict:  # fmt: skip
    """The next case of model ``name``: run in full, step only, or not run (and why)."""
    left = None if settings.budget is None else settings.budget - (time.perf_counter() - t0)
    ran = [r for r in mine if np.isfinite(r["case wall (s)"])]
    last = ran[-1] if ran else None
    overhead = 30.0
    if last is not None:  # its set-up and step, grown with the mesh above a fixed start-up
        extra = float(last["case wall (s)"]) - np.nan_to_num(last["static (s)"]) - 8.0
        overhead = 8.0 + max(extra, 0.0) * size / float(last["tets"])
    predicted = predict(mine, size)
    values = {"predicted static (s)": predicted[0], "predicted memory (bytes)": predicted[1]}
    cap = settings.reference_cap if name == settings.reference else settings.max_time
    status, why = state.static_stop, "a smaller size did not fit"
    if not status:
        why = _over(predicted, settings, cap)
        if not why:
            need = np.nan_to_num(predicted[0]) + overhead
            if left is not None and need > left:
                return _row(name, size, size, "not run: budget",
                            f"needs about {need:.0f} s, {left:.0f} s of the budget left",
                            **values)  # fmt: skip
            scene = scene_of(size)
            if scene is None:
                return _row(name, size, size, "not run: no mesh", "gmsh failed", **values)
            res = run_case(scene, name, warmup, cap, settings.max_memory)
            return measured_row(name, size, res, cap, settings.max_memory,
                                predicted)  # fmt: skip
        status = f"{DID_NOT_FIT}: predicted"
        step_only = state.step and "GB" not in why
    else:
        step_only = state.step and state.step_only_ok
        if status.startswith("not run") or not status.startswith(DID_NOT_FIT):
            status, why = "not run: failed at a smaller size", "a smaller size failed"
        elif "predicted" not in status:
            status = f"{DID_NOT_FIT}: after a smaller size"
    if not step_only or not ran:
        return _row(name, size, size, status, why, **values)
    if left is not None and overhead > left:
        return _row(name, size, size, status, f"{why}; step not run (budget)", **values)
    scene = scene_of(size)
    if scene is None:
        return _row(name, size, size, status, f"{why}; no mesh for the step", **values)
    res = run_case(scene, name, warmup, cap, settings.max_memory,
                   step_only=True)  # fmt: skip
    row = measured_row(name, size, res, cap, settings.max_memory, predicted)
    row.update(status=status, message=f"{why}; step only", **{"static (s)": np.nan})
    if "step" not in res.stages:
        row["message"] = f"{why}; step failed: {classify(res, 1e9, settings.max_memory)[1]}"
    return row


def _over(predicted: tuple[float, float], settings: ScaleSettings, cap: float) -> str:
    t, m = predicted
    if np.isfinite(m) and m > settings.max_memory:
        return f"predicted {m / 1e9:.3g} GB > the {settings.max_memory / 1e9:g} GB cap"
    if np.isfinite(t) and t > FAR * cap:
        return f"predicted {t:.3g} s > {FAR:g}x the {cap:g} s cap"
    return ""


def _load() -> str:
    return " ".join(f"{v:.2f}" for v in os.getloadavg())


def _case_line(row: dict) -> str:
    if not np.isfinite(row["case wall (s)"]):  # not run
        return f"  {int(row['tets']):>8} {row['model']:<22} {row['status']:<22} {row['message']}"
    step = row["step (s)"]
    step_text = f"step {step * 1e3:8.3f} ms" if np.isfinite(step) else " " * 16
    static = row["static (s)"]
    static_text = f"static {static:8.2f} s" if np.isfinite(static) else " " * 17
    return (
        f"  {int(row['tets']):>8} {row['model']:<22} {row['status']:<22} {static_text} "
        f"{step_text} peak {row['peak memory (bytes)'] / 1e9:6.2f} GB  "
        f"load {row['load average']:.2f}  ({row['case wall (s)']:.0f} s)"
        + (f"  {row['message'][:80]}" if row["status"] not in SOLVED else "")
    )
