"""Study ``tissue``: the spring model against the Guccione FEM at finite strain.

Three measurements, each spring variant (:data:`~.cases.VARIANTS`: the exact element with
and without the tissue's stiffening, and the specification's element) against the FEM on the
same mesh (the beam and the ventricle: the P2 reference and the same-mesh P1):

- stress-stretch along and across the fibre: a unit cube of Land's problem-1 Guccione law
  (C = 2 kPa, b_f = 8, b_t = 2, b_fs = 4, penalty kappa = 100 kPa) and of Holzapfel &
  Ogden's 2009 myocardium fit (penalty 1000 kPa), pulled to 30 % with the lateral faces
  free; the nominal stress is the x reaction on the unit face;
- homogeneous deformations (stretch, simple shear in each frame plane, both) imposed on every
  node of a jittered cube: the nodal forces of the tissue and stiffened elements against
  their law's P1 (:mod:`.homogeneous`);
- the Land beam (problem 1): the deformed z of (10, 0.5, 1) mm (published 4.14-4.20 mm),
  and the P2/P1 FEM's on three meshes with a Richardson value (:mod:`.beam_levels`);
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

from ..registry import StudyContext, StudyOutput, study
from ..scenes import StudyScene
from .beam_levels import beam_level_scenes, beam_levels_finding, beam_levels_frame
from .cases import (
    FEM_MODELS,
    VARIANTS,
    VERSION,
    Settings,
    beam_case,
    scenes,
    stretch_case,
    ventricle_case,
)
from .convergence import (
    convergence_figure,
    convergence_findings,
    convergence_frame,
    richardson_frame,
)
from .homogeneous import (
    homogeneous_case,
    homogeneous_cases,
    homogeneous_findings,
    homogeneous_frame,
    homogeneous_table,
)
from .report import beam_frame, findings, pv_figure, stretch_frame, tables, ventricle_frame

__all__ = ["Settings", "run", "scenes"]

#: The models of the stress-stretch cube (P1 is the cube's FEM already).
MODELS = ("fem", *VARIANTS)
#: The beam and the ventricle also run the same-mesh P1 FEM.
STRUCTURE_MODELS = (*MODELS, "P1")
#: Why the study does not run on a user's scene.
NO_USER_SCENES = (
    "it measures its own bundled tissue scenes (a stress-stretch cube, Land's beam and "
    "ventricles) against published values; run accuracy, ablation or compare on your scene"
)


@study("tissue", Settings, scenes, user_scenes=NO_USER_SCENES)
def run(ctx: StudyContext, scenes: list[StudyScene], settings: Settings) -> StudyOutput:
    """Run the tissue study (see the module docstring).

    Parameters
    ----------
    ctx
        Output folder, cache and preset.
    scenes
        Its scenes by role: ``stretch`` (cubes), ``beam``, ``ventricle``, ``apex``.
    settings
        Meshes and stretches.

    Returns
    -------
    StudyOutput
        Findings, the three tables, the stress-stretch and pressure-volume figure, and the
        spring model's worst errors as headline numbers.
    """

    def cases(role: str, models: tuple[str, ...]) -> list[dict]:
        return [
            s.case("tissue", VERSION, model=m) for s in scenes if s.roles == (role,) for m in models
        ]

    cube = cases("stretch", MODELS)
    cube_res = ctx.cache.run(cube, stretch_case, ctx.progress, "stretch")
    beam = cases("beam", STRUCTURE_MODELS)
    beam_res = ctx.cache.run(beam, beam_case, ctx.progress, "beam")
    lv_models = tuple(m for m in STRUCTURE_MODELS if m in FEM_MODELS or m in settings.lv_variants)
    lv = cases("ventricle", lv_models)
    lv_res = ctx.cache.run(lv, ventricle_case, ctx.progress, "ventricle")
    sdf = stretch_frame(cube, cube_res)
    bdf = beam_frame(beam, beam_res)
    vdf = ventricle_frame(lv, lv_res)
    text, headline = findings(sdf, bdf, vdf)
    hom = homogeneous_cases(VERSION)
    hdf = homogeneous_frame(hom, ctx.cache.run(hom, homogeneous_case, ctx.progress, "homogeneous"))
    more, numbers = homogeneous_findings(hdf)
    text, headline = text + more, {**headline, **numbers}
    levels = [s.case("tissue", VERSION, model="fem")
              for s in beam_level_scenes(settings.beam_divisions)]  # fmt: skip
    ldf = beam_levels_frame(levels, ctx.cache.run(levels, beam_case, ctx.progress, "beam levels"))
    text += beam_levels_finding(ldf)
    conv = cases("apex", ("fem",))
    cdf = convergence_frame(conv, ctx.cache.run(conv, ventricle_case, ctx.progress, "apex"))
    rich = richardson_frame(cdf)
    text += convergence_findings(rich)
    for _, r in rich[np.isfinite(rich.extrapolated)].iterrows():
        headline[f"apex_{r.surface}_problem_{r.problem.split()[0]}_extrapolated"] = r.extrapolated
    apex = [
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
    ]  # fmt: skip
    return StudyOutput(
        name=ctx.name,
        title="Tissue: finite-strain anisotropy, spring model vs Guccione FEM",
        findings=text,
        tables=[*tables(ctx, sdf, bdf, vdf, settings), *apex, homogeneous_table(ctx, hdf)],
        figures=[pv_figure(ctx, sdf, lv, lv_res, settings), convergence_figure(ctx, cdf, rich)],
        headline=headline,
    )
