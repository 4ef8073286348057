"""The cases' work of the volume-drift study: the spring variants, a static solve and an
explicit run with their drift measures."""

from __future__ import annotations

from typing import Any

import numpy as np

from springfem.errors import SolverError
from springfem.model_api import declared
from springfem.result import Result, volume_summary
from springfem.scene import Scene
from springmodel.options import LMSOptions

from .. import models
from ..scenes import case_scene
from ..solve import Solution

STUDY, VERSION = "volume_drift", 2
VOLUME_OFF = models.spring_variant("spring-volume-off", "volume springs off", volume=False)
VOLUME_ON = models.spring_variant("spring-volume-on", "barycentric volume springs", volume=True)
LMS_SPEC = models.spring_variant(
    "spring-lms-spec", "volume springs + LMS as written (eq. 2.81)", volume=True, lms="spec"
)
LMS_ABS = models.spring_variant(
    "spring-lms-abs", "volume springs + LMS driven by |dV|", volume=True, lms="abs"
)
VOLUME_NNLS = models.spring_variant(
    "spring-volume-nnls", "volume springs, nnls calibration", volume=True, calibration="nnls"
)
#: The explicit series' variants; all but the exact element are the specification's.
DYNAMIC = (*(m.name for m in (VOLUME_OFF, VOLUME_ON, LMS_SPEC, LMS_ABS, VOLUME_NNLS)),
           "spring-exact")  # fmt: skip
SPEC_VARIANTS = DYNAMIC[:-1]
#: The static spring variants (no LMS: it acts per time step).
STATIC_SPRINGS = ("spring-volume-off", "spring-volume-on", "spring-volume-nnls", "spring-exact")
K_MIN, K_MAX = LMSOptions().k_min, LMSOptions().k_max  # the LMS clamp the variants use
NEWTON_TOL, NEWTON_ITER = 1e-9, 30  # static Newton of the spring variants, no load stepping
DIVERGED = 1.0  # element drift above which a run counts as diverged and is stopped


# -- the work of one case -----------------------------------------------------------------


def drift_measures(scene: Scene, x: np.ndarray) -> dict[str, float]:
    """``dV`` (total change over the rest volume), ``element_drift``, ``dL`` (mean relative
    change of the radial sums) and ``inverted`` (elements with ``V <= 0``) at ``x``."""
    V0, V = scene.mesh.volumes(), scene.mesh.volumes(x)
    X, X0 = x[scene.mesh.tets], scene.mesh.points[scene.mesh.tets]
    L = np.linalg.norm(X - X.mean(axis=1, keepdims=True), axis=-1).sum(axis=1)
    L0 = np.linalg.norm(X0 - X0.mean(axis=1, keepdims=True), axis=-1).sum(axis=1)
    return {"dV": float((V.sum() - V0.sum()) / V0.sum()),
            "element_drift": float(np.abs(V - V0).sum() / V0.sum()),
            "dL": float(np.mean(np.abs(L - L0) / L0)), "inverted": int((V <= 0).sum())}  # fmt: skip


def newton(model: models.Model, scene: Scene) -> Solution:
    """The spring variants by Newton at full load (no load stepping), FEM as registered."""
    if declared(model, "spring_options", scene) is None:
        return model.solve(scene)
    from springfem.mechanics import static

    system = model.system(scene)
    info = static(system, tol=NEWTON_TOL, max_iter=NEWTON_ITER, fallback=False)
    u, mesh = info.x - system.x0, scene.mesh
    result = Result(scene.name, "spring", "spring", model.name,
                    {"nodes": mesh.n_points, "tets": mesh.n_tets}, scene.probe_displacements(u),
                    volume_summary(mesh, u), {}, float("nan"), True, int(info.iterations),
                    status="converged")  # fmt: skip
    return Solution(result, u)


def static_case(case: dict[str, Any]) -> dict[str, Any]:
    """Static equilibrium of one model at load factor ``load``: drift measures, ``status``,
    the FEM's law and, for a mixed formulation, its P2 volume change."""
    scene = case_scene(case, case["load"])
    got = models.run(scene, case["model"], solve=newton)
    if not got.ok:
        return {"status": got.status, "message": got.message[:200]}
    res = got.solution.result
    out = {**drift_measures(scene, scene.mesh.points + got.u), "status": "ok"}
    if declared(got.model, "reference", default=False):
        out["law"] = res.law
    if "volume_p2" in res.info:
        out["dV (P2 volume)"] = float(res.info["volume_p2"]) / float(scene.mesh.volumes().sum()) - 1
    return out


def dynamic_case(case: dict[str, Any]) -> dict[str, Any]:
    """One damped explicit run of a spring variant (``period``, ``periods``, ``ramp`` in
    periods, 0: a sudden load, ``damping``, ``records``), recording ``t``, ``load``, the
    drifts and the LMS ratio ``k_s/k_s0`` (median, min, max). ``status``: ``ok``,
    ``inverted`` (at the end), ``diverged`` (element drift above :data:`DIVERGED`: stopped)
    or ``blew up`` (the integrator's blow-up test)."""
    from springfem.mechanics import explicit, stable_time_step

    scene = case_scene(case)
    spring = models.get(case["model"])
    model = spring.system(scene)
    period = float(case["period"])
    dt = 0.5 * stable_time_step(VOLUME_ON.system(scene))[0] / np.sqrt(K_MAX)
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
        row = {"t": t, "load": load(t), **m, "k_median": np.median(ratio),
               "k_min": ratio.min(), "k_max": ratio.max()}  # fmt: skip
        for key in keys:
            rec[key].append(float(row[key]))
        if m["inverted"] and not first_inverted:
            first_inverted.append(t)
        return not np.isfinite(m["element_drift"]) or m["element_drift"] > DIVERGED

    sample(0.0, model.x0)
    status, message, x_end = "ok", "", None
    try:
        traj = explicit(model, dt=dt, steps=steps, scale=load, record_every=steps,
                        mass_damping=case["damping"] * 2.0 * np.pi / period,
                        callback=lambda k, t, x, v: k % every == 0 and sample(t, x))  # fmt: skip
        x_end = traj.x
        if traj.steps < steps:
            status = "diverged"
            message = (
                f"element drift above {DIVERGED:g} at t = {rec['t'][-1]:.4g} s (first "
                f"inverted element at t = {first_inverted[0]:.4g} s); run stopped"
            )
    except SolverError as exc:  # the integrator's blow-up test: an outcome of the run
        status, message = "blew up", str(exc)[:200]
    first = first_inverted[0] if first_inverted else None
    out: dict[str, Any] = {**rec, "status": status, "message": message, "dt": dt,
                           "steps": steps, "first_inverted": first}  # fmt: skip
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
WORK = {"static": (static_case, "statics"), "step": (dynamic_case, "sudden load"),
        "ramp": (dynamic_case, "slow ramps")}  # fmt: skip
