"""Volume drift on a user scene (``springfem study volume-drift --scene FILE``).

The user's scene under its own loads:

- statics: the spring model with volume springs off, on, on with the least-squares
  calibration, and the exact axis-volume element (static Newton, no LMS), against the FEM:
  P1 with the small-strain law, P1 neo-Hookean (isotropic materials) and the FEM the scene
  itself asks for (its ``[fem]`` order, law and formulation; a mixed u-p formulation also
  reports its P2 volume);
- dynamics: a suddenly applied load, damped explicit runs of volume off / on, both LMS
  rules and the exact element (all at ``0.5 dt_crit / sqrt(k_max)``, run length in
  quarter-wave periods of a rod as long as the body), recording the drift over time.

Drift: ``dV`` = total volume change over the rest volume (of the P1 mesh at the vertex
positions), element drift = ``sum_k |V_k - V0_k| / V0``.

Examples
--------
>>> static_methods("transverse-linear")
('volume off', 'volume on', 'volume on (nnls)', 'axis-volume (exact)', 'fem-p1', 'fem-scene')
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from springfem.errors import SolverError

from ..registry import StudyContext, StudyOutput, Table
from ..tables import write_table
from ..user_scene import case_scene, scene_case, scene_label
from .cases import drift_measures, dynamic_case, spring_options

VERSION = 1

SPRING_STATIC = ("volume off", "volume on", "volume on (nnls)", "axis-volume (exact)")
DYNAMIC = ("volume off", "volume on", "LMS spec", "LMS abs", "axis-volume (exact)")


def user_period(scene) -> float:
    """The run-length time scale on a user scene: the quarter-wave period ``4 l / c`` of a rod
    as long as the body's largest extent ``l``, ``c`` from the stiffest longitudinal modulus
    of the material's small-strain matrix and the density.

    Parameters
    ----------
    scene
        The scene.

    Returns
    -------
    float
        Seconds.
    """
    from springfem.materials import material_matrix

    from ..user_scene import body_size

    c_max = float(np.max(np.diag(material_matrix(scene.material))[:3]))
    return 4.0 * body_size(scene) / np.sqrt(c_max / scene.material.density)


def static_methods(law: str) -> tuple[str, ...]:
    """The static methods for a material law (P1 neo-Hookean for isotropic laws only).

    Parameters
    ----------
    law
        The scene's material law.

    Returns
    -------
    tuple of str
    """
    fem = ("fem-p1", "fem-p1-neo-hookean") if law in ("linear", "neo-hookean") else ("fem-p1",)
    return (*SPRING_STATIC, *fem, "fem-scene")


def static_work(case: dict) -> dict:
    """Static equilibrium of the user scene by one method: drift measures and ``status``."""
    from ..compare import linear_law

    scene = case_scene(case)
    method = case["method"]
    extra: dict[str, Any] = {}
    try:
        if method in SPRING_STATIC:
            from springfem.mechanics import static
            from springmodel.model import SpringModel

            model = SpringModel(scene, spring_options(scene, method), parallel=False)
            x = static(model, tol=1e-9, max_iter=30, fallback=False).x
        else:
            import reference_fem

            from ..compare_models import model_scene  # a tissue P1: displacement formulation

            if method == "fem-scene":
                sol = reference_fem.solve(scene)
            elif method == "fem-p1":
                small = scene.material.law in ("linear", "neo-hookean", "transverse-linear")
                law = linear_law(scene) if small else None  # a tissue law: its own, at P1
                sol = reference_fem.solve(model_scene(scene, "P1"), order=1, law=law)
            else:
                sol = reference_fem.solve(model_scene(scene, "P1"), order=1, law="neo-hookean")
            x = scene.mesh.points + sol.u_vertices
            extra["law"] = sol.result.law
            if "volume_p2" in sol.result.info:
                v0 = float(scene.mesh.volumes().sum())
                extra["dV (P2 volume)"] = float(sol.result.info["volume_p2"]) / v0 - 1.0
    except SolverError as exc:
        return {"status": "fails", "message": str(exc)[:200]}
    return {**drift_measures(scene, x), **extra, "status": "ok"}


def run_on_scene(ctx: StudyContext, cfg) -> StudyOutput:
    """The volume-drift study on ``cfg.scene`` (see the module docstring).

    Parameters
    ----------
    ctx
        Output folder, cache and preset.
    cfg
        Settings with ``scene``, ``scene_path``, ``periods`` and ``records``.

    Returns
    -------
    StudyOutput
        Findings, the static and dynamic drift tables, headline drifts.
    """
    name = scene_label(cfg.scene, cfg.scene_path)
    law = case_scene({"table": cfg.scene, "path": cfg.scene_path}).material.law

    def case(**kw) -> dict:
        return scene_case("volume-drift-scene", VERSION, cfg.scene, cfg.scene_path, **kw)

    stat = [case(method=m) for m in static_methods(law)]
    sres = ctx.cache.run(stat, static_work, ctx.progress, "statics")
    dyn = [
        case(
            scene="user", variant=v, ramp=0.0, periods=cfg.periods, damping=0.3, records=cfg.records
        )
        for v in DYNAMIC
    ]
    dres = ctx.cache.run(dyn, dynamic_case, ctx.progress, "dynamic runs")

    cols = ["dV", "element_drift", "dL", "inverted", "dV (P2 volume)", "law"]
    srows = [
        {
            "method": c["method"],
            "status": r["status"],
            **{k: r.get(k) for k in cols},
            "message": r.get("message", ""),
        }
        for c, r in zip(stat, sres, strict=True)
    ]
    sdf = pd.DataFrame(srows)
    drows = []
    for c, r in zip(dyn, dres, strict=True):
        fin = r.get("final", {})
        drows.append(
            {
                "variant": c["variant"],
                "status": r["status"],
                "final dV": fin.get("dV"),
                "peak |dV|": fin.get("peak_dV"),
                "final element drift": fin.get("element_drift"),
                "LMS k/k0 median": fin.get("k_median"),
                "steps": r.get("steps"),
                "message": r.get("message", ""),
            }
        )
    ddf = pd.DataFrame(drows)
    tables = [
        Table(
            write_table(sdf, ctx.path("scene_static_drift")),
            f"{name}: static equilibria under the scene's loads: relative volume change dV "
            "of the P1 mesh at the vertex positions, element drift Σ|V_k − V0_k|/V0, mean "
            "change of the radial sums dL; fem-scene is the FEM of the scene's [fem] "
            "options (its P2 volume where it has one).",
        ),
        Table(
            write_table(ddf, ctx.path("scene_dynamic_drift")),
            f"{name}: damped explicit runs after a suddenly applied load ({cfg.periods:g} "
            "quarter-wave periods): final and peak volume change, element drift, median "
            "LMS stiffness ratio.",
        ),
    ]
    findings, headline = _findings(name, sdf, ddf)
    return StudyOutput(
        name=ctx.name,
        title=f"Volume drift on {name}: volume springs, LMS rules and FEM",
        findings=findings,
        tables=tables,
        headline=headline,
    )


def _reference(ok: pd.DataFrame) -> str | None:
    """The FEM the spring model's drift is measured against: a finite-strain one if any."""
    small = ("linear", "transverse-linear")
    if "fem-scene" in ok.index and str(ok.at["fem-scene", "law"]).split("/")[0] not in small:
        return "fem-scene"
    for m in ("fem-p1-neo-hookean", "fem-scene"):
        if m in ok.index:
            return m
    return None


def _findings(name: str, sdf: pd.DataFrame, ddf: pd.DataFrame):
    from .cases import variant_key

    s = sdf.set_index("method")
    ok = s[s.status == "ok"]
    ref = _reference(ok)
    headline = {f"static_dV_{variant_key(m)}": float(v) for m, v in ok["dV"].items()}
    d = ddf.set_index("variant")
    for v, x in d["final dV"].items():
        if x is not None and pd.notna(x):
            headline[f"dynamic_dV_{variant_key(v)}"] = float(x)
    springs = [m for m in SPRING_STATIC if m in ok.index]
    findings = [
        f"{name}, static under its loads: volume change "
        + ", ".join(f"{m} {ok.at[m, 'dV']:+.3g}" for m in ok.index)
        + (
            f"; the finite-strain reference {ref} ({ok.at[ref, 'law']}) gives "
            f"{ok.at[ref, 'dV']:+.3g} — what the material itself does (a small-strain solution "
            "measured on the deformed mesh also counts the volume its linearised rotations "
            "add)."
            if ref
            else "."
        )
    ]
    if ref and springs:
        gap = {m: abs(ok.at[m, "dV"] - ok.at[ref, "dV"]) for m in springs}
        best = min(gap, key=gap.get)
        findings.append(
            f"Closest spring variant to the FEM's volume change: {best} (|ΔdV| {gap[best]:.2g}"
            "); " + ", ".join(f"{m} {g:.2g}" for m, g in gap.items() if m != best) + "."
        )
    findings.append(
        f"{name}, explicit after a sudden load: "
        + ", ".join(
            f"{v} {r['status']}"
            + (f" (final dV {r['final dV']:+.3g})" if r["status"] == "ok" else "")
            for v, r in d.iterrows()
        )
        + "."
    )
    return findings, headline
