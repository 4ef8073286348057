"""Study ``tissue``: the spring model against the Guccione FEM at finite strain.

Three measurements, each spring variant (:data:`~.cases.VARIANTS`: the exact element with
and without the tissue's stiffening, and the seed's default) against the FEM on the same mesh
(the beam and the ventricle: the P2 reference and the same-mesh P1):

- stress-stretch along and across the fibre: a unit cube of Land's problem-1 Guccione law
  (C = 2 kPa, b_f = 8, b_t = 2, b_fs = 4, penalty kappa = 100 kPa) and of Holzapfel &
  Ogden's 2009 myocardium fit (penalty 1000 kPa), pulled to 30 % with the lateral faces
  free; the nominal stress is the x reaction on the unit face;
- the Land beam (problem 1): the deformed z of (10, 0.5, 1) mm (published 4.14-4.20 mm);
- the Land ventricle (problem 2; the quick preset: problem 3's passive inflation, which
  converges on a coarser mesh): the apex positions and the cavity's pressure-volume curve;
- the apex positions' mesh convergence (P2/P1 mixed FEM, problems 2 and 3 passive), with a
  Richardson extrapolation beside the published problem-2 values (:mod:`.convergence`).

The study is split into :mod:`.cases` (scenes, measurements, settings) and
:mod:`.report` (tables, figure, findings).

Examples
--------
>>> Settings.quick().stretches
(1.1, 1.3)
"""

from __future__ import annotations

import numpy as np

from ..registry import StudyContext, StudyOutput, Table, study
from ..tables import write_table
from .cases import (
    FEM_P1,
    STRETCH_LAWS,
    VARIANTS,
    Settings,
    beam_case,
    stretch_case,
    ventricle_case,
)
from .convergence import (
    convergence_cases,
    convergence_figure,
    convergence_findings,
    convergence_frame,
    richardson_frame,
)
from .report import beam_frame, findings, pv_figure, stretch_frame, tables, ventricle_frame

__all__ = ["Settings", "run"]

MODELS = [("fem", None)] + [("spring", v) for v in VARIANTS]
#: The beam and the ventricle also run the same-mesh P1 FEM (the cube's FEM is P1 already).
STRUCTURE_MODELS = [*MODELS, (FEM_P1, None)]


@study("tissue", Settings)
def run(ctx: StudyContext, settings: Settings) -> StudyOutput:
    """Run the tissue study (see the module docstring).

    Parameters
    ----------
    ctx
        Output folder, cache and preset.
    settings
        Meshes and stretches.

    Returns
    -------
    StudyOutput
        Findings, the three tables, the stress-stretch and pressure-volume figure, and the
        spring model's worst errors as headline numbers.
    """
    cube = [
        {"law": law, "direction": d, "stretch": s, "n": settings.n, "model": m, "variant": v}
        for law in STRETCH_LAWS
        for d in ("along", "across")
        for s in settings.stretches
        for m, v in MODELS
    ]
    cube_res = ctx.cache.run(cube, stretch_case, ctx.progress, "stretch")
    beam = [{"divisions": list(settings.beam_divisions), "model": m, "variant": v}
            for m, v in STRUCTURE_MODELS]  # fmt: skip
    beam_res = ctx.cache.run(beam, beam_case, ctx.progress, "beam")
    where = {"scene": settings.lv_scene, "size": settings.lv_size, "steps": settings.lv_steps}
    lv = [{**where, "model": m, "variant": v} for m, v in STRUCTURE_MODELS
          if v is None or v in settings.lv_variants]  # fmt: skip
    lv_res = ctx.cache.run(lv, ventricle_case, ctx.progress, "ventricle")
    sdf = stretch_frame(cube, cube_res)
    bdf = beam_frame(beam, beam_res)
    vdf = ventricle_frame(lv, lv_res)
    text, headline = findings(sdf, bdf, vdf)
    conv = convergence_cases(settings)
    cdf = convergence_frame(conv, ctx.cache.run(conv, ventricle_case, ctx.progress, "apex"))
    rich = richardson_frame(cdf)
    text += convergence_findings(rich)
    for _, r in rich[np.isfinite(rich.extrapolated)].iterrows():
        headline[f"apex_{r.surface}_problem_{r.problem.split()[0]}_extrapolated"] = r.extrapolated
    apex = [
        Table(write_table(cdf, ctx.path("apex_convergence")), "Apex z (mm) of the P2/P1 "
              "mixed FEM per mesh: gmsh size, effective h (the regular-tet edge of the mean "
              "tet volume), DOFs, wall time (s)."),
        Table(write_table(rich, ctx.path("apex_richardson")), "Richardson extrapolation "
              "from the three finest meshes (observed order; the coarser triple's order "
              "checks the asymptotic range) beside the published problem-2 apex z "
              "(FEniCS-pulse, finsberg/pulse PR 98: -26.53 / -28.18 mm)."),
    ]  # fmt: skip
    return StudyOutput(
        name=ctx.name,
        title="Tissue: finite-strain anisotropy, spring model vs Guccione FEM",
        findings=text,
        tables=tables(ctx, sdf, bdf, vdf, settings) + apex,
        figures=[pv_figure(ctx, sdf, lv, lv_res, settings), convergence_figure(ctx, cdf, rich)],
        headline=headline,
    )
