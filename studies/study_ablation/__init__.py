"""Study ``ablation``: "model no more than a scene needs".

For every scene (the bundled ones, coarse meshes in the quick settings, or the user's
``--scene``) the spring model is solved with its parts switched on one by one:

========================================  =================================================
``spring-axial``                          axial springs only (torsion off, volume off)
``spring-axial+volume``                   + barycentric volume springs, no torsion (enough
                                          for a stretch along the axes?)
``spring-axial+cosine``                   + torsion springs, the spec's cosine law
                                          (2.44–2.45)
``spring-axial+energy``                   + torsion springs, the energy-consistent law
``spring-axial+cosine+volume``            + barycentric volume springs
``spring-axial+energy+volume``            + barycentric volume springs
``spring-axial+energy+volume+lms-abs``    with sign-consistent LMS; LMS acts once per time
                                          step, so this variant needs a dynamic solver:
                                          dynamic relaxation (kinetic damping) from rest
``spring-axial+energy+volume+nnls``       with the per-element least-squares calibration
                                          instead of the analytic one
``spring-exact-no-coupling``              the exact element (axis-volume, energy torsion,
                                          exact calibration) without coupling springs
``spring-exact+coupling``                 the exact element with Poisson-coupling springs
========================================  =================================================

Model error is the relative L2 error of the vertex displacements against FEM P1 (the scene's
law) on the same mesh; total error (against a converged solution) is the convergence
study's business. Cost is the wall time of the static solve (Newton with the analytic
Hessian for the gradient variants, a coloured finite-difference Jacobian for cosine torsion;
median of 3 when a solve takes under half a second) and the throughput of the serial force
kernel (elements per second). A variant that the solver cannot bring to equilibrium (a
singular tangent: the axial-only network has zero-energy modes; or no convergence) is
recorded as ``fails`` with the solver's message.

The cheapest adequate model of a scene is the variant with the smallest static solve time
among those whose model error is within :data:`.cases.TOLERANCE` (relative) of the best spring
variant's error.

The study is split into :mod:`.cases` (variants, settings, one solve), :mod:`.tables`
(every variant, winners), :mod:`.figures` and :mod:`.findings`.

Examples
--------
>>> list(ALL_VARIANTS)[:2]
['spring-axial', 'spring-axial+volume']
"""

from __future__ import annotations

import pandas as pd

from ..registry import StudyContext, StudyOutput, study_run
from ..scenes import StudyScene
from .cases import (
    ALL_VARIANTS,
    VERSION,
    Settings,
    bundled_scenes,
    fem_case,
    reference_model,
    spring_case,
)
from .figures import error_cost_figure
from .findings import report_findings
from .tables import ablation_table, result_rows, winners_frame, winners_table

__all__ = ["Settings", "bundled_scenes", "run"]


@study_run(
    "ablation",
    Settings,
    bundled_scenes,
    settings_doc="Meshes and step budget.",
    returns="Findings, the ablation and winners tables, the error-vs-cost figure, headline.",
)
def run(ctx: StudyContext, scenes: list[StudyScene], settings: Settings) -> StudyOutput:
    rows, fem_times, notes = [], {}, []
    for s in scenes:
        name = s.label
        ref = reference_model(s.build()).name
        fem = ctx.cache.run([s.case("ablation", VERSION, model=ref)], fem_case, ctx.progress, name)[
            0
        ]
        if fem["status"] != "ok":
            notes.append(f"{name}: the FEM P1 reference fails ({fem['message']}).")
            continue
        fem_times[name] = fem["time"]
        cases = [
            s.case("ablation", VERSION, variant=v, dr_steps=settings.dr_steps) for v in ALL_VARIANTS
        ]
        res = ctx.cache.run(cases, spring_case, ctx.progress, name)
        rows += result_rows(name, cases, res, fem["u"])
    df = pd.DataFrame(rows)
    winners, headline = winners_frame(df, settings.max_error)
    findings, counts = report_findings(df, winners, fem_times, settings.dr_steps, notes)
    return StudyOutput(
        name=ctx.name,
        title="Ablation: model no more than a scene needs"
        + ("" if not scenes or not scenes[0].user else f" ({scenes[0].label})"),
        findings=findings,
        tables=[
            ablation_table(ctx, df, fem_times),
            winners_table(ctx, winners, settings.max_error),
        ],
        figures=[error_cost_figure(ctx, df, winners, fem_times)],
        headline={**headline, **counts},
    )
