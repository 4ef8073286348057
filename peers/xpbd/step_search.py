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
survivor and the first failure. The plug-in offers it as
:meth:`peers.plugin.XPBDModel.largest_step` (the stability study's critical-step series).

Examples
--------
>>> from .solver import XPBDSettings
>>> one_substep(XPBDSettings(iteration="jacobi"), 1e-3).substeps
1
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np

from springfem.mechanics.limits import Deadline, SolveStopped, checkpoint
from springfem.scene import Scene

from .energy import StableNeoHookean
from .solver import XPBD, XPBDSettings

#: Energy growth over the initial energy that counts as a blow-up.
GROWTH = 100.0
#: Largest substep tried, over the bound ``2 / omega_max``; smallest: :data:`BOTTOM`.
TOP, BOTTOM = 1024.0, 1.0 / 64.0


def one_substep(settings: XPBDSettings, h: float, damping: float = 0.0) -> XPBDSettings:
    """``settings`` with frames of one substep ``h`` (undamped unless told)."""
    return replace(settings, dt=h, substeps=1, damping=damping)


def survives(
    scene: Scene, settings: XPBDSettings, h: float, steps: int, v0: np.ndarray
) -> str | None:
    """``None`` when ``steps`` undamped substeps of ``h`` survive (the module docstring);
    else why not."""
    solver = XPBD(scene, one_substep(settings, h))
    energy = StableNeoHookean(scene)
    x, v = solver.start()
    v += v0
    a = np.zeros_like(x)
    m = solver.masses[:, None]

    def total() -> float:
        return 0.5 * float(np.sum(m * v * v)) + energy.strain_energy(x)

    e0 = total()
    for k in range(1, steps + 1):
        checkpoint()  # the caller's time cap (largest_step watches it)
        solver.advance(x, v, a)
        if not (np.isfinite(x).all() and np.isfinite(v).all()):
            return f"positions not finite at substep {k}"
        inverted = int((scene.mesh.volumes(x) <= 0).sum())
        if inverted:
            return f"{inverted} inverted elements at substep {k}"
        if total() > GROWTH * e0:
            return f"energy grew by more than {GROWTH:g}x at substep {k}"
    return None


def measure_step(
    scene: Scene, settings: XPBDSettings, steps: int, bisections: int
) -> dict[str, Any]:
    """The largest surviving substep of ``settings`` on ``scene`` (loads off).

    Returns ``dt_pred`` (``2 / omega_max`` of the stable neo-Hookean energy), ``ratio``
    (largest surviving ``h`` over it; ``nan`` below :data:`BOTTOM`), ``dt_measured``,
    ``bounded`` (survived at :data:`TOP`), ``setting_h`` (the settings' own substep) and
    ``failure`` (why the first failing step failed).
    """
    from springfem.mechanics import stable_time_step

    dt_pred, omega = stable_time_step(StableNeoHookean(scene))
    rng = np.random.default_rng(0)  # the explicit series' perturbation
    v0 = 1e-6 * rng.standard_normal(scene.mesh.points.shape)
    v0.reshape(-1)[np.asarray(scene.dirichlet()[0], dtype=int)] = 0.0
    why: dict[float, str | None] = {}

    def ok(f: float) -> bool:
        why[f] = survives(scene, settings, f * dt_pred, steps, v0)
        return why[f] is None

    out: dict[str, Any] = {"dt_pred": dt_pred, "omega_max": omega,
                           "setting_h": settings.dt / settings.substeps}  # fmt: skip
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


def largest_step(
    scene: Scene, settings: XPBDSettings, steps: int, bisections: int
) -> dict[str, Any]:
    """:func:`measure_step` under the time cap of
    :func:`springfem.mechanics.limits.solve_limits`: a stop is a row with ``nan`` values
    and the reason as ``failure``, not an exception."""
    try:
        with Deadline().watch():
            return measure_step(scene, settings, steps, bisections)
    except SolveStopped as exc:
        nan = float("nan")
        return {"dt_pred": nan, "dt_measured": nan, "ratio": nan, "failure": str(exc)[:200]}


__all__ = ["BOTTOM", "GROWTH", "TOP", "largest_step", "measure_step", "one_substep", "survives"]
