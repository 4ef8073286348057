"""The work of one case of the volume-drift study: drift measures, a static solve, an
explicit run."""

from __future__ import annotations

from typing import Any

import numpy as np

from springfem.errors import SolverError
from springfem.result import Result, volume_summary
from springfem.scene import Scene

from .. import models
from ..scenes import case_scene
from ..solve import Solution
from .cases import K_MAX, VOLUME_ON

#: Static Newton of the spring variants: tolerance and iterations, no load stepping.
NEWTON_TOL, NEWTON_ITER = 1e-9, 30
#: Element drift above which a run counts as diverged and is stopped.
DIVERGED = 1.0


def drift_measures(scene: Scene, x: np.ndarray) -> dict[str, float]:
    """Total and element volume drift and radial-sum change at positions ``x`` ``(n, 3)``.

    ``dV`` (total change over the rest volume), ``element_drift`` (``sum_k |V_k - V0_k| /
    V0``), ``dL`` (mean relative change of the radial sums ``sum_j |xi_j|``), ``inverted``
    (elements with ``V <= 0``).
    """
    V0 = scene.mesh.volumes()
    V = scene.mesh.volumes(x)
    X, X0 = x[scene.mesh.tets], scene.mesh.points[scene.mesh.tets]
    L = np.linalg.norm(X - X.mean(axis=1, keepdims=True), axis=-1).sum(axis=1)
    L0 = np.linalg.norm(X0 - X0.mean(axis=1, keepdims=True), axis=-1).sum(axis=1)
    return {
        "dV": float((V.sum() - V0.sum()) / V0.sum()),
        "element_drift": float(np.abs(V - V0).sum() / V0.sum()),
        "dL": float(np.mean(np.abs(L - L0) / L0)),
        "inverted": int((V <= 0).sum()),
    }


# ------------------------------------------------------------------------------ statics


def newton(model: models.Model, scene: Scene) -> Solution:
    """Static solve for :func:`studies.models.run`: the spring variants by Newton at full
    load (:data:`NEWTON_TOL`, :data:`NEWTON_ITER`, no load stepping), FEM as registered."""
    if model.kind != "spring":
        return model.solve(scene)
    from springfem.mechanics import static

    system = model.system(scene)
    info = static(system, tol=NEWTON_TOL, max_iter=NEWTON_ITER, fallback=False)
    u = info.x - system.x0
    mesh = scene.mesh
    counts = {"nodes": mesh.n_points, "tets": mesh.n_tets}
    result = Result(
        scene.name,
        "spring",
        "spring",
        model.name,
        counts,
        scene.probe_displacements(u),
        volume_summary(mesh, u),
        {},
        float("nan"),
        True,
        int(info.iterations),
        status="converged",
    )
    return Solution(result, u)


def static_case(case: dict[str, Any]) -> dict[str, Any]:
    """Static equilibrium of one model at load factor ``load``: drift measures, ``status``
    (``ok``, ``partial``, ``failed`` with ``message``), the FEM's law and, for a mixed
    formulation, its P2 volume change."""
    scene = case_scene(case, case["load"])
    got = models.run(scene, case["model"], solve=newton)
    if not got.ok:
        return {"status": got.status, "message": got.message[:200]}
    res = got.solution.result
    out = {**drift_measures(scene, scene.mesh.points + got.u), "status": "ok"}
    if got.model.kind == "fem":
        out["law"] = res.law
    if "volume_p2" in res.info:
        out["dV (P2 volume)"] = float(res.info["volume_p2"]) / float(scene.mesh.volumes().sum()) - 1
    return out


# ------------------------------------------------------------------------------ dynamics


def common_time_step(scene: Scene) -> float:
    """``0.5 dt_crit / sqrt(k_max)`` of the scene's ``spring-volume-on`` (every variant).

    LMS may stiffen a volume spring up to ``k_max`` times, raising ``omega_max`` by up to
    ``sqrt(k_max)``.
    """
    from springfem.mechanics import stable_time_step

    dt_crit, _ = stable_time_step(VOLUME_ON.system(scene))
    return 0.5 * dt_crit / np.sqrt(K_MAX)


def dynamic_case(case: dict[str, Any]) -> dict[str, Any]:
    """One damped explicit run of a spring variant, recording the drift over time.

    ``case``: ``model``, ``period`` (seconds), ``periods`` (run length), ``ramp`` (periods
    of a linear load ramp, 0: the load applied suddenly), ``damping`` (mass damping as a
    fraction of ``2 pi / period``), ``records`` (samples).

    Returns lists ``t``, ``load`` (load factor), ``dV``, ``element_drift``, ``dL``,
    ``k_median``, ``k_min``, ``k_max`` (LMS stiffness ratio ``k_s/k_s0``) and the ``final``
    values; ``status`` is ``ok``, ``inverted`` (ended with inverted elements), ``diverged``
    (element drift above :data:`DIVERGED`: the run is stopped there) or ``blew up`` (the
    integrator's blow-up test); ``message`` says where and when.
    """
    from springfem.mechanics import explicit

    scene = case_scene(case)
    spring = models.get(case["model"])
    model = spring.system(scene)
    period = float(case["period"])
    dt = common_time_step(scene)
    steps = int(np.ceil(case["periods"] * period / dt))
    every = max(1, steps // int(case["records"]))
    t_ramp = case["ramp"] * period

    def load(t: float) -> float:
        return 1.0 if t_ramp <= 0 else min(1.0, t / t_ramp)

    keys = ("t", "load", "dV", "element_drift", "dL", "k_median", "k_min", "k_max")
    rec: dict[str, list[float]] = {k: [] for k in keys}
    first_inverted: list[float] = []
    has_volume = bool(spring.spring_options(scene).volume)

    def sample(t: float, x: np.ndarray) -> bool:
        """Record one sample; ``True`` when the body has diverged (stop the run)."""
        m = drift_measures(scene, x)
        el = model.elements
        ratio = el.k_volume / np.where(el.k_volume0 > 0, el.k_volume0, 1.0)
        if not has_volume:
            ratio = np.zeros(1)
        k = {"k_median": np.median(ratio), "k_min": ratio.min(), "k_max": ratio.max()}
        row = {"t": t, "load": load(t), **m, **k}
        for key in keys:
            rec[key].append(float(row[key]))
        if m["inverted"] and not first_inverted:
            first_inverted.append(t)
        return not np.isfinite(m["element_drift"]) or m["element_drift"] > DIVERGED

    sample(0.0, model.x0)
    status, message, x_end = "ok", "", None
    try:
        traj = explicit(
            model,
            dt=dt,
            steps=steps,
            mass_damping=case["damping"] * 2.0 * np.pi / period,
            scale=load,
            record_every=steps,
            callback=lambda k, t, x, v: k % every == 0 and sample(t, x),
        )
        x_end = traj.x
        if traj.steps < steps:
            status = "diverged"
            message = (
                f"element drift above {DIVERGED:g} at t = {rec['t'][-1]:.4g} s (first inverted "
                f"element at t = {first_inverted[0]:.4g} s); run stopped"
            )
    except SolverError as exc:  # the integrator's blow-up test: an outcome of the run
        status, message = "blew up", str(exc)[:200]
    out: dict[str, Any] = {
        **rec,
        "status": status,
        "message": message,
        "dt": dt,
        "steps": steps,
        "first_inverted": first_inverted[0] if first_inverted else None,
    }
    if x_end is not None:
        final = drift_measures(scene, x_end)
        if status == "ok" and final["inverted"]:
            out["status"] = "inverted"
            out["message"] = f"{final['inverted']} inverted elements at the end"
        final.update({k: rec[k][-1] for k in ("k_median", "k_min", "k_max")})
        final["peak_dV"] = float(np.abs(rec["dV"]).max())
        final["peak_element_drift"] = float(np.max(rec["element_drift"]))
        out["final"] = final
    return out


#: Series -> (the work of one case, progress label).
WORK = {
    "static": (static_case, "statics"),
    "step": (dynamic_case, "sudden load"),
    "ramp": (dynamic_case, "slow ramps"),
}
