"""Stability on a user scene (``springfem study stability --scene FILE``).

Three of the study's four series, on the user's mesh, material, boundary conditions and
loads (load factor = every load value and prescribed displacement of the scene times the
factor):

1. critical time step: the predicted ``2 / omega_max`` against the largest stable explicit
   step found by bisection (undamped runs from the rest state, loads off, perturbed);
2. largest load: static solves at growing load factors by the spring variants and FEM;
   a solve fails as ``diverged`` (solver), ``inverted`` (elements with J <= 0) or, for a
   small-strain law, ``unphysical`` (largest displacement beyond 10 % of the body's size);
3. failure map: damped explicit dynamics over load factor x time-step factor.

The locking series is left out: its reference is beam theory for the bundled bar.
The explicit FEM has isotropic laws only; on an anisotropic scene the explicit series
run the spring variants alone and the static series solve FEM with the scene's own law.

Examples
--------
>>> scene_methods("transverse-linear")["load"][-1]
'fem-transverse-linear'
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from springfem.errors import SolverError

from ..registry import StudyContext, StudyOutput, Table
from ..tables import write_table
from ..user_scene import body_size, case_scene, scene_case, scene_label
from .cases import _inverted, _system, spring_options
from .critical_step import measure_critical_step

VERSION = 1

#: Settings of ``for_scene``: load factors multiply the scene's own loads.
SCENE_QUICK = {"dt_steps": 400, "dt_bisections": 4, "load_factors": (1, 10, 1000),
               "map_loads": (1, 100), "map_dt_factors": (0.5, 1.1), "map_steps": 400}  # fmt: skip
SCENE_FULL = {"load_factors": (1, 3, 10, 30, 100, 300, 1000, 3000), "map_loads": (1, 10, 100, 1000)}

SPRINGS = ("spring-energy", "spring-cosine", "spring-exact")

#: Beyond this largest displacement over the body's size a small-strain solution is not one.
UNPHYSICAL = 0.1


def scene_methods(law: str) -> dict[str, tuple[str, ...]]:
    """The methods of each series for a material law.

    Parameters
    ----------
    law
        The scene's material law.

    Returns
    -------
    dict
        ``dt``, ``load`` and ``map`` -> method names.
    """
    if law in ("linear", "neo-hookean"):
        return {
            "dt": (*SPRINGS, "fem-neo-hookean", "fem-linear"),
            "load": (*SPRINGS, "fem-linear", "fem-neo-hookean"),
            "map": (*SPRINGS, "fem-neo-hookean"),
        }
    return {"dt": SPRINGS, "load": (*SPRINGS, f"fem-{law}"), "map": SPRINGS}


def dt_work(case: dict) -> dict:
    """Predicted and measured critical explicit step of one method (loads off)."""
    scene = case_scene(case, 0.0)
    system = _system(scene, case["method"])
    dt_pred, _, ratio = measure_critical_step(system, case["steps"], case["bisections"])
    return {"dt_pred": dt_pred, "dt_measured": ratio * dt_pred, "ratio": ratio}


def load_work(case: dict) -> dict:
    """Static solve at one load factor by one method: ``status``, largest ``|u|`` / size."""
    scene = case_scene(case, case["factor"])
    method = case["method"]
    try:
        if method.startswith("spring-"):
            from springmodel.model import solve_spring

            u = solve_spring(scene, spring_options(scene, method), parallel=False).u
        else:
            import reference_fem

            from ..compare_models import model_scene  # a tissue P1: displacement formulation

            law = method.split("-", 1)[1]
            u = reference_fem.solve(model_scene(scene, "P1"), order=1, law=law).u_vertices
    except SolverError as exc:
        return {"status": "diverged", "message": str(exc)[:160], "u/size": float("nan")}
    ratio = float(np.linalg.norm(u, axis=1).max() / body_size(scene))
    inv = _inverted(scene, u)
    if inv:
        return {"status": "inverted", "u/size": ratio, "message": f"{inv} inverted elements"}
    if method.endswith("linear") and ratio > UNPHYSICAL:
        msg = f"small-strain kinematics beyond |u|/size = {UNPHYSICAL:g}"
        return {"status": "unphysical", "u/size": ratio, "message": msg}
    return {"status": "ok", "u/size": ratio, "message": ""}


def map_work(case: dict) -> dict:
    """Damped explicit dynamics at (load factor, dt factor): ok, blew up or inverted."""
    from springfem.mechanics import explicit, stable_time_step

    scene = case_scene(case, case["factor"])
    system = _system(scene, case["method"])
    dt_crit, omega = stable_time_step(system)
    try:  # mass damping omega_max / 200, as on the bundled bar
        traj = explicit(
            system,
            dt=case["dt_factor"] * dt_crit,
            steps=case["steps"],
            mass_damping=omega / 200.0,
            record_every=case["steps"],
        )
    except SolverError as exc:
        return {"status": "inverted" if "inverted" in str(exc) else "blew up"}
    return {"status": "inverted" if _inverted(scene, traj.x - system.x0) else "ok"}


def scene_grids(cfg, law: str) -> dict[str, list[dict]]:
    """The cases of the three series on ``cfg.scene``.

    Parameters
    ----------
    cfg
        Settings with ``scene`` and ``scene_path``.
    law
        The scene's material law.

    Returns
    -------
    dict
        ``dt``, ``load``, ``map`` -> cases.
    """
    m = scene_methods(law)

    def case(kind: str, **kw) -> dict:
        return scene_case("stability-scene", VERSION, cfg.scene, cfg.scene_path, kind=kind, **kw)

    return {
        "dt": [
            case("dt", method=x, steps=cfg.dt_steps, bisections=cfg.dt_bisections) for x in m["dt"]
        ],
        "load": [case("load", method=x, factor=f) for x in m["load"] for f in cfg.load_factors],
        "map": [
            case("map", method=x, factor=f, dt_factor=d, steps=cfg.map_steps)
            for x in m["map"]
            for f in cfg.map_loads
            for d in cfg.map_dt_factors
        ],
    }


def run_on_scene(ctx: StudyContext, cfg) -> StudyOutput:
    """The stability study on ``cfg.scene`` (see the module docstring).

    Parameters
    ----------
    ctx
        Output folder, cache and preset.
    cfg
        Settings with ``scene`` and ``scene_path``.

    Returns
    -------
    StudyOutput
        Findings, three tables, the failure map, headline ratios and largest loads.
    """
    from .figures import failure_map_figure

    name = scene_label(cfg.scene, cfg.scene_path)
    law = case_scene({"table": cfg.scene, "path": cfg.scene_path}).material.law
    grids = scene_grids(cfg, law)
    work = {
        "dt": (dt_work, "critical dt"),
        "load": (load_work, "max load"),
        "map": (map_work, "failure map"),
    }
    res = {k: ctx.cache.run(grids[k], fn, ctx.progress, label) for k, (fn, label) in work.items()}
    f = {
        k: pd.DataFrame([{**_keys(c), **r} for c, r in zip(grids[k], res[k], strict=True)])
        for k in grids
    }
    f["dt"] = f["dt"][["method", "dt_pred", "dt_measured", "ratio"]]
    f["load"] = f["load"].rename(columns={"factor": "load_factor"})
    f["map"] = f["map"].rename(columns={"factor": "load_factor"})
    tables = [
        Table(
            write_table(f["dt"], ctx.path("critical_dt")),
            f"{name}: predicted critical step 2/ω_max against the measured largest stable "
            "step (bisection, undamped runs from the perturbed rest state, loads off); "
            "ratio = measured / predicted.",
        ),
        Table(
            write_table(
                f["load"][["method", "load_factor", "status", "u/size", "message"]],
                ctx.path("max_load"),
            ),
            f"{name}: static solves with the scene's loads times the load factor: status "
            "and the largest displacement over the body's size.",
        ),
        Table(
            write_table(
                f["map"][["method", "load_factor", "dt_factor", "status"]], ctx.path("failure_map")
            ),
            f"{name}: damped explicit dynamics on the load × time-step grid: ok, blew "
            "up, or ended with inverted elements.",
        ),
    ]
    fig = failure_map_figure(ctx, f["map"], cfg, methods=scene_methods(law)["map"])
    findings, headline = _findings(name, f)
    return StudyOutput(
        name=ctx.name,
        title=f"Stability on {name}: critical time step, largest load, failure map",
        findings=findings,
        tables=tables,
        figures=[fig],
        headline=headline,
    )


def _keys(case: dict) -> dict[str, Any]:
    return {k: case[k] for k in ("method", "factor", "dt_factor") if k in case}


def _findings(name: str, f: dict[str, pd.DataFrame]) -> tuple[list[str], dict[str, float]]:
    headline: dict[str, float] = {}
    dt = f["dt"].set_index("method")["ratio"]
    for m, r in dt.items():
        headline[f"dt_ratio_{m}"] = round(float(r), 2)
    dl = f["load"]
    survive = {}
    for m in dict.fromkeys(dl["method"]):
        ok = dl[(dl.method == m) & (dl.status == "ok")]["load_factor"]
        survive[m] = float(ok.max()) if len(ok) else 0.0
        headline[f"max_load_{m}"] = survive[m]
    share = f["map"].groupby("method", sort=False)["status"].apply(lambda s: (s == "ok").mean())
    return [
        f"{name}: measured/predicted critical explicit step "
        + ", ".join(f"{m} {r:.2f}" for m, r in dt.items())
        + " (near 1: the linearised bound 2/ω_max predicts the limit on this mesh).",
        f"{name}: largest load factor solved without failure "
        + ", ".join(f"{m} {v:g}" for m, v in survive.items())
        + f" (of {', '.join(f'{x:g}' for x in dict.fromkeys(dl['load_factor']))}); failures "
        "are 'diverged', 'inverted' or, for a small-strain law, 'unphysical' (|u| beyond "
        f"{UNPHYSICAL:.0%} of the body's size).",
        f"{name}: share of the load × time-step grid that runs ok in damped explicit dynamics: "
        + ", ".join(f"{m} {v:.0%}" for m, v in share.items())
        + ".",
    ], headline
