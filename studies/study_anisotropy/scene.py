"""Anisotropy on a user scene (``springfem study anisotropy --scene FILE``).

The bundled study rotates the fibre of a cube in uniaxial stress and compares with the
off-axis modulus formula; an arbitrary body under its own loads has no such closed form.
What carries over is the split of the response and of each model's error into the fibre
direction and across it, on the user's mesh, axes, material and loads:

- displacement: at every vertex the fibre direction ``f`` (principal direction of the sum of
  ``f f^T`` over the tets around it, so the sign of a fibre does not matter); the error
  ``e = u - u_ref`` splits into ``e . f`` and ``e - (e . f) f``, each given relative to
  ``||u_ref||`` (the two add in quadrature to the total relative L2 error);
- strain: the fibre strain ``f . eps f`` and the mean cross-fibre normal strain
  ``(s . eps s + n . eps n) / 2`` per tet (``eps`` the small-strain tensor of the P1
  interpolation of the vertex displacements), relative L2 errors of each field.

Models: the spring model (analytic, nnls and exact + coupling calibrations, as in the
bundled study), FEM P1 and P2 with the scene's law. Errors against P2 (total) and against
P1 on the same mesh (model error). The study needs an anisotropic law; an isotropic scene is
refused with the reason, and so is one without an ``[axes]`` section.

Examples
--------
>>> refusal({"material": {"law": "linear"}}, "ball.toml").split(":")[0]
'scene ball has isotropic material (law linear)'
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from springfem.errors import SolverError
from springfem.mesh import displacement_gradients

from ..registry import StudyContext, StudyOutput, Table
from ..tables import write_table
from ..user_scene import case_scene, scene_case, scene_label
from .cases import EXACT, MODELS

VERSION = 1

ANISOTROPIC = ("transverse-linear", "guccione", "holzapfel-ogden")


def refusal(table: dict, path: str | None) -> str | None:
    """Why the scene cannot run the anisotropy study (``None``: it can).

    Parameters
    ----------
    table
        The scene table.
    path
        The scene file.

    Returns
    -------
    str or None
    """
    law = str(table.get("material", {}).get("law", "linear"))
    name = scene_label(table, path)
    if law not in ANISOTROPIC:
        return (
            f"scene {name} has isotropic material (law {law}): anisotropy needs a "
            f"fibre-reinforced law ({', '.join(ANISOTROPIC)}) with its fibre direction from "
            "[axes]"
        )
    if "axes" not in table:
        return (
            f"scene {name} has no [axes] section (its fibre would be the default x axis): "
            "anisotropy needs the fibre direction stated (uniform, helix, rule-based or cells)"
        )
    return None


def solve_work(case: dict) -> dict:
    """Vertex displacements of one model on the user scene (``status``, ``u``)."""
    from dataclasses import replace

    scene = case_scene(case)
    try:
        if case["model"] == "spring":
            from springmodel.model import solve_spring
            from springmodel.options import SpringOptions

            extra = EXACT if case["calibration"] == "exact" else {}
            opts = replace(SpringOptions.of(scene), calibration=case["calibration"], **extra)
            u = solve_spring(scene, opts, parallel=False).u
        else:
            import reference_fem

            from ..compare_models import model_scene  # a tissue P1: displacement formulation

            fem_scene = model_scene(scene, f"P{case['order']}")
            u = reference_fem.solve(fem_scene, order=case["order"]).u_vertices
    except SolverError as exc:
        return {"status": "fails", "message": str(exc)[:200]}
    return {"status": "ok", "u": np.asarray(u)}


def vertex_fibres(tets: np.ndarray, frames: np.ndarray, n_points: int) -> np.ndarray:
    """Fibre direction per vertex: principal eigenvector of ``sum f f^T`` over its tets.

    Parameters
    ----------
    tets
        ``(m, 4)`` vertex ids.
    frames
        ``(m, 3, 3)`` element frames (row 0: fibre).
    n_points
        Number of vertices.

    Returns
    -------
    numpy.ndarray
        ``(n, 3)`` unit vectors (sign arbitrary).

    Examples
    --------
    >>> fr = np.tile(np.eye(3), (2, 1, 1)); fr[1, 0] *= -1  # the same fibre, opposite signs
    >>> np.abs(vertex_fibres(np.array([[0, 1, 2, 3], [1, 2, 3, 4]]), fr, 5)).round(6)[1]
    array([1., 0., 0.])
    """
    f = frames[:, 0, :]
    T = np.zeros((n_points, 3, 3))
    for j in range(tets.shape[1]):
        np.add.at(T, tets[:, j], f[:, :, None] * f[:, None, :])
    return np.linalg.eigh(T)[1][:, :, -1]


def tet_strains(points: np.ndarray, tets: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Small-strain tensor per tet of the P1 interpolation of vertex displacements ``u``.

    Parameters
    ----------
    points, tets
        The mesh.
    u
        ``(n, 3)`` vertex displacements.

    Returns
    -------
    numpy.ndarray
        ``(m, 3, 3)``.
    """
    G = displacement_gradients(points, tets, u)
    return 0.5 * (G + np.transpose(G, (0, 2, 1)))


def split_errors(scene, u: np.ndarray, u_ref: np.ndarray) -> dict[str, float]:
    """Fibre / cross-fibre split of the displacement and strain error of ``u`` vs ``u_ref``.

    Parameters
    ----------
    scene
        The scene (mesh and element frames).
    u, u_ref
        ``(n, 3)`` vertex displacements.

    Returns
    -------
    dict
        ``fibre``, ``cross``, ``total`` (displacement, relative to ``||u_ref||``),
        ``strain_fibre``, ``strain_cross`` (relative L2 of the strain fields).
    """
    m = scene.mesh
    f = vertex_fibres(m.tets, scene.frames, m.n_points)
    e = u - u_ref
    ef = np.sum(e * f, axis=1)
    ec = e - ef[:, None] * f
    norm = np.linalg.norm(u_ref)
    fr = scene.frames
    strains = {}
    for key, eps in (("model", tet_strains(m.points, m.tets, u)),
                     ("ref", tet_strains(m.points, m.tets, u_ref))):  # fmt: skip
        proj = np.einsum("kli,kij,klj->kl", fr, eps, fr)  # normal strain along each axis
        strains[key] = (proj[:, 0], 0.5 * (proj[:, 1] + proj[:, 2]))
    (mf, mc), (rf, rc) = strains["model"], strains["ref"]
    return {
        "fibre": float(np.linalg.norm(ef) / norm),
        "cross": float(np.linalg.norm(ec) / norm),
        "total": float(np.linalg.norm(e) / norm),
        "strain_fibre": float(np.linalg.norm(mf - rf) / np.linalg.norm(rf)),
        "strain_cross": float(np.linalg.norm(mc - rc) / np.linalg.norm(rc)),
    }


def run_on_scene(ctx: StudyContext, cfg) -> StudyOutput:
    """The anisotropy study on ``cfg.scene`` (see the module docstring).

    Parameters
    ----------
    ctx
        Output folder, cache and preset.
    cfg
        Settings with ``scene`` and ``scene_path``.

    Returns
    -------
    StudyOutput
        Findings, the split-error table, headline errors.
    """
    name = scene_label(cfg.scene, cfg.scene_path)
    cases = []
    for label, (kind, setting) in MODELS.items():
        key = "calibration" if kind == "spring" else "order"
        c = scene_case("anisotropy-scene", VERSION, cfg.scene, cfg.scene_path, model=kind)
        cases.append((label, {**c, key: setting}))
    res = dict(
        zip(
            (lbl for lbl, _ in cases),
            ctx.cache.run([c for _, c in cases], solve_work, ctx.progress, "models"),
            strict=True,
        )
    )
    scene = case_scene(cases[0][1])
    for ref in ("FEM P2", "FEM P1"):
        if res[ref]["status"] != "ok":
            raise SolverError(f"{name}: the reference {ref} failed: {res[ref]['message']}")
    rows = []
    for label, r in res.items():
        for against in ("FEM P2", "FEM P1"):
            if label == against or r["status"] != "ok":
                continue
            if label == "FEM P2" and against == "FEM P1":
                continue
            u = np.asarray(r["u"], float)
            err = split_errors(scene, u, np.asarray(res[against]["u"], float))
            rows.append({"model": label, "against": against, **err})
    df = pd.DataFrame(rows)
    df = df.rename(columns={
        "fibre": "fibre err (displ.)", "cross": "cross err (displ.)", "total": "L2 err",
        "strain_fibre": "fibre strain err", "strain_cross": "cross strain err",
    })  # fmt: skip
    u_ref = np.asarray(res["FEM P2"]["u"], float)
    f = vertex_fibres(scene.mesh.tets, scene.frames, scene.mesh.n_points)
    along = float(np.linalg.norm(np.sum(u_ref * f, axis=1)) / np.linalg.norm(u_ref))
    table = Table(
        write_table(df, ctx.path("scene_fibre_split")),
        f"{name}: each model's displacement error split into the fibre direction and across "
        "it (relative to ‖u_ref‖; the two add in quadrature to the L2 error), and the relative "
        "L2 errors of the fibre strain f·εf and the mean cross-fibre normal strain per tet. "
        f"The reference's displacement is {along:.0%} along the fibre (L2 share).",
    )
    failed = [lbl for lbl, r in res.items() if r["status"] != "ok"]
    total = df[df["against"] == "FEM P2"].set_index("model")
    model = df[df["against"] == "FEM P1"].set_index("model")
    findings = [
        f"{name} ({scene.material.law}) under its loads, error against P2 split along / across "
        "the fibre: "
        + "; ".join(
            f"{m} {r['fibre err (displ.)']:.2%} / {r['cross err (displ.)']:.2%} (strain "
            f"{r['fibre strain err']:.1%} / {r['cross strain err']:.1%})"
            for m, r in total.iterrows()
        )
        + (f"; failed: {', '.join(failed)}" if failed else "")
        + ".",
        "Against P1 on the same mesh (model error), along / across: "
        + "; ".join(
            f"{m} {r['fibre err (displ.)']:.2%} / {r['cross err (displ.)']:.2%}"
            for m, r in model.iterrows()
        )
        + " — where the fibre part dominates, the model's fibre stiffness is what is off.",
    ]
    headline = {}
    for (m, a), r in df.set_index(["model", "against"]).iterrows():
        key = f"{m}_vs_{a}".lower().replace(" ", "_").replace("(", "").replace(")", "")
        key = key.replace(".", "").replace("+", "plus")
        headline[f"fibre_err_{key}"] = float(r["fibre err (displ.)"])
        headline[f"cross_err_{key}"] = float(r["cross err (displ.)"])
    return StudyOutput(
        name=ctx.name,
        title=f"Anisotropy on {name}: error along and across the fibre",
        findings=findings,
        tables=[table],
        headline=headline,
    )
