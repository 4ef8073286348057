"""The largest XPBD substep that survives, beside the explicit models' critical step.

XPBD integrates by constraint projection, not by forces, so there is no linear-stability
bound to bisect around; what is measured is the largest substep ``h = dt / substeps`` that a
run survives, in units of ``2 / omega_max`` of XPBD's own energy as a mechanical system
(:class:`peers.xpbd.StableNeoHookean`, the step an explicit integrator of the same energy
could take). The run is the explicit series' test: loads off, undamped, ``steps`` substeps
from the rest shape with the same tiny random velocity. It **survives** when the positions
stay finite, no element is inverted at any frame end, and the energy (kinetic + stable
neo-Hookean strain) never exceeds :data:`GROWTH` times its initial value (XPBD dissipates;
an unstable run grows exponentially, by many orders of magnitude within the run).

Only ``h`` matters: a frame of ``substeps`` substeps advances exactly as ``substeps`` frames
of one (the multipliers restart every substep), so the runs use frames of one substep. The
search starts at half the bound, halves down while that fails, doubles up while it survives
(at most to :data:`TOP` times the bound), then bisects geometrically between the last
survivor and the first failure.

Examples
--------
>>> sorted(VARIANTS)
['xpbd', 'xpbd-jacobi']
>>> xpbd_settings("xpbd-jacobi", 1e-3).iteration, xpbd_settings("xpbd", 1e-3).substeps
('jacobi', 1)
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np

from springfem.errors import SolverError
from springfem.mechanics.limits import Deadline, SolveStopped, checkpoint
from springfem.scene import Scene

from .. import models
from ..scenes import case_scene

#: XPBD variants of the step search: the plug-in's own settings, and Jacobi iteration.
VARIANTS: dict[str, dict[str, Any]] = {"xpbd": {}, "xpbd-jacobi": {"iteration": "jacobi"}}
#: Energy growth over the initial energy that counts as a blow-up.
GROWTH = 100.0
#: Largest substep tried, over the bound ``2 / omega_max``; smallest: :data:`BOTTOM`.
TOP, BOTTOM = 1024.0, 1.0 / 64.0
#: Frames at most of the Jacobi variant's run to rest (the plug-in's 20,000 cost minutes when
#: rest never comes; docs/peers.rst's measured runs took at most 3,000).
LOAD_MAX_FRAMES = 3000


def xpbd_settings(method: str, h: float, damping: float | str = 0.0):
    """The :class:`~peers.xpbd.XPBDSettings` of a variant with frames of one substep ``h``."""
    from peers.xpbd import XPBDSettings

    own = XPBDSettings(**dict(models.get("xpbd").plugin.settings))
    return replace(own, dt=h, substeps=1, damping=damping, **VARIANTS[method])


def setting_substep(method: str) -> float:
    """The substep ``dt / substeps`` of the plug-in's own settings (s)."""
    s = models.get("xpbd").plugin.settings
    return float(s["dt"]) / int(s["substeps"])


def survives(scene: Scene, method: str, h: float, steps: int, v0: np.ndarray) -> str | None:
    """``None`` when ``steps`` undamped substeps of ``h`` survive (the module docstring);
    else why not."""
    from peers.xpbd import XPBD, StableNeoHookean

    solver = XPBD(scene, xpbd_settings(method, h))
    energy = StableNeoHookean(scene)
    x, v = solver.start()
    v += v0
    a = np.zeros_like(x)
    m = solver.masses[:, None]

    def total() -> float:
        return 0.5 * float(np.sum(m * v * v)) + energy.strain_energy(x)

    e0 = total()
    for k in range(1, steps + 1):
        checkpoint()  # the case's time cap (xpbd_step_case watches it)
        solver.advance(x, v, a)
        if not (np.isfinite(x).all() and np.isfinite(v).all()):
            return f"positions not finite at substep {k}"
        inverted = int((scene.mesh.volumes(x) <= 0).sum())
        if inverted:
            return f"{inverted} inverted elements at substep {k}"
        if total() > GROWTH * e0:
            return f"energy grew by more than {GROWTH:g}x at substep {k}"
    return None


def measure_xpbd_step(scene: Scene, method: str, steps: int, bisections: int) -> dict[str, Any]:
    """The largest surviving substep of ``method`` on ``scene`` (loads off).

    Returns ``dt_pred`` (``2 / omega_max`` of the stable neo-Hookean energy), ``ratio``
    (largest surviving ``h`` over it; ``nan`` below :data:`BOTTOM`), ``dt_measured``,
    ``bounded`` (survived at :data:`TOP`), ``setting_h`` (the plug-in's own substep) and
    ``failure`` (why the first failing step failed).
    """
    from peers.xpbd import StableNeoHookean
    from springfem.mechanics import stable_time_step

    dt_pred, omega = stable_time_step(StableNeoHookean(scene))
    rng = np.random.default_rng(0)  # the explicit series' perturbation
    v0 = (1e-6 * rng.standard_normal(scene.mesh.points.shape)).reshape(-1)
    v0[np.asarray(scene.dirichlet()[0], dtype=int)] = 0.0
    v0 = v0.reshape(-1, 3)
    why: dict[float, str | None] = {}

    def ok(f: float) -> bool:
        why[f] = survives(scene, method, f * dt_pred, steps, v0)
        return why[f] is None

    out: dict[str, Any] = {"dt_pred": dt_pred, "omega_max": omega,
                           "setting_h": setting_substep(method)}  # fmt: skip
    lo = 0.5
    while not ok(lo):
        if lo <= BOTTOM:
            return {**out, "ratio": float("nan"), "dt_measured": float("nan"),
                    "failure": why[lo]}  # fmt: skip
        lo /= 2.0
    hi = 2.0 * lo
    while lo < TOP and ok(hi):
        lo, hi = hi, 2.0 * hi
    if lo >= TOP:
        return {**out, "ratio": lo, "dt_measured": lo * dt_pred, "bounded": True, "failure": ""}
    for _ in range(bisections):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return {**out, "ratio": lo, "dt_measured": lo * dt_pred, "failure": why[hi] or ""}


def xpbd_step_case(case: dict) -> dict[str, Any]:
    """A ``dt`` case of an XPBD variant (:func:`measure_xpbd_step`)."""
    scene = case_scene(case, 0.0)
    try:
        with Deadline().watch():
            return measure_xpbd_step(scene, case["method"], case["steps"], case["bisections"])
    except SolveStopped as exc:  # a missing value, not a lost study
        nan = float("nan")
        return {"dt_pred": nan, "dt_measured": nan, "ratio": nan, "failure": str(exc)[:200]}


def xpbd_load_case(case: dict) -> dict[str, Any]:
    """A ``load`` case of the Jacobi variant (the plug-in's own is ``xpbd``, through
    :func:`studies.models.run`): its run to rest at the plug-in's settings with Jacobi
    iteration and at most :data:`LOAD_MAX_FRAMES` frames, ``diverged`` when rest does not
    come or the positions stop being finite, ``inverted`` with elements of J <= 0 at rest."""
    from peers.xpbd import XPBD, XPBDSettings

    from ..analytic import extent

    scene = case_scene(case, case["factor"])
    own = dict(models.get("xpbd").plugin.settings)
    settings = XPBDSettings(**{**own, **VARIANTS[case["method"]], "max_frames": LOAD_MAX_FRAMES})
    try:
        with Deadline().watch():
            out = XPBD(scene, settings).solve()
    except SolverError as exc:
        return {"status": "diverged", "message": str(exc)[:160], "u/size": float("nan")}
    except SolveStopped as exc:
        return {"status": "stopped", "message": str(exc)[:160], "u/size": float("nan")}
    ratio = float(np.linalg.norm(out.u, axis=1).max() / max(extent(scene)))
    if not out.converged:
        msg = f"no rest after {out.frames} frames"
        return {"status": "diverged", "message": msg, "u/size": ratio}
    inv = int((scene.mesh.volumes(scene.mesh.points + out.u) <= 0).sum())
    if inv:
        return {"status": "inverted", "u/size": ratio, "message": f"{inv} inverted elements"}
    return {"status": "ok", "u/size": ratio, "message": ""}
