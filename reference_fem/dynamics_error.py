"""The dynamic reference's own error: two time steps (Richardson) and two meshes.

:func:`estimate_error` runs :func:`~reference_fem.dynamics_implicit.run` three times: the
scene at ``dt`` (the run whose error is estimated), at ``dt / 2``, and on the scene's mesh
refined once (each tet into 8, :func:`springfem.mesh.refine_uniform`) at ``dt``. For each
probe it takes the largest difference over the run:

- time: ``|q(dt) - q(dt/2)| * 2^p / (2^p - 1)`` with ``p = 2`` (both rules are second
  order), Richardson's estimate of the error of the ``dt`` run; a third run at ``dt / 4``
  (``observed_order=True``) measures the order instead of assuming it;
- mesh: ``|q(h) - q(h/2)| * 2^p / (2^p - 1)`` with ``p = 2`` (P2's energy-norm order, the
  cautious choice: its displacements converge at 3 on smooth problems).

Both are stated relative to the largest probe displacement of the run too. The estimate
holds when each run is in its asymptotic range: a load that jumps excites modes no step
resolves (docs/fem.rst#the-dynamic-reference), and the time estimate then bounds only the
resolved motion.

Examples
--------
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({
...     "mesh": {"generator": "box", "size": [0.1, 0.02, 0.01], "divisions": [4, 1, 1]},
...     "material": {"law": "linear", "E": 1.0e4, "nu": 0.3, "density": 1000.0},
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
...     "load": [{"type": "traction", "region": "x_max", "value": [0, 0, -0.01],
...               "time": {"ramp": [0.0, 0.2]}}],
...     "probe": [{"name": "tip", "point": [0.1, 0.01, 0.005]}]})
>>> e = estimate_error(scene, t_end=0.4, dt=0.02)
>>> bool(0 < e.time["tip"] < e.mesh["tip"]), e.runs["fine mesh"].info["tets"]
(True, 192)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from springfem.mesh import refine_uniform
from springfem.scene import Scene, scene_from_dict

from .dynamics_implicit import DynamicResult, run

#: The orders assumed for the Richardson factors (time: the rules; mesh: P2, cautiously).
TIME_ORDER, MESH_ORDER = 2, 2


@dataclass
class ErrorEstimate:
    """The estimated error of a dynamic reference run, per probe.

    Attributes
    ----------
    time, mesh
        Probe name -> estimated largest error over the run (the scene's length unit).
    relative
        ``time`` and ``mesh`` over the largest probe displacement of the run.
    order
        Probe name -> observed order in the time step (with ``observed_order``), else
        empty.
    runs
        ``base`` (the estimated run), ``half step``, ``fine mesh`` (and ``quarter step``).
    """

    time: dict[str, float]
    mesh: dict[str, float]
    relative: dict[str, dict[str, float]]
    order: dict[str, float] = field(default_factory=dict)
    runs: dict[str, DynamicResult] = field(default_factory=dict, repr=False)

    def to_dict(self) -> dict:
        """Plain numbers, for JSON."""
        return {"time": self.time, "mesh": self.mesh, "relative": self.relative,
                "order": self.order}  # fmt: skip


def refined(scene: Scene) -> Scene:
    """The scene on its mesh refined once (regions, probes and sections re-read).

    Parameters
    ----------
    scene
        A scene built from a table (``scene.raw``).

    Returns
    -------
    Scene
    """
    return scene_from_dict({**scene.raw, "mesh": refine_uniform(scene.mesh)}, path=scene.path)


def on_grid(coarse: DynamicResult, fine: DynamicResult, name: str) -> np.ndarray:
    """The fine run's trajectory of probe ``name`` at the coarse run's times."""
    idx = np.searchsorted(fine.times, coarse.times - 1e-12 * coarse.times[-1])
    idx = np.minimum(idx, len(fine.times) - 1)
    if not np.allclose(fine.times[idx], coarse.times, rtol=0, atol=1e-9 * coarse.times[-1]):
        raise ValueError("the finer run's grid does not contain the coarser run's times")
    return fine.probes[name][idx]


def _gap(a: DynamicResult, b: DynamicResult, name: str) -> float:
    return float(np.linalg.norm(a.probes[name] - on_grid(a, b, name), axis=1).max())


def estimate_error(
    scene: Scene,
    t_end: float | None = None,
    dt: float | None = None,
    observed_order: bool = False,
    **kwargs,
) -> ErrorEstimate:
    """Estimate the error of ``run(scene, t_end, dt, ...)`` from two time steps and two
    meshes (module docstring).

    Parameters
    ----------
    scene
        The scene (with probes, or ``probes=`` in ``kwargs``).
    t_end, dt
        As for :func:`~reference_fem.dynamics_implicit.run`; ``dt`` defaults to the
        scene's.
    observed_order
        Also run at ``dt / 4`` and report the observed order in time.
    **kwargs
        Passed to every :func:`~reference_fem.dynamics_implicit.run` (``order``,
        ``formulation``, ``integrator`` ...).

    Returns
    -------
    ErrorEstimate
    """
    base = run(scene, t_end, dt, **kwargs)
    dt = float(base.info["dt"])
    t_end = float(base.info["t_end"])
    runs = {"base": base, "half step": run(scene, t_end, dt / 2, **kwargs)}
    runs["fine mesh"] = run(refined(scene), t_end, dt, **kwargs)
    if observed_order:
        runs["quarter step"] = run(scene, t_end, dt / 4, **kwargs)
    ft, fm = 2**TIME_ORDER / (2**TIME_ORDER - 1), 2**MESH_ORDER / (2**MESH_ORDER - 1)
    time_err, mesh_err, rel, order = {}, {}, {}, {}
    for name in base.probes:
        peak = float(np.linalg.norm(base.probes[name], axis=1).max()) or 1.0
        time_err[name] = ft * _gap(base, runs["half step"], name)
        mesh_err[name] = fm * _gap(base, runs["fine mesh"], name)
        rel[name] = {"time": time_err[name] / peak, "mesh": mesh_err[name] / peak}
        if observed_order:
            d2 = _gap(runs["half step"], runs["quarter step"], name)
            order[name] = float(np.log2(time_err[name] / ft / d2)) if d2 > 0 else float("inf")
    return ErrorEstimate(time_err, mesh_err, rel, order, runs)
