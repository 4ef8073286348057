"""``springfem verdict SCENE --frame-rate HZ``: the most accurate fast model that runs at the
user's frame rate on the user's mesh.

The flow, one pass:

1. **Plan.** The run's length (the scene's ``[dynamics] t_end``, else the end of its load
   history plus the settling time :data:`SETTLE`), the frame ``1 / rate``, the dynamic
   reference's time step and its predicted time; the fast models to weigh.
2. **Reference.** The converged dynamic reference (:func:`studies.realtime.reference_motion`:
   implicit P2, or P2/P1 mixed for a nearly incompressible material) over the run, sampled
   at the frames.
3. **Models.** For each fast model (every registered model weighed by default that has frames
   or an explicit form), :func:`studies.realtime.weigh`: the settings whose cost per frame on
   this machine fits the frame, run over the scene's history; probe and field error against
   the reference, energy drift, stability.
4. **Sentence.** The most accurate model that fits (and stays stable); or, if none does, the
   nearest miss and what it would need: a step so many times faster, or about so many tets
   (cost per frame taken as proportional to the tets).

Examples
--------
>>> import pandas as pd
>>> t = pd.DataFrame({"fits": [True, False], "stable": [True, True],
...     "probe error": [0.031, 0.002], "ms per frame": [9.0, 41.0],
...     "settings": ["20 x 1", "safety 0.9"]}, index=["xpbd", "P1-NH"])
>>> frame_sentence(t, 60.0, 5012)
'At 60 Hz on this 5,012-tet mesh, xpbd (20 x 1) is the most accurate model that runs in \
real time: 3.1 % probe error, 9 ms of the 16.7 ms frame.'
>>> frame_sentence(t.assign(fits=[False, False], **{"ms per frame": [25.0, 41.0]}), 60.0, 5012)
'No model runs at 60 Hz on this 5,012-tet mesh. The nearest is xpbd (20 x 1) at 25 ms a \
frame, 1.5x the 16.7 ms frame: it would need a 1.5x faster frame, or about 3,300 tets.'
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from springfem.errors import InputError, SolverError
from springfem.files import atomic_write_text
from springfem.mechanics.limits import SolveStopped
from springfem.scene import Scene

from . import realtime

#: Seconds of free motion after the last change of the loads, when the scene sets no t_end.
SETTLE = 0.3
#: The share of the budget the reference may use (the models get the rest).
REFERENCE_SHARE = 0.7
#: The reference is not started when its prediction is this many times the time it may use
#: (the prediction is rough; the cap stops a run that overshoots).
SKIP_FACTOR = 3.0
#: Reference time steps per frame at most (the reference's step is also bounded by its own
#: accuracy: :func:`studies.realtime.reference_step`).
COLUMNS = ["settings", "ms per frame", "fits", "stable", "probe error", "field error",
           "energy error", "note"]  # fmt: skip


@dataclass
class FrameVerdict:
    """The frame-rate verdict of one scene.

    Attributes
    ----------
    scene, rate, tets
        What was weighed, at which frame rate, on how many tets.
    reference
        The reference's description (method, step, error estimate), or why there is none.
    table
        One row per fast model (:data:`COLUMNS`).
    pick
        The most accurate model that fits, or ``None``.
    sentence
        The answer in words.
    plan
        The plan's lines.
    """

    scene: str
    rate: float
    tets: int
    reference: str
    table: pd.DataFrame
    pick: str | None
    sentence: str
    plan: list[str] = field(default_factory=list)

    def to_json(self) -> str:
        """Everything, as JSON (every model's numbers)."""
        rows = json.loads(self.table.to_json(orient="index"))
        return json.dumps({"scene": self.scene, "frame_rate": self.rate, "tets": self.tets,
                           "reference": self.reference, "pick": self.pick,
                           "sentence": self.sentence, "plan": self.plan, "models": rows},
                          indent=2)  # fmt: skip


def run_length(scene: Scene) -> float:
    """The run's length: the scene's ``[dynamics] t_end``, else the time the loads stop
    changing plus :data:`SETTLE`."""
    from springfem.frames import LoadHistory
    from springfem.scene.dynamics import DynamicsOptions

    if "t_end" in (scene.raw.get("dynamics") or {}):
        return float(DynamicsOptions.of(scene).t_end)
    return LoadHistory(scene).settles_at() + SETTLE


def fast_models(scene: Scene, names: Sequence[str] | None = None) -> list[Any]:
    """The models to weigh: ``names``, else the static verdict's candidates
    (:func:`studies.verdict.candidate_models`) but the second-order FEM (references, not
    fast models)."""
    from . import models
    from .verdict import candidate_models

    chosen = list(names) if names else candidate_models(scene)
    out = []
    for n in chosen:
        m = models.get(n)
        if not names and (getattr(m, "order", None) == 2 or "P2" in m.name):
            continue
        out.append(_plugin(m))
    return out


def _plugin(m: Any) -> Any:
    return getattr(m, "plugin", None) or m


def _order(m: Any) -> int | None:
    return getattr(m, "order", None)


def frame_sentence(table: pd.DataFrame, rate: float, tets: int) -> str:
    """The verdict in words (see the module docstring)."""
    budget = 1e3 / rate
    head = f"{rate:g} Hz on this {tets:,}-tet mesh"
    ok = table[table["fits"].astype(bool) & table["stable"].astype(bool)]
    ok = ok[np.isfinite(ok["probe error"].astype(float))]
    if len(ok):
        name = str(ok["probe error"].astype(float).idxmin())
        r = ok.loc[name]
        return (f"At {head}, {name} ({r['settings']}) is the most accurate model that runs in "
                f"real time: {100 * float(r['probe error']):.2g} % probe error, "
                f"{float(r['ms per frame']):.3g} ms of the {budget:.3g} ms frame.")  # fmt: skip
    timed = table[np.isfinite(table["ms per frame"].astype(float))]
    if not len(timed):
        return f"No model could be timed at {head}."
    name = str(timed["ms per frame"].astype(float).idxmin())
    r = timed.loc[name]
    over = float(r["ms per frame"]) / budget
    need = float(f"{tets / over:.2g}") if over > 1 else tets
    why = "" if over > 1 else " (it fits, but did not stay stable)"
    fewer = f", or about {need:,.0f} tets" if need >= 100 else ""
    ms = float(r["ms per frame"])
    return (f"No model runs at {head}. The nearest is {name} ({r['settings']}) at {ms:.3g} ms "
            f"a frame, {over:.2g}x the {budget:.3g} ms frame{why}: it would need a {over:.2g}x "
            f"faster frame{fewer}.")  # fmt: skip


def _settings_text(s: dict[str, Any]) -> str:
    if "iterations" in s:
        n = s["substeps"]
        return f"{n} substep{'s' if n != 1 else ''} x {s['iterations']}"
    if "safety" in s:
        n = s.get("substeps", "?")
        return f"{n} step{'s' if n != 1 else ''} of {s['safety']:g} dt_crit"
    return ", ".join(f"{k} {v}" for k, v in s.items()) or "default"


def frame_verdict(
    scene: Scene,
    rate: float,
    *,
    names: Sequence[str] | None = None,
    budget: float | None = 600.0,
    log: Callable[[str], None] = print,
    reference: Callable[..., tuple[realtime.Motion, str]] | None = None,
) -> FrameVerdict:
    """Weigh the fast models at ``rate`` frames per second (see the module docstring).

    Parameters
    ----------
    scene
        The scene, with a load history (time functions) or a constant load.
    rate
        Frames per second (60 for a picture, 500-1000 for haptics).
    names
        Models to weigh (default: :func:`fast_models`).
    budget
        Seconds for the whole verdict (``None``: no limit); each model gets the time left.
    log
        Where the plan and progress lines go.
    reference
        ``reference(scene, t_end, frame_dt, scale) -> (Motion, description)``; default
        :func:`studies.realtime.reference_motion`.

    Returns
    -------
    FrameVerdict
    """
    if not rate > 0:
        raise InputError(f"--frame-rate must be > 0 frames per second (got {rate:g})")
    start = time.monotonic()
    deadline = None if budget is None else start + float(budget)
    tets = scene.mesh.n_tets
    t_end = run_length(scene)
    frame_dt = 1.0 / rate
    scale = realtime.load_factor(scene)
    candidates = fast_models(scene, names)
    plan = [f"frame-rate verdict of {scene.name}: {tets:,} tets, {rate:g} Hz "
            f"({1e3 * frame_dt:.3g} ms a frame), run of {t_end:.3g} s "
            f"({int(round(t_end / frame_dt))} frames)",
            "models: " + ", ".join(m.name for m in candidates)]  # fmt: skip
    ref_line, ref_seconds = realtime.reference_plan(scene, t_end, frame_dt)
    plan.insert(1, ref_line)
    room = None if deadline is None else REFERENCE_SHARE * (deadline - time.monotonic())
    if room is not None and ref_seconds > SKIP_FACTOR * room:
        plan.append(f"the reference would take about {ref_seconds:.3g} s, more than the "
                    f"{room:.3g} s it may use of the budget: the models are timed, not weighed "
                    "(--budget)")  # fmt: skip
    for line in plan:
        log(line)
    ref: realtime.Motion | None = None
    if room is None or ref_seconds <= SKIP_FACTOR * room:
        try:
            if reference is None:
                ref, ref_text = realtime.reference_motion(scene, t_end, frame_dt, scale, room)
            else:
                ref, ref_text = reference(scene, t_end, frame_dt, scale)
        except (SolveStopped, SolverError) as exc:
            ref_text = f"not finished: {str(exc)[:160]}"
    else:
        ref_text = f"not run: it would take about {ref_seconds:.3g} s"
    log(f"reference: {ref_text} ({time.monotonic() - start:.1f} s)")
    rows = {}
    for m in candidates:
        if deadline is not None and time.monotonic() > deadline:
            rows[m.name] = _row({}, np.nan, False, False, {}, "skipped (budget)")
            continue
        why = m.applies(scene) if hasattr(m, "applies") else None
        if why:
            rows[m.name] = _row({}, np.nan, False, False, {}, f"not applicable: {why}")
            continue
        t0 = time.monotonic()
        r = realtime.weigh(m, scene, rate=rate, t_end=t_end, scale=scale, reference=ref,
                           deadline=deadline)  # fmt: skip
        if ref is None and not r.message:
            r.message = "fits the frame; error not measured (no reference)"
        fits = bool(np.isfinite(r.seconds_per_frame) and r.seconds_per_frame <= frame_dt)
        rows[m.name] = _row(r.settings, r.seconds_per_frame, fits, r.stable, r.errors, r.message)
        e = r.errors.get("probe", float("nan"))
        log(f"  {m.name}: {_settings_text(r.settings)}, {1e3 * r.seconds_per_frame:.3g} ms a "
            f"frame, probe error {100 * e:.3g} % ({time.monotonic() - t0:.1f} s)")  # fmt: skip
    table = pd.DataFrame.from_dict(rows, orient="index", columns=COLUMNS)
    sentence = frame_sentence(table, rate, tets)
    if ref is None:
        fit = [str(n) for n in table.index[table["fits"].astype(bool)]]
        sentence = (f"No dynamic reference within the budget ({ref_text}), so no error is "
                    f"measured. At {rate:g} Hz on this {tets:,}-tet mesh these models fit the "
                    f"frame: {', '.join(fit) or 'none'}.")  # fmt: skip
    pick = None
    if sentence.startswith("At "):
        ok = table[table["fits"].astype(bool) & table["stable"].astype(bool)]
        pick = str(ok["probe error"].astype(float).idxmin())
    return FrameVerdict(scene.name, rate, tets, ref_text, table, pick, sentence, plan)


def _row(settings: dict[str, Any], spf: float, fits: bool, stable: bool,
         errors: dict[str, float], note: str) -> list[Any]:  # fmt: skip
    return [_settings_text(settings) if settings else "", 1e3 * spf, fits, stable,
            errors.get("probe", np.nan), errors.get("field", np.nan),
            errors.get("energy", np.nan), note]  # fmt: skip


def write_frame_verdict(v: FrameVerdict, out: Path) -> Path:
    """``frame-verdict.md`` and ``frame-verdict.json`` in ``out`` (atomic writes)."""
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / "frame-verdict.json", v.to_json())
    t = v.table.copy()
    for c in ("probe error", "field error", "energy error"):
        t[c] = [f"{100 * x:.3g} %" if math.isfinite(x) else "" for x in t[c].astype(float)]
    t["ms per frame"] = [f"{x:.3g}" if math.isfinite(x) else "" for x in t["ms per frame"]]
    md = "\n".join([f"# Frame-rate verdict: {v.scene} at {v.rate:g} Hz", "", v.sentence, "",
                    "## Plan", "", *[f"- {p}" for p in v.plan], f"- reference: {v.reference}",
                    "", "## Models", "", t.to_markdown(), ""])  # fmt: skip
    path = out / "frame-verdict.md"
    atomic_write_text(path, md)
    return path
