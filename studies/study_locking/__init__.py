"""Study ``locking``: which method is cheapest within 5 % near incompressibility.

The probe deflection against the Poisson ratio ν = 0.3, 0.45, 0.49, 0.499, 0.4999 on three
mesh levels, for every method of :data:`~.cases.METHODS`:

- FEM on the scene's own law: P1 (displacement), P1 with nodal-averaged volume
  (``[fem] formulation = "nodal-volume"``, Bonet & Burton 1998, with its default
  stabilisation), P1 with nodal-averaged strain where the FEM offers it, MINI (P1-bubble /
  P1), P2 (displacement) and P2/P1 Taylor–Hood (``mixed``);
- the spring model: the specification's element (``spring-spec``), the exact element
  (``spring-exact``), the exact element on nodal volumes (``spring-nodal-volume``) and with
  nodal strain and nodal volume at their default stabilisations (``spring-stabilised``).

The shear modulus is held and ν sets the bulk modulus (:func:`~.cases.with_nu`; a tissue
law: its volumetric penalty). The reference at each ν is the P2/P1 Taylor–Hood deflection on
the finest level; a method's error is its relative difference from it and its cost the wall
time of its static solve. The answer per ν is the cheapest method and level within 5 % of
the reference (the reference itself excluded): "none" when none is. A solve is capped
(:attr:`~.cases.Settings.max_time`); one that needs longer is recorded as stopped.

The bundled run: Cook's membrane (neo-Hookean, shear load, Cook's μ = 80.19 kPa; deflection
``u_y`` of the corner) and Land's beam (Guccione, follower pressure; ``u_z`` of the tip).
``springfem study locking --scene FILE`` runs the same on a user's scene (an isotropic or
tissue law and a ``[[probe]]``; the deflection is its first probe's dominant component).

The study is split into :mod:`.cases` (methods, settings, ν, one timed solve), :mod:`.tables`
(rows, references, the cheapest method), :mod:`.figures` and :mod:`.findings`.

Examples
--------
>>> [s.label for s in bundled_scenes(Settings.quick())]
['cook-membrane', 'land-beam']
"""

from __future__ import annotations

from ..registry import StudyContext, StudyOutput, study_run
from ..scenes import StudyScene, require
from .cases import Settings, bundled_scenes, cases, locking_case
from .figures import deflection_figure, error_cost_figure
from .findings import report_findings
from .tables import (
    answer_frame,
    answer_table,
    cases_table,
    reference_table,
    result_frame,
    with_errors,
)

__all__ = ["Settings", "bundled_scenes", "run"]


@study_run(
    "locking",
    Settings,
    bundled_scenes,
    settings_doc="Poisson ratios, levels, methods, the solve cap.",
    returns=(
        "Findings, the table of every case, the references, the cheapest method "
        "per ν, the two figures, headline errors."
    ),
)
def run(ctx: StudyContext, scenes: list[StudyScene], settings: Settings) -> StudyOutput:
    require(scenes, ctx.name)
    all_cases, all_results, laws = [], [], {}
    for sc in scenes:
        laws[sc.label] = str(sc.table.get("material", {}).get("law", "linear"))
        cs = cases(sc, settings)
        all_cases += cs
        all_results += ctx.cache.run(cs, locking_case, ctx.progress, sc.label)
    df, refs = with_errors(result_frame(all_cases, all_results))
    answers = answer_frame(df)
    findings, headline = report_findings(df, refs, answers, laws, settings.max_time)
    names = ", ".join(sc.label for sc in scenes)
    return StudyOutput(
        name=ctx.name,
        title=f"Locking: the cheapest method within 5 % near incompressibility ({names})",
        findings=findings,
        tables=[answer_table(ctx, answers), cases_table(ctx, df), reference_table(ctx, refs)],
        figures=[deflection_figure(ctx, df), error_cost_figure(ctx, df)],
        headline=headline,
    )
