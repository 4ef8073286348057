"""Speed against accuracy on a user scene (``springfem study speed-accuracy --scene FILE``).

The user's scene at the refinement levels of the convergence study
(:func:`studies.study_convergence.scene.level_scene`: level 1 is the scene's mesh; a box
generator doubles its divisions, a mesh file is refined uniformly, each tet into 8). Every
point is one timed solve from the scene to the answer; its error is the relative L2 error
at the level-1 vertices (which every level contains) against P2 with the scene's own law on
the finest level. The reference solve itself is a point too (error 0 by construction).

Methods: FEM P1 and P2 with the scene's small-strain law and, for isotropic materials,
coupled neo-Hookean (for a tissue law: the law itself); the spring model (energy torsion,
as on the bundled cantilever) by static Newton, implicit pseudo-time stepping (level 1) and
explicit dynamic relaxation, the exact spring element by static Newton and explicit
relaxation, and the explicit P1 FEM (isotropic materials). The costly points (explicit
methods, neo-Hookean FEM) run on the levels in ``Settings.scene_costly_levels``. Timings
are one run each on a shared machine.

Examples
--------
>>> sorted(fem_methods("transverse-linear"))
['fem-p1-transverse-linear', 'fem-p2-transverse-linear']
"""

from __future__ import annotations

import time

import numpy as np
import pandas as pd

from springfem.errors import SolverError

from .. import metrics
from ..registry import Figure, StudyContext, StudyOutput, Table
from ..tables import save_figure, write_table
from ..user_scene import scene_case, scene_label
from .cases import IMPLICIT_TOL, STATIC_TOL, TORSION, _solve, _warm_up
from .tables import pareto_front

VERSION = 1

#: Setting of the explicit relaxation runs and the implicit run (on level 1).
EXPLICIT = {"tol": 1e-6, "dt_safety": 0.5}
IMPLICIT = {"dt_factor": 100.0, "tol": IMPLICIT_TOL}

ISOTROPIC = ("linear", "neo-hookean")


def fem_methods(law: str) -> dict[str, tuple[int, str | None]]:
    """Static FEM methods for a material law: name -> (order, law).

    Parameters
    ----------
    law
        The scene's material law.

    Returns
    -------
    dict
    """
    if law in ISOTROPIC:
        laws = ("linear", "neo-hookean/coupled")
    elif law == "transverse-linear":
        laws = ("transverse-linear",)
    else:
        laws = (law,)
    return {f"fem-p{o}-{x.split('/')[0]}": (o, x) for o in (1, 2) for x in laws}


def _scene(table: dict, path: str | None, level: int):
    from dataclasses import replace

    from springmodel.options import SpringOptions

    from ..study_convergence.scene import level_scene

    scene = level_scene(table, path, level)
    return scene.with_options(spring=replace(SpringOptions.of(scene), torsion=TORSION))


def point_work(case: dict) -> dict:
    """One timed solve of one method on one level: seconds and the level-1 field."""
    from ..study_convergence.scene import coarse_vertex_index

    scene = _scene(case["table"], case["path"], case["level"])
    method, setting = case["method"], case["setting"]
    fem = fem_methods(scene.material.law)
    if method not in fem:
        _warm_up(method, setting)
    t0 = time.perf_counter()
    try:
        if method in fem:
            import reference_fem

            order, law = fem[method]
            from ..compare_models import model_scene  # a tissue P1: displacement formulation

            u = reference_fem.solve(
                model_scene(scene, f"P{order}"), order=order, law=law
            ).u_vertices
        else:
            u, _ = _solve(scene, method, setting)
    except SolverError as exc:
        return {"status": "failed", "seconds": time.perf_counter() - t0, "message": str(exc)[:200]}
    seconds = time.perf_counter() - t0
    idx = coarse_vertex_index(case["table"], case["path"], case["level"], scene.mesh)
    return {"status": "ok", "seconds": seconds, "tets": scene.mesh.n_tets, "u": np.asarray(u)[idx]}


def scene_points(cfg, law: str) -> list[dict]:
    """The point cases on ``cfg.scene`` (every method on its levels).

    Parameters
    ----------
    cfg
        Settings with ``scene``, ``scene_path``, ``scene_levels``, ``scene_costly_levels``.
    law
        The scene's material law.

    Returns
    -------
    list of dict
    """
    out = []
    for k in cfg.scene_levels:

        def add(method: str, setting: dict, level: int = k) -> None:
            out.append(
                scene_case(
                    "speed-accuracy-scene",
                    VERSION,
                    cfg.scene,
                    cfg.scene_path,
                    method=method,
                    level=level,
                    setting=setting,
                )
            )

        for m in fem_methods(law):
            if k in cfg.scene_costly_levels or not m.endswith("neo-hookean"):
                add(m, {})
        add("spring-static", {"tol": STATIC_TOL})
        add("spring-exact-static", {"tol": STATIC_TOL})
        if k == cfg.scene_levels[0]:
            add("spring-implicit", IMPLICIT)
        if k in cfg.scene_costly_levels:
            add("spring-explicit", EXPLICIT)
            add("spring-exact-explicit", EXPLICIT)
            if law in ISOTROPIC:
                add("fem-explicit-p1-neo-hookean", EXPLICIT)
    return out


def run_on_scene(ctx: StudyContext, cfg) -> StudyOutput:
    """The speed-accuracy study on ``cfg.scene`` (see the module docstring).

    Parameters
    ----------
    ctx
        Output folder, cache and preset.
    cfg
        Settings with ``scene``, ``scene_path``, ``scene_levels``, ``scene_costly_levels``.

    Returns
    -------
    StudyOutput
        Findings, the points table, the time-error figure, headline errors.
    """
    from .cases import scene_from_dict

    name = scene_label(cfg.scene, cfg.scene_path)
    law = scene_from_dict(cfg.scene, path=cfg.scene_path).material.law
    cases = scene_points(cfg, law)
    res = ctx.cache.run(cases, point_work, ctx.progress, "points")
    finest = cfg.scene_levels[-1]
    ref_name = f"fem-p2-{law}"  # P2 with the scene's own law (a key of fem_methods)
    ref = next(
        r
        for c, r in zip(cases, res, strict=True)
        if c["method"] == ref_name and c["level"] == finest
    )
    if ref["status"] != "ok":
        raise SolverError(f"the reference {ref_name} on level {finest} failed: {ref['message']}")
    u_ref = np.asarray(ref["u"], float)
    rows = []
    for c, r in zip(cases, res, strict=True):
        ok = r["status"] == "ok"
        rows.append(
            {
                "method": c["method"],
                "level": c["level"],
                "tets": r.get("tets"),
                "status": r["status"],
                "seconds": r["seconds"],
                "L2 err (level-1 vertices)": (
                    metrics.relative_l2_error(np.asarray(r["u"], float), u_ref) if ok else np.nan
                ),
                "message": r.get("message", ""),
            }
        )
    df = pd.DataFrame(rows)
    good = df["status"] == "ok"
    df["pareto"] = False
    df.loc[good, "pareto"] = pareto_front(
        df.loc[good, "seconds"].to_numpy(), df.loc[good, "L2 err (level-1 vertices)"].to_numpy()
    )
    table = Table(
        write_table(df, ctx.path("scene_points")),
        f"{name}: wall time of one solve against the relative L2 error at the level-1 vertices "
        f"(reference: {ref_name} on level {finest}, {ref['tets']} tets); level 1 is the "
        "scene's mesh, each level halves the mesh size; pareto = no other point is both "
        "faster and more accurate.",
    )
    fig = _figure(ctx, df, name, ref_name, finest)
    front = df[df["pareto"]].sort_values("seconds")
    findings = [
        f"{name}: non-dominated (time, error) points: "
        + "; ".join(
            f"{r['method']} level {r['level']} ({r['seconds']:.2g} s, "
            f"{r['L2 err (level-1 vertices)']:.2%})"
            for _, r in front.iterrows()
        )
        + f" (error against {ref_name} on level {finest}; one run each).",
    ]
    d = df[good].set_index(["method", "level"])["L2 err (level-1 vertices)"]
    for m in ("spring-static", "spring-exact-static"):
        if (m, finest) in d.index and (m, cfg.scene_levels[0]) in d.index:
            findings.append(
                f"{m}: error {d[(m, cfg.scene_levels[0])]:.2%} on level "
                f"{cfg.scene_levels[0]} and {d[(m, finest)]:.2%} on level {finest}."
            )
    headline = {
        f"err_{m.replace('-', '_')}_level{k}": float(v)
        for (m, k), v in d.items()
        if not m.startswith(("spring-explicit", "spring-exact-explicit", "fem-explicit"))
    }
    return StudyOutput(
        name=ctx.name,
        title=f"Speed against accuracy on {name}",
        findings=findings,
        tables=[table],
        figures=[fig],
        headline=headline,
    )


def _figure(ctx: StudyContext, df: pd.DataFrame, name: str, ref: str, finest: int) -> Figure:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    d = df[(df["status"] == "ok") & (df["L2 err (level-1 vertices)"] > 0)]
    for m, g in d.groupby("method", sort=False):
        ax.loglog(g["seconds"], g["L2 err (level-1 vertices)"], "o-", label=m, ms=5)
    ax.set_xlabel("wall time of one solve (s)")
    ax.set_ylabel("relative L2 error at the level-1 vertices")
    ax.set_title(f"{name}: against {ref} on level {finest}", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return Figure(
        save_figure(fig, ctx.path("scene_speed_accuracy.png")),
        f"{name}: time against error of each method over the refinement levels (lines join "
        "one method's levels).",
    )
