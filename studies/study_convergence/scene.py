"""Convergence on a user scene (``springfem study convergence --scene FILE``).

Level 1 is the scene's own mesh. A generated box gets ``divisions * 2^(level-1)``; a mesh
file is refined uniformly (:func:`springfem.mesh.refine_uniform`, each tet into 8), so the
mesh size halves per level either way and every level contains the level-1 vertices.
The seed spring model (the scene's own ``[spring]``), the exact spring element, P1 and P2
are solved on every level; errors are relative L2 over the level-1 vertices against P2 on
the finest level, rates are slopes of ``log err`` over ``log h`` with ``h`` the mean edge
length of the level's mesh.

Examples
--------
>>> level_divisions([4, 2, 1], 3)
[16, 8, 4]
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from springfem.mesh import TetMesh, refine_uniform
from springfem.scene import Scene, scene_from_dict

from .. import metrics
from ..compare import solve_model
from ..registry import Figure, StudyContext, StudyOutput, Table, mesh_digest
from ..tables import save_figure, write_table

#: Models solved on every level ("spring-exact": the exact element of issue 10).
SCENE_MODELS = ("spring", "spring-exact", "P1", "P2")

VERSION = 1


def level_divisions(divisions: list[int], level: int) -> list[int]:
    """Box divisions of a refinement level (level 1: the scene's own)."""
    return [int(d) * 2 ** (level - 1) for d in divisions]


def level_scene(table: dict, path: str | None, level: int) -> Scene:
    """The scene at one refinement level.

    Parameters
    ----------
    table
        The scene table.
    path
        The scene file (anchors a relative mesh path).
    level
        1 = the scene's mesh; each level halves the mesh size.

    Returns
    -------
    Scene
    """
    data = dict(table)
    mesh = data.get("mesh", {})
    if isinstance(mesh, dict) and "divisions" in mesh:
        data["mesh"] = {**mesh, "divisions": level_divisions(mesh["divisions"], level)}
        return scene_from_dict(data, path=path)
    m: TetMesh = scene_from_dict(data, path=path).mesh
    for _ in range(level - 1):
        m = refine_uniform(m)
    data["mesh"] = m
    return scene_from_dict(data, path=path)


def mean_edge(mesh: TetMesh) -> float:
    """Mean edge length over the tets' six edges (the mesh size ``h``)."""
    p, t = mesh.points, mesh.tets
    pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    return float(np.mean([np.linalg.norm(p[t[:, a]] - p[t[:, b]], axis=1) for a, b in pairs]))


def scene_case(table: dict, path: str | None, model: str, level: int) -> dict[str, Any]:
    """The cache case of one model on one level (the table and mesh file decide it)."""
    return {
        "study": "convergence-scene",
        "version": VERSION,
        "model": model,
        "level": level,
        "table": table,
        "path": path,
        "mesh_digest": mesh_digest(table, path),
    }


def coarse_vertex_index(table: dict, path: str | None, level: int, mesh: TetMesh) -> np.ndarray:
    """Where each level-1 vertex sits in ``mesh``, the mesh of refinement ``level``.

    Uniform refinement keeps the vertices, so level-1 fields compare across levels.

    Parameters
    ----------
    table, path
        The scene table and its file.
    level
        The refinement level of ``mesh``.
    mesh
        That level's mesh.

    Returns
    -------
    numpy.ndarray
        ``(n_1,)`` indices into ``mesh.points``.

    Raises
    ------
    AssertionError
        If a level-1 vertex is not a vertex of ``mesh``.
    """
    if level == 1:
        return np.arange(mesh.n_points)
    from scipy.spatial import cKDTree

    coarse = level_scene(table, path, 1).mesh.points
    dist, idx = cKDTree(mesh.points).query(coarse)
    if dist.max() > 1e-9 * float(np.ptp(coarse, axis=0).max()):
        raise AssertionError("level-1 vertices are not vertices of the refined mesh")
    return idx


def scene_work(c: dict[str, Any]) -> dict[str, Any]:
    """Solve one level with one model: probes and the field at the level-1 vertices."""
    scene = level_scene(c["table"], c["path"], c["level"])
    if c["model"] == "spring-exact":
        from springmodel.model import solve_spring

        from ..study_accuracy.variants import exact_options

        sol = solve_spring(scene.with_options(spring=exact_options(scene)))
        u, r = sol.u, sol.result
    else:
        sol = solve_model(scene, c["model"])
        u, r = sol.u, sol.result
    idx = coarse_vertex_index(c["table"], c["path"], c["level"], scene.mesh)
    return {
        "h": mean_edge(scene.mesh),
        "tets": scene.mesh.n_tets,
        "u_coarse": np.asarray(u)[idx],
        "probes": r.probes,
        "wall": r.wall_time,
    }


def run_on_scene(ctx: StudyContext, cfg) -> StudyOutput:
    """The convergence study on ``cfg.scene`` (see the module docstring).

    Parameters
    ----------
    ctx
        Output folder, cache and preset.
    cfg
        Settings with ``scene``, ``scene_path`` and ``scene_levels``.

    Returns
    -------
    StudyOutput
        Findings, the level and rate tables, the error figure, headline rates.
    """
    levels = tuple(cfg.scene_levels)
    finest = levels[-1]
    cases = [scene_case(cfg.scene, cfg.scene_path, m, k) for m in SCENE_MODELS for k in levels]
    results = ctx.cache.run(cases, scene_work, progress=ctx.progress, desc="convergence")
    res = {(c["model"], c["level"]): r for c, r in zip(cases, results, strict=True)}
    u_ref = np.asarray(res[("P2", finest)]["u_coarse"], float)
    name = cfg.scene.get("name") or "scene"
    rows = []
    for (m, k), r in res.items():
        if m == "P2" and k == finest:
            continue  # the reference itself
        rows.append(
            {
                "model": m,
                "level": k,
                "tets": r["tets"],
                "h (m)": r["h"],
                "L2 err (level-1 vertices)": metrics.relative_l2_error(r["u_coarse"], u_ref),
                "wall time (s)": r["wall"],
            }
        )
    df = pd.DataFrame(rows)
    t_levels = Table(
        write_table(df, ctx.path("convergence_scene_levels")),
        f"{name}: relative L2 error at the level-1 vertices against P2 on level {finest} "
        f"({res[('P2', finest)]['tets']} tets); level 1 is the scene's mesh, each level "
        "halves the mesh size (uniform refinement of a mesh file, doubled divisions of a box).",
    )
    rates, rrows = {}, []
    for m in SCENE_MODELS:
        d = df[df["model"] == m].sort_values("h (m)", ascending=False)
        rates[m] = metrics.fitted_rate(d["h (m)"], d["L2 err (level-1 vertices)"])
        if len(d):
            rrows.append(
                {
                    "model": m,
                    "levels": len(d),
                    "rate (L2)": rates[m],
                    "L2 err at finest": float(d["L2 err (level-1 vertices)"].iloc[-1]),
                }
            )
    rdf = pd.DataFrame(rrows)
    t_rates = Table(
        write_table(rdf, ctx.path("convergence_scene_rates")),
        "Fitted rates (slope of log error over log h over the levels) per model.",
    )
    fig = _figure(ctx, df, name, finest)
    fin = rdf.set_index("model")
    findings = [
        f"{name} refined {len(levels)} levels (up to {max(r['tets'] for r in results)} tets): "
        + "; ".join(
            f"{m} L2 error {fin.at[m, 'L2 err at finest']:.2%} at the finest level, rate "
            f"{fin.at[m, 'rate (L2)']:.2f}"
            for m in fin.index
        )
        + f" (against P2 on level {finest}; P1 converges at rate 2 in L2 when the solution is "
        "smooth).",
    ]
    if {"spring", "spring-exact", "P1"} <= set(fin.index):
        findings.append(
            f"On the same meshes the seed spring model's error at the finest level is "
            f"{fin.at['spring', 'L2 err at finest']:.1%} (rate {fin.at['spring', 'rate (L2)']:.2f}"
            f"), the exact element's {fin.at['spring-exact', 'L2 err at finest']:.2%} and P1's "
            f"{fin.at['P1', 'L2 err at finest']:.2%}: the exact element's small-strain "
            "stiffness is the P1 element's (DESIGN §4b), so it converges like P1."
        )
    headline = {f"rate_l2_{m.replace('-', '_')}": rates[m] for m in SCENE_MODELS}
    return StudyOutput(
        name=ctx.name,
        title=f"Convergence under refinement ({name}): seed and exact spring models, P1, P2",
        findings=findings,
        tables=[t_levels, t_rates],
        figures=[fig],
        headline=headline,
    )


def _figure(ctx: StudyContext, df: pd.DataFrame, name: str, finest: int) -> Figure:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4.2))
    for m, mk in zip(SCENE_MODELS, "osD^", strict=True):
        d = df[df["model"] == m].sort_values("h (m)")
        if len(d):
            ax.loglog(d["h (m)"], d["L2 err (level-1 vertices)"], marker=mk, label=m)
    ax.set_xlabel("h (mean edge length, m)")
    ax.set_ylabel("relative L2 error at the level-1 vertices")
    ax.set_title(f"{name}: error against P2 on level {finest}", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return Figure(
        save_figure(fig, ctx.path("convergence_scene.png")),
        f"{name}: displacement error of each model under uniform refinement, against P2 on "
        f"the finest level ({finest}).",
    )
