"""Study ``dynamics``: the spring elements and the fast peers against explicit P1 FEM of the
same law, in undamped dynamics of an anisotropic tissue scene and of its isotropic twin.

Every model starts from its own static equilibrium under the scene's loads and is released
(loads off): undamped symplectic Euler at half its own critical step
(:mod:`.work`). The models are the tissue spring element (``spring-tissue``: the law's own
energy per element), the stiffened exact element (``spring-stiffened``: one exponent per
element) and the exact small-strain element (``spring-exact``), against explicit P1 of the
scene's law on the same mesh (:class:`reference_fem.explicit.ExplicitFem`, the compiled
anisotropic kernels), and the plug-in models weighed by default where they apply: those
with an explicit form (co-rotational P1, the mass-spring network) the same way, those with
their own time integration (XPBD: its undamped substeps from its run to rest) by their
``release_run`` (:class:`springfem.model_api.ModelPlugin`); a plug-in that does not
apply has a row saying why. It reports the probe displacement error over time (relative L2
over the run and max), each model's energy balance (kinetic + strain − work, drift relative
to its initial energy), the stable step each model uses, and the median cost of one step of
every model, interleaved in one process after a warm-up.

The bundled run uses Land's beam (Land et al. 2015, problem 1: Guccione, fibres along the
beam) made compressible for explicit dynamics: ``kappa = 50 C`` (explicit P1 has no
pressure unknown), density 1000 kg/m³ in the scene's mm-kPa units, Land's 0.004 kPa as a
dead traction on the bottom face, and the same beam in compressible neo-Hookean
(``land-beam-nh``: ``E = C b_f``, ``nu = 0.45``), where the isotropic peers apply. The run
length is in Rayleigh periods of the reference's static deflection. The ventricle under a
pressure pulse is not part of it: see docs/studies.rst. ``springfem study dynamics --scene
FILE`` runs the same function on a user's compressible scene with a load (its first
``[[probe]]``, else the node farthest from the fixed nodes).

The study is split into :mod:`.cases` (settings, models, the beam, the cases), :mod:`.work`
(the period, one release run, the step cost), :mod:`.tables`,
:mod:`.figures` and :mod:`.findings`.

Examples
--------
>>> [s.label for s in bundled_scenes(Settings.quick())]
['land-beam', 'land-beam-nh']
"""

from __future__ import annotations

from ..registry import StudyContext, StudyOutput, study
from ..scenes import StudyScene, require
from .cases import Settings, bundled_scenes, cost_case, period_case, reference_model, release_cases
from .figures import energy_figure, probe_figure
from .findings import report_findings
from .tables import dynamics_table, result_frame
from .work import WORK

__all__ = ["Settings", "bundled_scenes", "run"]


@study("dynamics", Settings, bundled_scenes)
def run(ctx: StudyContext, scenes: list[StudyScene], s: Settings) -> StudyOutput:
    """Release runs of each model against explicit P1 of the same law."""
    require(scenes, ctx.name)
    periods = ctx.cache.run([period_case(sc) for sc in scenes], WORK["period"][0], ctx.progress,
                            WORK["period"][1])  # fmt: skip
    t_end = {sc.label: s.periods * p["period"] for sc, p in zip(scenes, periods, strict=True)}
    cases = [c for sc in scenes for c in release_cases(sc, s, t_end[sc.label])]
    results = ctx.cache.run(cases, WORK["release"][0], ctx.progress, WORK["release"][1])
    runs = list(zip(cases, results, strict=True))
    cost = ctx.cache.run([cost_case(sc, s) for sc in scenes], WORK["cost"][0], ctx.progress,
                         WORK["cost"][1])  # fmt: skip
    costs = {sc.label: c["step_seconds"] for sc, c in zip(scenes, cost, strict=True)}
    refs = {sc.label: reference_model(sc.build()) for sc in scenes}
    df = result_frame(runs, costs, refs)
    findings, headline = report_findings(df, refs, t_end, ctx.quick)
    names = ", ".join(sc.label for sc in scenes)
    return StudyOutput(
        name=ctx.name,
        title=f"Dynamics: spring elements against explicit P1 of the same law ({names})",
        findings=findings,
        tables=[dynamics_table(ctx, df, t_end)],
        figures=[probe_figure(ctx, runs, refs), energy_figure(ctx, runs, refs)],
        headline=headline,
    )
