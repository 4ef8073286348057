"""Study ``frame_budget``: every fast model's error against its cost per frame, at 60 Hz
(a picture) and 1 kHz (haptics), against the converged dynamic reference.

On each scene (bundled: ``pull-release``, a tool pulling a patch of a soft block and letting
go, and ``organ-settle``, a gmsh organ settling under gravity from rest; or the user's
``--scene`` with its load history), at each frame rate, the dynamic reference
(:func:`studies.realtime.reference_motion`: implicit P2, P2/P1 for a nearly incompressible
material) is run once, and each fast model runs the scene's history frame by frame at each
of its frame settings (:func:`springfem.frames.frames_settings`: an explicit form at
fractions of its critical step, XPBD, VBD and PD at substeps x iterations). A point of the
chart is one setting: its median wall time of a frame on this machine, and its RMS probe
error over the run against the reference. The vertical line is the frame's budget: points
left of it run in real time here.

The errors do not depend on the machine; the costs do (and on its load, printed in the
findings). The headline keeps, per model and rate, the smallest error over its settings
and the cost of its cheapest frame.

Examples
--------
>>> [s.label for s in bundled_scenes(Settings.quick())]
['pull-release']
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from springfem.frames import LoadHistory, frame_stepper, frames_settings

from . import models
from .realtime import Motion, energy_error, frame_run, reference_motion, trajectory_error
from .registry import StudyContext, StudyOutput, study
from .scenes import StudyScene, case_scene
from .tables import pyplot
from .verdict_frames import fast_models, frame_sentence, run_length

VERSION = 1
#: The fraction of P1-NH's critical step of the floor run (time-converged on the mesh).
FLOOR_SAFETY = 0.1
#: The fast models of the bundled scenes (those registered and applicable are weighed).
MODELS = ("P1-NH", "spring-exact", "corotational", "mass-spring", "xpbd", "vbd", "pd")


@dataclass(frozen=True)
class Settings:
    """Scenes (bundled name -> changes), frame rates, run length (``None``: the scene's),
    models (``None``: :data:`MODELS` on bundled scenes, the verdict's on a user's), and at
    most how many frame settings of each model."""

    scenes: dict[str, dict[str, Any]] = field(
        default_factory=lambda: {"pull-release": {}, "organ-settle": {"dynamics.t_end": 0.5}}
    )
    rates: tuple[float, ...] = (60.0, 1000.0)
    t_end: float | None = None
    models: tuple[str, ...] | None = MODELS
    per_model: int = 8

    @classmethod
    def full(cls) -> Settings:
        """Both bundled scenes, 60 Hz and 1 kHz, up to eight settings a model."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """The pull on a 192-tet block for 0.08 s, three models, two settings each."""
        return cls(
            scenes={"pull-release": {"mesh.divisions": [4, 4, 2], "dynamics.dt": 2e-3}},
            t_end=0.08,
            models=("P1-NH", "xpbd", "vbd"),
            per_model=2,
        )


def bundled_scenes(s: Settings) -> list[StudyScene]:
    """The settings' bundled scenes with their changes."""
    return [StudyScene.bundled(name, changes) for name, changes in s.scenes.items()]


def _settings_of(model: Any, n: int) -> list[dict[str, Any]]:
    """At most ``n`` of the model's frame settings, spread from cheapest to dearest."""
    all_ = frames_settings(model)
    if len(all_) <= n:
        return all_
    return [all_[int(round(i))] for i in np.linspace(0, len(all_) - 1, n)]


def _motion_dict(m: Motion) -> dict[str, Any]:
    return {
        "times": m.times.tolist(),
        "probes": m.probes.tolist(),
        "field": None if m.field is None else m.field.tolist(),
        "field_times": np.asarray(getattr(m, "field_times", m.times)).tolist(),
        "energy": None if m.energy is None else m.energy.tolist(),
        "scale": m.scale,
    }


def _motion(d: dict[str, Any]) -> Motion:
    m = Motion(
        np.asarray(d["times"]),
        np.asarray(d["probes"]),
        None if d["field"] is None else np.asarray(d["field"]),
        None if d["energy"] is None else np.asarray(d["energy"]),
        d["scale"],
    )
    m.field_times = np.asarray(d["field_times"])  # type: ignore[attr-defined]
    return m


def reference_case(case: dict[str, Any]) -> dict[str, Any]:
    """The dynamic reference of the case's scene at its rate, and the mesh's floor: explicit
    P1-NH at :data:`FLOOR_SAFETY` of its critical step (P1 converged in time on this mesh;
    what is left of its error is the mesh's)."""
    scene = case_scene(case)
    history = LoadHistory(scene)
    motion, text = reference_motion(scene, case["t_end"], 1.0 / case["rate"], history)
    floor = float("nan")
    stepper = frame_stepper(models.get("P1-NH"), scene, 1.0 / case["rate"], safety=FLOOR_SAFETY)
    if stepper is not None:
        r = frame_run(stepper, scene, case["t_end"], history)
        if r.stable and r.motion is not None:
            floor = trajectory_error(r.motion, motion)["probe"]
    return {"motion": _motion_dict(motion), "text": text, "floor": floor}


def model_case(case: dict[str, Any]) -> dict[str, Any]:
    """One model at one frame setting over the run: cost per frame and motion."""
    scene = case_scene(case)
    m = models.get(case["model"])
    m = getattr(m, "plugin", None) or m
    history = LoadHistory(scene)
    try:
        stepper = frame_stepper(m, scene, 1.0 / case["rate"], **case["settings"])
    except Exception as exc:  # noqa: BLE001 - a model that cannot step is a row
        return {"status": f"no frames: {str(exc)[:120]}"}
    if stepper is None:
        return {"status": "no frames"}
    x, v = stepper.start()
    stepper.frame(x, v, 0.0, history)  # warm: compiled kernels
    r = frame_run(stepper, scene, case["t_end"], history, model=m.name)
    return {
        "status": "ok" if r.stable else f"unstable: {r.message}",
        "ms": 1e3 * r.seconds_per_frame,
        "settings": dict(stepper.settings),
        "motion": _motion_dict(r.motion) if r.motion is not None else None,
    }


def _known(name: str) -> bool:
    try:
        models.get(name)
    except Exception:  # noqa: BLE001 - a plug-in not installed here
        return False
    return True


def _label(s: dict[str, Any]) -> str:
    if "iterations" in s:
        return f"{s['substeps']}x{s['iterations']}"
    return f"{s.get('safety', '')} dt_crit"


@study("frame_budget", Settings, bundled_scenes, serial=True)
def run(ctx: StudyContext, scenes: list[StudyScene], s: Settings) -> StudyOutput:
    """Weigh each fast model's frame settings against the dynamic reference, per rate."""
    rows, findings, figures, headline = [], [], [], {}
    tets: dict[str, int] = {}
    floors: dict[tuple[str, float], float] = {}
    load = os.getloadavg()[0]
    for sc in scenes:
        scene = sc.build()
        t_end = s.t_end or run_length(scene)
        names = [n for n in s.models if _known(n)] if s.models and not sc.user else None
        tets[sc.label] = scene.mesh.n_tets
        weighed = fast_models(scene, names)
        refs = ctx.cache.run(
            [
                sc.case("frame_budget", VERSION, kind="reference", rate=r, t_end=t_end)
                for r in s.rates
            ],
            reference_case,
            ctx.progress,
            "references",
        )
        for rate, ref in zip(s.rates, refs, strict=True):
            reference = _motion(ref["motion"])
            cases = [
                sc.case(
                    "frame_budget",
                    VERSION,
                    kind="model",
                    rate=rate,
                    t_end=t_end,
                    model=m.name,
                    settings=st,
                )
                for m in weighed
                if not (m.applies(scene) if hasattr(m, "applies") else None)
                for st in _settings_of(m, s.per_model)
            ]
            results = ctx.cache.run(cases, model_case, ctx.progress, f"models at {rate:g} Hz")
            for c, r in zip(cases, results, strict=True):
                row = {
                    "scene": sc.label,
                    "rate": rate,
                    "model": c["model"],
                    "settings": _label(r.get("settings", c["settings"])),
                    "ms per frame": r.get("ms", np.nan),
                    "status": r["status"],
                }
                if r.get("motion") and r["status"] == "ok":
                    motion = _motion(r["motion"])
                    err = trajectory_error(motion, reference)
                    row.update(
                        {
                            "probe error": err["probe"],
                            "field error": err.get("field"),
                            "energy error": energy_error(motion, reference),
                        }
                    )
                rows.append(row)
            floors[(sc.label, rate)] = ref["floor"]
            headline[f"{sc.label}_{rate:g}Hz_P1-NH_floor"] = float(ref["floor"])
            findings.append(
                f"{sc.label}, {rate:g} Hz: reference {ref['text']}; P1-NH converged "
                f"in time on this mesh is {100 * ref['floor']:.3g} % off it (the "
                "mesh's floor for a P1 model)."
            )
    df = pd.DataFrame(rows)
    if df.empty:
        return StudyOutput(ctx.name, "Frame budget", ["no model could step these scenes"])
    df["fits"] = df["ms per frame"] <= 1e3 / df["rate"]
    df["stable"] = df["status"] == "ok"
    for (label, rate), g in df.groupby(["scene", "rate"], sort=False):
        best = g.sort_values("probe error").groupby("model").head(1).set_index("model")
        fitting = g[g["fits"] & g["stable"]].sort_values("probe error")
        table = (fitting if len(fitting) else g).groupby("model").head(1).set_index("model")
        findings.append(
            frame_sentence(table, rate, tets[label]) + f" (load average {load:.1f} while timing.)"
        )
        for m, r in best.iterrows():
            headline[f"{label}_{rate:g}Hz_{m}_error_min"] = float(r["probe error"])
            cheap = g[g["model"] == m]["ms per frame"].min()
            headline[f"{label}_{rate:g}Hz_{m}_ms_min"] = float(cheap)
    for label, g in df.groupby("scene", sort=False):
        floor = {r: floors[(str(label), r)] for r in s.rates}
        figures.append(
            ctx.figure(
                _chart(g, s.rates, floor),
                f"frame-budget-{label}.png",
                f"{label}: probe error against the cost of a frame, each point "
                "one setting of a model; left of the dashed line runs in real time; the dotted "
                "line is P1-NH converged in time on the mesh.",
            )
        )
    tables = [
        ctx.table(
            df.drop(columns=["fits", "stable"]),
            "frame-budget",
            "Every model's frame settings: cost per frame, errors, status.",
        )
    ]
    return StudyOutput(
        ctx.name, "Frame budget: error against cost per frame", findings, tables, figures, headline
    )


def _chart(g: pd.DataFrame, rates: tuple[float, ...], floor: dict[float, float]):
    plt = pyplot()
    fig, axes = plt.subplots(1, len(rates), figsize=(5.5 * len(rates), 4.2), squeeze=False)
    for ax, rate in zip(axes[0], rates, strict=True):
        part = g[(g["rate"] == rate) & g["stable"]].dropna(subset=["probe error"])
        for m, pts in part.groupby("model", sort=False):
            pts = pts.sort_values("ms per frame")
            ax.semilogx(pts["ms per frame"], 100 * pts["probe error"], "o-", label=m, ms=4)
        ax.axvline(1e3 / rate, color="k", ls="--", lw=1)
        if np.isfinite(floor.get(rate, np.nan)):
            ax.axhline(100 * floor[rate], color="grey", ls=":", lw=1)
        ax.text(1e3 / rate, ax.get_ylim()[1], f" {rate:g} Hz budget", va="top", fontsize=8)
        ax.set_xlabel("wall time of a frame (ms)")
        ax.set_ylabel("RMS probe error vs dynamic reference (%)")
        ax.set_title(f"{rate:g} Hz frames")
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    return fig
