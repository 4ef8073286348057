"""Study ``tissue``: the spring model against the Guccione FEM at finite strain.

Each spring variant (:data:`VARIANTS`) against the FEM on the same mesh (the beam and the
ventricle: the P2 reference and the same-mesh P1):

- stress-stretch along and across the fibre: a unit cube of Land's problem-1 Guccione law
  (C = 2 kPa, b_f = 8, b_t = 2, b_fs = 4, penalty kappa = 100 kPa) and of Holzapfel &
  Ogden's 2009 myocardium fit (penalty 1000 kPa), pulled to 30 % with the lateral faces
  free; the nominal stress is the x reaction on the unit face;
- homogeneous deformations (stretch, simple shear in each frame plane, both) imposed on every
  node of a jittered cube: the nodal forces of the tissue and stiffened elements against
  their law's P1 (:mod:`.homogeneous`);
- the Land beam (problem 1): the deformed z of (10, 0.5, 1) mm (published 4.14-4.20 mm),
  and the P2/P1 FEM's on three meshes with a Richardson value (:mod:`.convergence`);
- the Land ventricle (problem 2; the quick preset: problem 3's passive inflation, which
  converges on a coarser mesh): the apex positions and the cavity's pressure-volume curve;
- the apex positions' mesh convergence (P2/P1 mixed FEM, problems 2 and 3 passive), with a
  Richardson extrapolation beside the published problem-2 values (:mod:`.convergence`).

Examples
--------
>>> Settings.quick().stretches
(1.1, 1.3)
>>> s = cube("across", 1.2, 1, "guccione").build()
>>> s.frames[0, 0].tolist(), s.boundaries[-1].value.tolist()
([0.0, 1.0, 0.0], [0.19999999999999996, 0.0, 0.0])
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from springfem.scene import Scene

from .. import models
from ..registry import StudyContext, StudyOutput, study
from ..scenes import StudyScene, case_scene
from ..tables import pyplot
from .convergence import (
    PUBLISHED_RANGE,
    beam_level_scenes,
    beam_levels_finding,
    beam_levels_frame,
    convergence_figure,
    convergence_findings,
    convergence_frame,
    richardson_frame,
)
from .homogeneous import (
    GUCCIONE,
    HOLZAPFEL_OGDEN,
    STRETCH_LAWS,
    homogeneous_case,
    homogeneous_cases,
    homogeneous_findings,
    homogeneous_frame,
    homogeneous_table,
)

__all__ = ["GUCCIONE", "HOLZAPFEL_OGDEN", "Settings", "run", "scenes"]

#: The spring variants compared: the tissue element (Green axial and torsion springs, each
#: group stiffened as the law's terms: the law itself under any homogeneous deformation),
#: the exact element with the tissue's stiffening (shear torsion, one exponential element
#: energy, the FEM's penalty U(J): what the bundled ventricle scenes use), the exact element
#: with the specification's quadratic springs, and the specification's element.
VARIANTS = ("spring-tissue", "spring-stiffened", "spring-exact", "spring-spec")
#: The FEM models: the scene's own (the P2 reference) and P1 on the spring's mesh and element
#: order (the displacement formulation with the spring's penalty, :mod:`studies.models`).
FEM_MODELS = ("fem", "P1")
#: The models of the stress-stretch cube (P1 is the cube's FEM already); the beam and the
#: ventricle also run the same-mesh P1.
MODELS = ("fem", *VARIANTS)
STRUCTURE_MODELS = (*MODELS, "P1")
VERSION = 3


@dataclass(frozen=True)
class Settings:
    """Sizes of the ``tissue`` study.

    Parameters
    ----------
    n
        Box divisions per side of the unit cube.
    stretches
        Stretches of the stress-stretch curves.
    beam_divisions
        Divisions of the Land beam.
    lv_scene, lv_size, lv_steps
        The bundled ventricle scene: ``land-ventricle`` (problem 2) or
        ``land-ventricle-fibres`` (problem 3's passive inflation; converges on coarser
        meshes than problem 2, whose mixed FEM fails at sizes 5 and 6 mm); its element size
        (mm) and FEM load steps (points of its pressure-volume curve).
    lv_variants
        The spring variants run on the ventricle (the specification's element fails slowly:
        the quick preset leaves it out).
    conv_scenes, conv_sizes, conv_steps
        The apex mesh-convergence study (P2/P1 mixed FEM): the ventricle scenes, their
        element sizes (mm, coarse to fine) and load steps. Measured here: 2 mm takes
        ~5-8 min per scene on a shared 2-core machine; at 1.75 mm problem 2's Newton fails
        (line search at load factor 0.48, after 28 min), so the full preset stops at 2 mm.
    """

    n: int = 3
    stretches: tuple[float, ...] = (1.05, 1.1, 1.15, 1.2, 1.25, 1.3)
    beam_divisions: tuple[int, int, int] = (30, 3, 3)
    lv_scene: str = "land-ventricle"
    lv_size: float = 4.0
    lv_steps: int = 10
    lv_variants: tuple[str, ...] = VARIANTS
    conv_scenes: tuple[str, ...] = ("land-ventricle", "land-ventricle-fibres")
    conv_sizes: tuple[float, ...] = (4.0, 3.0, 2.5, 2.0)
    conv_steps: int = 10

    @classmethod
    def full(cls) -> Settings:
        """The report's preset."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """A few seconds: a coarse cube, beam and ventricle."""
        return cls(n=1, stretches=(1.1, 1.3), beam_divisions=(10, 1, 1),
                   lv_scene="land-ventricle-fibres", lv_size=6.0, lv_steps=3,
                   lv_variants=VARIANTS[:2], conv_scenes=("land-ventricle-fibres",),
                   conv_sizes=(6.0, 5.0), conv_steps=3)  # fmt: skip


def stretch_data(direction: str, stretch: float, n: int, law: str = "guccione") -> dict:
    """The table of a unit cube (mm) of a :data:`STRETCH_LAWS` material pulled to
    ``stretch`` along x on ``n³`` boxes, the fibre along x (``along``) or y (``across``),
    the lateral faces free (rigid motions removed only)."""
    fiber = [1.0, 0.0, 0.0] if direction == "along" else [0.0, 1.0, 0.0]
    sheet = [0.0, 1.0, 0.0] if direction == "along" else [1.0, 0.0, 0.0]
    return {
        "name": f"tissue-{direction}",
        "units": "mm-kPa",
        "mesh": {"generator": "box", "size": [1.0, 1.0, 1.0], "divisions": [n, n, n]},
        "material": dict(STRETCH_LAWS[law]),
        "axes": {"fiber": fiber, "sheet": sheet},
        "boundary": [
            {"region": "x_min", "fix": ["x"]},
            {"region": {"point": [0.0, 0.0, 0.0]}, "fix": ["y", "z"]},
            {"region": {"point": [0.0, 1.0, 0.0]}, "fix": ["z"]},
            {"region": "x_max", "fix": ["x"], "displacement": [stretch - 1.0, 0.0, 0.0]},
        ],
        "fem": {"order": 1, "load_steps": 3},
    }


def cube(direction: str, stretch: float, n: int, law: str) -> StudyScene:
    """The stress-stretch cube of :func:`stretch_data` as a study scene (role ``stretch``)."""
    params = {"law": law, "direction": direction, "stretch": stretch}
    table = stretch_data(direction, stretch, n, law)
    return StudyScene(f"{law} cube {direction} {stretch:g}", table, None, ("stretch",),
                      params=params)  # fmt: skip


def ventricle(name: str, size: float, steps: int, role: str) -> StudyScene:
    """A bundled Land ventricle at element ``size`` (mm) with ``steps`` FEM load steps."""
    sets = {"mesh.size": size, "fem.load_steps": steps}
    s = StudyScene.bundled(name, sets, label=f"{name} {size:g} mm", roles=(role,))
    return replace(s, params={"scene": name, "size": size, "steps": steps})


def scenes(settings: Settings) -> list[StudyScene]:
    """The stress-stretch cubes (``stretch``), the Land beam (``beam``), the ventricle
    (``ventricle``) and the apex mesh-convergence ventricles (``apex``)."""
    cubes = [cube(d, s, settings.n, law) for law in STRETCH_LAWS for d in ("along", "across")
             for s in settings.stretches]  # fmt: skip
    beam = StudyScene.bundled("land-beam", {"mesh.divisions": list(settings.beam_divisions)},
                              roles=("beam",))  # fmt: skip
    lv = ventricle(settings.lv_scene, settings.lv_size, settings.lv_steps, "ventricle")
    apex = [ventricle(s, h, settings.conv_steps, "apex") for s in settings.conv_scenes
            for h in settings.conv_sizes]  # fmt: skip
    return [*cubes, beam, lv, *apex]


def _solve(scene: Scene, model: str, partial: bool = False):
    """``(Solution, "")``, or ``(None, message)`` for a solver failure; with ``partial``, a
    solve that stopped part way along its load gives ``(its partial Solution, message)``."""
    got = models.run(scene, model)
    if got.ok:
        return got.solution, ""
    message = got.message.splitlines()[0][:200]
    return (got.solution if partial and got.status == "partial" else None), message


def stretch_case(case: dict) -> dict:
    """Nominal stress ``P_xx`` (kPa: the x reaction on the unit ``x_max`` face) of a cube:
    ``stress`` (NaN on failure), ``wall_time`` and ``error`` (message or "")."""
    sol, err = _solve(case_scene(case), case["model"])
    if sol is None:
        return {"stress": math.nan, "wall_time": math.nan, "error": err}
    return {"stress": float(sol.result.reactions["x_max"][0]), "wall_time": sol.result.wall_time,
            "error": ""}  # fmt: skip


def beam_case(case: dict) -> dict:
    """The Land beam's deformed tip z (mm): ``tip_z``, ``wall_time`` and ``error``."""
    sol, err = _solve(case_scene(case), case["model"])
    if sol is None:
        return {"tip_z": math.nan, "wall_time": math.nan, "error": err}
    return {"tip_z": 1.0 + sol.result.probes["tip"][2], "wall_time": sol.result.wall_time,
            "error": ""}  # fmt: skip


def ventricle_case(case: dict) -> dict:
    """A Land ventricle's ``endo_apex_z``, ``epi_apex_z`` (the probes at the rest apexes
    (0, 0, -17) and (0, 0, -20), vertices of the gmsh ellipsoid), ``cavity`` (initial/final,
    FEM: the pressure-volume rows), ``wall_time``, ``dofs``, ``tets``, ``load_factor`` (below
    1: the values at the load a failed solve reached, with its ``error``) and ``error``."""
    sol, err = _solve(case_scene(case), case["model"], partial=True)
    if sol is None:
        nan = math.nan
        return {"endo_apex_z": nan, "epi_apex_z": nan, "cavity": {}, "wall_time": nan,
                "dofs": nan, "tets": nan, "load_factor": nan, "error": err}  # fmt: skip
    r = sol.result
    return {"endo_apex_z": -17.0 + r.probes["endo_apex"][2],
            "epi_apex_z": -20.0 + r.probes["epi_apex"][2],
            "cavity": r.info.get("cavity", {}), "wall_time": r.wall_time,
            "load_factor": float(r.info.get("load_factor", 1.0)),
            "dofs": r.counts.get("dofs", math.nan),  # a partial state carries no counts
            "tets": r.counts.get("tets", math.nan), "error": err}  # fmt: skip


def _rel(value: float, ref: float) -> float:
    return (value - ref) / abs(ref) if ref and math.isfinite(ref) else math.nan


def _p1(df: pd.DataFrame, column: str) -> float:
    """The same-mesh P1 FEM's ``column`` (NaN when the P1 row is missing or failed)."""
    rows = df.loc[(df.model == "P1") & (df.error.fillna("") == ""), column]
    return float(rows.iloc[0]) if len(rows) else math.nan


def _frame(cases: list[dict], results: list[dict], keys: tuple[str, ...]) -> pd.DataFrame:
    """One row per case: its ``model`` and the result's ``keys`` (numeric but ``error``;
    a failed case's NaN comes back from JSON as None)."""
    df = pd.DataFrame([{"model": c["model"], **{k: r.get(k) for k in keys}}
                       for c, r in zip(cases, results, strict=True)])  # fmt: skip
    for k in keys:
        if k != "error":
            df[k] = pd.to_numeric(df[k])
    return df


def stretch_frame(cases: list[dict], results: list[dict]) -> pd.DataFrame:
    """One row per (law, direction, stretch, model): stress and its error against the FEM."""
    df = _frame(cases, results, ("stress", "error"))
    df.insert(0, "stretch", [c["stretch"] for c in cases])
    df.insert(0, "direction", [c["direction"] for c in cases])
    df.insert(0, "law", [c.get("law", "guccione") for c in cases])
    df = df[["law", "direction", "stretch", "model", "stress", "error"]]
    ref = df[df.model == "fem"].set_index(["law", "direction", "stretch"])["stress"]
    df["rel_error"] = [_rel(s, ref[tuple(key)]) for *key, s in
                       zip(df.law, df.direction, df.stretch, df.stress, strict=True)]  # fmt: skip
    return df


def beam_frame(cases: list[dict], results: list[dict]) -> pd.DataFrame:
    """One row per model: the deformed tip z, the error of the deflection (``tip_z - 1``)
    against the FEM and the same-mesh P1, time."""
    df = _frame(cases, results, ("tip_z", "wall_time", "error"))
    fem, p1 = float(df.loc[df.model == "fem", "tip_z"].iloc[0]), _p1(df, "tip_z")
    df["rel_error"] = [_rel(z - 1.0, fem - 1.0) for z in df.tip_z]
    df["rel_error_p1"] = [_rel(z - 1.0, p1 - 1.0) for z in df.tip_z]
    return df


def ventricle_frame(cases: list[dict], results: list[dict]) -> pd.DataFrame:
    """One row per model: apex z, cavity volumes, errors of the apex motion ``-17 - z``
    (negative: it moves less) against the FEM and the same-mesh P1 (none for a partial row:
    its values are at another load)."""
    results = [{**r, "cavity_initial": (r.get("cavity") or {}).get("initial"),
                "cavity_final": (r.get("cavity") or {}).get("final"),
                "load_factor": r.get("load_factor", 1.0)} for r in results]  # fmt: skip
    df = _frame(cases, results, ("endo_apex_z", "epi_apex_z", "cavity_initial", "cavity_final",
                                 "wall_time", "load_factor", "error"))  # fmt: skip
    fem, p1 = float(df.loc[df.model == "fem", "endo_apex_z"].iloc[0]), _p1(df, "endo_apex_z")
    df["rel_error"] = [_rel(-17.0 - z, -17.0 - fem) for z in df.endo_apex_z]
    df["rel_error_p1"] = [_rel(-17.0 - z, -17.0 - p1) for z in df.endo_apex_z]
    cav = _p1(df, "cavity_final")
    df["cavity_rel_p1"] = [_rel(v, cav) for v in df.cavity_final]
    df.loc[~(df.load_factor >= 1.0), ["rel_error", "rel_error_p1", "cavity_rel_p1"]] = math.nan
    return df


def _findings(sdf, bdf, vdf) -> tuple[list[str], dict[str, float]]:
    """Findings of the cube, the beam and the ventricle (one line each), and the headline."""
    text, head = [], {}
    last = sdf[sdf.stretch == sdf.stretch.max()]
    for _, row in last[last.model != "fem"].iterrows():
        text.append(f"{row.law}, at stretch {row.stretch:g} {row.direction} the fibre, "
                    f"{row.model} is {100 * row.rel_error:+.1f}% off the FEM's nominal stress"
                    + (f" (failed: {row.error})" if row.error else "") + ".")  # fmt: skip
        law = "" if row.law == "guccione" else f"{row.law}_"  # the Guccione keys as before
        head[f"stress_error_{law}{row.direction}_{row.model}"] = float(row.rel_error)
    fem = bdf[bdf.model == "fem"].iloc[0]
    lo, hi = PUBLISHED_RANGE
    text.append(f"Land beam: FEM tip z = {fem.tip_z:.4g} mm "
                f"({'inside' if lo <= fem.tip_z <= hi else 'outside'} the published {lo}-{hi} "
                "mm on this mesh).")  # fmt: skip
    for _, row in bdf[bdf.model != "fem"].iterrows():
        what = f"failed: {row.error}" if row.error else f"{100 * row.rel_error:+.1f}% deflection"
        if not row.error and row.model != "P1" and math.isfinite(row.rel_error_p1):
            what += f", {100 * row.rel_error_p1:+.1f}% against the same-mesh P1 FEM"
        text.append(f"Land beam, {row.model}: tip z = {row.tip_z:.4g} mm ({what}).")
        head[f"beam_error_{row.model}"] = float(row.rel_error)
    for _, row in vdf.iterrows():
        what = (f"failed: {row.error}" if row.error else
                f"endo apex z = {row.endo_apex_z:.4g} mm, epi {row.epi_apex_z:.4g} mm")  # fmt: skip
        if row.error and row.load_factor == row.load_factor:  # partial (not NaN)
            what = (f"partial, stopped at load factor {row.load_factor:.3g}: endo apex z = "
                    f"{row.endo_apex_z:.4g} mm, epi {row.epi_apex_z:.4g} mm")  # fmt: skip
        if not row.error and row.model not in FEM_MODELS and math.isfinite(row.cavity_rel_p1):
            what += (f"; against the same-mesh P1 FEM: apex motion {100 * row.rel_error_p1:+.1f}%,"
                     f" final cavity {100 * row.cavity_rel_p1:+.1f}%")  # fmt: skip
        text.append(f"Land ventricle, {row.model}: {what}.")
        if row.model != "fem":
            head[f"ventricle_error_{row.model}"] = float(row.rel_error)
    return text, head


def _pv_figure(ctx: StudyContext, sdf, lv_cases, lv_results):
    """Stress-stretch curves of both laws and the ventricle's pressure-volume curve."""
    fig, axes = pyplot().subplots(1, 3, figsize=(13, 3.8))
    for ax, law in zip(axes[:2], ("guccione", "holzapfel-ogden"), strict=True):
        for (direction, model), g in sdf[sdf.law == law].groupby(["direction", "model"]):
            style = "-" if model == "fem" else "--"
            ax.plot(g.stretch, g.stress, style, marker="o", ms=3, label=f"{model}, {direction}")
        ax.set_yscale("log")  # Holzapfel-Ogden's fibre stress grows by e^7.6 to 30 %
        ax.set_title(law, fontsize=9)
        ax.set(xlabel="stretch", ylabel="nominal stress (kPa)")
        ax.legend(fontsize=6)
        ax.grid(True, alpha=0.3)
    b = axes[2]
    p_end = math.nan  # the FEM's full pressure: the spring model's one point is drawn there
    for c, r in zip(lv_cases, lv_results, strict=True):
        if rows := (r.get("cavity") or {}).get("pressure_volume"):
            pv = np.asarray(rows, dtype=float)
            p_end = pv[-1, 1]
            b.plot(pv[:, 2] / 1000.0, pv[:, 1], "o-", ms=3, label=c["model"])
    for c, r in zip(lv_cases, lv_results, strict=True):
        cav = r.get("cavity") or {}
        if c["model"].startswith("spring") and cav.get("final") and math.isfinite(p_end):
            lf = r.get("load_factor", 1.0)
            b.plot(cav["final"] / 1000.0, p_end * lf, "s", ms=6,
                   label=c["model"] + ("" if lf >= 1 else f" (stopped at {lf:.2f})"))  # fmt: skip
    b.set(xlabel="cavity volume (ml)", ylabel="endocardial pressure (kPa)")
    b.legend(fontsize=7)
    b.grid(True, alpha=0.3)
    return ctx.figure(fig, "tissue.png", "Left and middle: nominal stress against stretch "
                      "along and across the fibre (log scale), Guccione and Holzapfel-Ogden, "
                      "FEM solid, spring variants dashed. Right: the Land ventricle's "
                      "pressure-volume curve over the FEM's load steps (P2 reference and "
                      "same-mesh P1); squares: the spring variants' final cavity, at the load "
                      "factor each reached.")  # fmt: skip


NO_USER_SCENES = (
    "it measures its own bundled tissue scenes (a stress-stretch cube, Land's beam and "
    "ventricles) against published values; run accuracy, ablation or compare on your scene"
)


@study("tissue", Settings, scenes, user_scenes=NO_USER_SCENES)
def run(ctx: StudyContext, scenes: list[StudyScene], settings: Settings) -> StudyOutput:
    """Run the cubes, the homogeneous deformations, the beam and its levels, the ventricle
    and the apex convergence (scenes by role: ``stretch``, ``beam``, ``ventricle``,
    ``apex``)."""

    def cases(role: str, models: tuple[str, ...]) -> list[dict]:
        return [s.case("tissue", VERSION, model=m) for s in scenes if s.roles == (role,)
                for m in models]  # fmt: skip

    def solved(cases: list[dict], work, label: str) -> list[dict]:
        return ctx.cache.run(cases, work, ctx.progress, label)

    cube = cases("stretch", MODELS)
    sdf = stretch_frame(cube, solved(cube, stretch_case, "stretch"))
    beam = cases("beam", STRUCTURE_MODELS)
    bdf = beam_frame(beam, solved(beam, beam_case, "beam"))
    lv = cases("ventricle", tuple(m for m in STRUCTURE_MODELS
                                  if m in FEM_MODELS or m in settings.lv_variants))  # fmt: skip
    lv_res = solved(lv, ventricle_case, "ventricle")
    vdf = ventricle_frame(lv, lv_res)
    text, headline = _findings(sdf, bdf, vdf)
    hom = homogeneous_cases(VERSION)
    hdf = homogeneous_frame(hom, solved(hom, homogeneous_case, "homogeneous"))
    more, numbers = homogeneous_findings(hdf)
    text, headline = text + more, {**headline, **numbers}
    levels = [s.case("tissue", VERSION, model="fem")
              for s in beam_level_scenes(settings.beam_divisions)]  # fmt: skip
    ldf = beam_levels_frame(levels, solved(levels, beam_case, "beam levels"))
    text += beam_levels_finding(ldf)
    conv = cases("apex", ("fem",))
    cdf = convergence_frame(conv, solved(conv, ventricle_case, "apex"))
    rich = richardson_frame(cdf)
    text += convergence_findings(rich)
    for _, r in rich[np.isfinite(rich.extrapolated)].iterrows():
        headline[f"apex_{r.surface}_problem_{r.problem.split()[0]}_extrapolated"] = r.extrapolated
    s = settings
    tables = [
        ctx.table(sdf, "stress_stretch", f"Nominal stress (kPa) of the unit cube ({s.n}^3 "
                  "boxes of 6 tets), Guccione (Land's problem 1) and Holzapfel-Ogden (their "
                  "2009 fit), fibre along or across the pull; rel_error against the P1 FEM "
                  "(exact for this homogeneous stretch)."),
        ctx.table(bdf, "beam", f"Land beam {tuple(s.beam_divisions)}: deformed z of "
                  f"(10, 0.5, 1) mm (published {PUBLISHED_RANGE[0]}-{PUBLISHED_RANGE[1]}); "
                  "rel_error of the deflection against the FEM (P2 mixed), rel_error_p1 against "
                  "the same-mesh P1 FEM (displacement formulation, the spring's penalty)."),
        ctx.table(vdf, "ventricle", f"{s.lv_scene} (size {s.lv_size} mm): apex z (mm) and "
                  "cavity volume (mm^3, each model's own field: the P2 FEM's quadratic facets, "
                  "the P1 FEM's and the spring model's flat ones); rel_error of the endocardial "
                  "apex's downward motion vs the FEM (negative: it moves less), rel_error_p1 vs "
                  "the same-mesh P1 FEM, cavity_rel_p1 of the final cavity vs P1's (none for a "
                  "partial row: its values are at the load_factor it reached)."),
        ctx.table(ldf, "beam_levels", "Land's beam (problem 1), P2/P1 mixed FEM on three "
                  "meshes: tip z (mm) per mesh and the Richardson value from them, beside the "
                  "11 codes' published range."),
        ctx.table(cdf, "apex_convergence", "Apex z (mm) of the P2/P1 mixed FEM per mesh: "
                  "gmsh size, effective h (the regular-tet edge of the mean tet volume), DOFs, "
                  "wall time (s)."),
        ctx.table(rich, "apex_richardson", "Richardson extrapolation from the three finest "
                  "meshes (observed order; the coarser triple's order checks the asymptotic "
                  "range) beside the published problem-2 apex z (FEniCS-pulse, finsberg/pulse "
                  "PR 98: -26.53 / -28.18 mm)."),
        homogeneous_table(ctx, hdf),
    ]  # fmt: skip
    return StudyOutput(ctx.name, "Tissue: finite-strain anisotropy, spring model vs Guccione FEM",
                       text, tables, [_pv_figure(ctx, sdf, lv, lv_res),
                                      convergence_figure(ctx, cdf, rich)], headline)  # fmt: skip
