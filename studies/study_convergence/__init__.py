"""Study ``convergence``: refinement of a scene for the spring model, P1 and P2.

Every scene is refined by the factors of the settings (:mod:`.levels`: a box grid's
divisions times the factor, any other mesh uniformly, each tet into 8 per doubling), so
every level contains the level-1 vertices. On each level the spring model
(``spring-energy``), the exact spring element (``spring-exact``) and P1 are solved, P2 on
its own levels (``P1-NH`` and ``P2-NH`` on a neo-Hookean scene: the FEM of the scene's law);
errors are measured against P2 on the reference level (the settings' ``ref``, or the finest
level the scene runs): the relative L2 error at the level-1 vertices and the relative
error of one displacement component ``w`` (the scene's closed-form quantity, e.g. the
cantilever's tip deflection, else a probe's, else a vertex's). Rates are slopes of
``log err`` over ``log h`` (:func:`studies.metrics.fitted_rate`) with ``h = h₁ / factor``,
``h₁`` the mean edge length of the scene's own mesh.

The spring model need not converge to the FEM limit: its calibration cannot match the
material on six-tet meshes. The study tracks ``spring / P1 − 1`` of ``w`` on the same meshes
(does the gap close under refinement?) and extrapolates each model's limit from its three
finest levels (P1's extrapolation, whose true limit is the reference, shows how far the
extrapolation itself can be trusted). A scene with a closed-form reference
(:mod:`studies.analytic`, the bar's Timoshenko deflection) compares the P2 reference with it.

The spring model runs with energy torsion (analytic Hessian) instead of the specification's
cosine torsion (finite-difference Jacobian, ~4× slower per Newton solve); one extra case
(``spring-cosine``) at ``Settings.cosine_check_level`` measures the difference.

The bundled report runs it on the cantilever bar (0.1 × 0.01 × 0.01 m) on ``[10, 1, 1]``
hexahedra refined by 1–8; ``springfem study convergence --scene FILE`` on the user's scene.
The study is split into :mod:`.levels` (refinement), :mod:`.cases` (settings, plan, one
solve), :mod:`.tables` (errors, rates, the gap), :mod:`.figures` and :mod:`.findings`.

Examples
--------
>>> [s.label for s in bundled_scenes(Settings.quick())]
['cantilever']
"""

from __future__ import annotations

from springfem.files import safe_filename

from ..registry import StudyContext, StudyOutput, study_run
from ..scenes import StudyScene, require
from .cases import Settings, bundled_scenes, plan, richardson_limit, work
from .figures import rate_figure, tip_figure
from .findings import headline, report_findings
from .tables import analyse, write_tables

__all__ = ["Settings", "bundled_scenes", "richardson_limit", "run", "work"]


@study_run(
    "convergence",
    Settings,
    bundled_scenes,
    scenes_doc=(
        "The scenes to refine (one table pair, two figures and the headline "
        "each; with several scenes, files and headline keys end in the scene's "
        "label)."
    ),
    settings_doc="Refinement levels.",
    returns="Findings, level and rate tables, two figures, headline rates and gaps.",
)
def run(ctx: StudyContext, scenes: list[StudyScene], settings: Settings) -> StudyOutput:
    require(scenes, "convergence")
    out = StudyOutput(ctx.name, "")
    for s in scenes:
        suffix = "" if len(scenes) == 1 else f"_{safe_filename(s.label)}"
        p = plan(s, settings)
        cases = p.cases()
        a = analyse(p, cases, ctx.cache.run(cases, work, ctx.progress, "convergence"))
        out.tables += write_tables(ctx, a, suffix)
        out.figures += [rate_figure(ctx, a, suffix), tip_figure(ctx, a, suffix)]
        out.findings += report_findings(a, ctx.quick)
        out.headline.update({f"{k}{suffix}": v for k, v in headline(a).items()})
    names = ", ".join(s.label for s in scenes)
    out.title = f"Convergence under refinement ({names}): spring models, P1, P2"
    return out
