"""``springfem bench frames``: every fast model's cost per frame on organ meshes of several
sizes, interleaved.

For each size (gmsh organs of :func:`springfem.mesh.organ.organ_scene`, neo-Hookean,
ν = 0.49, gravity) and each fast model at its default frame settings (an explicit form:
substeps of 0.9 of its critical step at rest; XPBD, VBD, PD: their own substeps and
iterations), a stepper is built and warmed, then every round times ``frames`` frames of
each model from rest (the organ sags under gravity: a long run would time a crumpled
organ), in a shuffled order. The table gives the median milliseconds per frame, the
median of the per-round ratios to explicit P1-NH's frame, and how many frames per second
that is. The machine's load average is printed beside it (other work inflates every wall
time; the ratios move less).

Examples
--------
>>> ratios = per_round_ratios({"a": [2.0, 4.0], "b": [1.0, 1.0]}, "b")
>>> ratios["a"]
3.0
"""

from __future__ import annotations

import os
import random
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from springfem.frames import frame_stepper, frames_settings

#: Mesh sizes (tets, about) of the default run.
SIZES = (1_000, 10_000, 50_000)
#: The fast models weighed by default (those registered are used).
MODELS = ("P1-NH", "spring-exact", "corotational", "mass-spring", "xpbd", "vbd", "pd")
#: The model the ratios are taken against.
BASE = "P1-NH"


def per_round_ratios(times: dict[str, list[float]], base: str) -> dict[str, float]:
    """The median over rounds of each model's time over ``base``'s in the same round."""
    b = np.asarray(times[base])
    return {m: float(np.nanmedian(np.asarray(t) / b)) for m, t in times.items()}


def _default_settings(model: Any) -> dict[str, Any]:
    if callable(getattr(model, "frames", None)):
        return {}
    return dict(frames_settings(model)[0])


def bench_frames(
    sizes: Sequence[int] = SIZES,
    names: Sequence[str] = MODELS,
    rate: float = 60.0,
    rounds: int = 3,
    frames: int = 2,
    log=print,
) -> list[dict[str, Any]]:
    """Rows ``{tets, model, settings, ms_per_frame, ratio, fps}`` (see the module docstring).

    Parameters
    ----------
    sizes
        Organ mesh sizes (tets, about).
    names
        Models (those not registered or not applicable are left out, with a line).
    rate
        Frames per second (the frame length's only use: the substeps of an explicit form).
    rounds, frames
        Timing rounds, and frames timed per model per round.
    log
        Progress lines.
    """
    from springfem.mesh.organ import organ_scene
    from springfem.scene import load_scene

    from . import models

    rows: list[dict[str, Any]] = []
    frame_dt = 1.0 / rate
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            scene = load_scene(organ_scene(Path(tmp) / f"organ-{n}", tets=n))
            tets = scene.mesh.n_tets
            steppers: dict[str, Any] = {}
            for name in names:
                try:
                    m = models.get(name)
                except Exception as exc:  # noqa: BLE001 - an absent plug-in is a line
                    log(f"  {name}: not registered ({str(exc)[:80]})")
                    continue
                m = getattr(m, "plugin", None) or m
                why = m.applies(scene) if hasattr(m, "applies") else None
                if why:
                    log(f"  {name}: not applicable ({why[:80]})")
                    continue
                t0 = time.perf_counter()
                st = frame_stepper(m, scene, frame_dt, **_default_settings(m))
                if st is None:
                    log(f"  {name}: no frames")
                    continue
                x, v = st.start()
                st.frame(x, v, 0.0, lambda t: 1.0)  # warm: compiled kernels, caches
                steppers[name] = (st, x, v)
                took = time.perf_counter() - t0
                log(f"  {name} on {tets:,} tets: built and warm in {took:.1f} s")
            times: dict[str, list[float]] = {k: [] for k in steppers}
            for _ in range(rounds):
                order = list(steppers)
                random.shuffle(order)
                for name in order:
                    st = steppers[name][0]
                    x, v = st.start()  # from rest each round: the first frames of a run
                    t0 = time.perf_counter()
                    try:
                        for k in range(frames):
                            st.frame(x, v, k * frame_dt, lambda t: 1.0)
                    except Exception as exc:  # noqa: BLE001 - a failing model is a line
                        log(f"  {name}: failed ({str(exc)[:100]})")
                        times[name].append(float("nan"))
                        continue
                    times[name].append((time.perf_counter() - t0) / frames)
            ratios = per_round_ratios(times, BASE) if BASE in times else {}
            for name, t in times.items():
                ms = 1e3 * float(np.nanmedian(t)) if np.isfinite(t).any() else float("nan")
                rows.append({"tets": tets, "model": name,
                             "settings": dict(steppers[name][0].settings),
                             "ms_per_frame": ms, "ratio": ratios.get(name, float("nan")),
                             "fps": 1e3 / ms})  # fmt: skip
                log(f"  {name:>14} {tets:>8,} tets: {ms:9.3g} ms a frame "
                    f"({ratios.get(name, float('nan')):.3g}x {BASE})")  # fmt: skip
    return rows


def frames_markdown(rows: list[dict[str, Any]], rate: float = 60.0) -> str:
    """A Markdown table: one row per model, one column per mesh size (ms a frame)."""
    sizes = sorted({r["tets"] for r in rows})
    names = list(dict.fromkeys(r["model"] for r in rows))
    head = "| model | " + " | ".join(f"{s:,} tets" for s in sizes) + " |"
    lines = [head, "|---|" + "---:|" * len(sizes)]
    for m in names:
        cells = []
        for s in sizes:
            r = next((r for r in rows if r["model"] == m and r["tets"] == s), None)
            cells.append("" if r is None else f"{r['ms_per_frame']:.3g} ms ({r['ratio']:.2g}x)")
        lines.append(f"| {m} | " + " | ".join(cells) + " |")
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    lines.append("")
    lines.append(f"Milliseconds a frame at {rate:g} Hz (ratio to {BASE}'s frame); load "
                 f"average {load:.2f}.")  # fmt: skip
    return "\n".join(lines)
