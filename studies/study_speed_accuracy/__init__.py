"""Study ``speed_accuracy``: wall time against error, one point per method, level and setting.

Each scene is refined by the factors of the settings, as in the convergence study
(:mod:`studies.study_convergence.levels`). Every point is one timed solve from the scene to
the answer; its error is measured against P2 with the scene's law (``P2``, or ``P2-NH`` on a
neo-Hookean scene) on the reference level, the settings' ``reference`` or the finest level
the scene runs: the relative error of the scene's probe displacement (the cantilever's
tip; Timoshenko's value for context) or, without probes, the relative L2 error at the
level-1 vertices. A method is a model of :mod:`studies.models` and a solution method
(:mod:`.cases`), named ``"<model> <solution>"``:

- ``spring-energy`` (energy-consistent torsion): ``static`` Newton, ``implicit``
  backward-Euler pseudo-time stepping to rest (``dt`` a multiple of the critical step),
  ``explicit`` dynamic relaxation (:func:`springfem.mechanics.explicit_static`, kinetic
  damping) at the settings' tolerances and time-step safety factors;
- ``spring-exact``: static Newton and explicit relaxation (the last explicit setting);
- ``P1``, ``P2``, ``P1-NH``, ``P2-NH`` static, those that apply to the scene's law;
- ``P1-NH explicit``: the explicit P1 FEM (isotropic laws), to rest with the same solver
  and settings as the spring model;
- the plug-in models weighed by default (``corotational``, ``xpbd``, ``mass-spring``):
  ``static`` (and ``explicit`` with an explicit form); a plug-in with a sweep of its own
  settings a static point per setting, ``xpbd 20x2 static`` (substeps x iterations).

The non-dominated (Pareto) points are those no other point beats in both time and error,
among all points and per model (the figure). The table also has each point's error against
the P1-NH answer on its own level (:data:`.tables.SAME`): for XPBD the substep error, whose
observed rate the findings give (:mod:`.sweeps`).
Where the explicit FEM applies, a separate case measures on each level the cost of one
explicit step of the spring model and of the explicit P1 FEM (median of repeats, both in
the same run, same solver loop). Timings are noisy on a shared machine: they appear in
tables and findings, never in the headline numbers.

The bundled report runs it on the cantilever bar on ``[10, 1, 1]`` hexahedra refined by 1,
2, 4 (reference 6); ``springfem study speed-accuracy --scene FILE`` on the user's scene.
The study is split into :mod:`.cases` (settings, methods, one timed solve), :mod:`.tables`
(points with the Pareto front, step costs), :mod:`.figures` and :mod:`.findings`.

Examples
--------
>>> Settings.quick().levels, Settings.quick().reference
((1, 2), 4)
"""

from __future__ import annotations

from springfem.errors import SolverError
from springfem.files import safe_filename

from ..registry import StudyContext, StudyOutput, study
from ..scenes import StudyScene, require
from ..study_convergence.levels import level_label, select_levels
from .cases import (
    Settings,
    bundled_scenes,
    explicit_fem_refusal,
    method_name,
    point_case,
    point_work,
    points,
    reference_model,
    step_cost_case,
    step_cost_work,
)
from .figures import pareto_figure
from .findings import report_findings
from .tables import measure, pareto_front, points_frame, step_frame, write_tables

__all__ = ["Settings", "bundled_scenes", "pareto_front", "point_work", "run"]


@study("speed_accuracy", Settings, bundled_scenes, serial=True)
def run(ctx: StudyContext, scenes: list[StudyScene], settings: Settings) -> StudyOutput:
    """Time and error of every model at each level; the Pareto front."""
    require(scenes, "speed-accuracy")
    out = StudyOutput(ctx.name, "")
    for s in scenes:
        suffix = "" if len(scenes) == 1 else f"_{safe_filename(s.label)}"
        scene = s.build()
        wanted = sorted({*settings.levels, settings.reference})
        kept, notes = select_levels(s.table, scene.mesh.n_tets, wanted, settings.max_tets)
        levels = [k for k in settings.levels if k in kept]
        ref_level = settings.reference if settings.reference in kept else max(kept)
        ref_model = reference_model(scene.material.law)
        ref_text = f"{method_name(ref_model, 'static')} on {level_label(s.table, ref_level)}"
        ref_case = point_case(s, ref_model, "static", ref_level, {})
        ref = ctx.cache.run([ref_case], point_work, ctx.progress, "reference")[0]
        if ref["status"] != "ok":
            raise SolverError(f"the reference {ref_text} failed: {ref['message']}")
        cases = points(s, scene, levels, settings)
        how = measure(s, ref)
        df = points_frame(s, cases, ctx.cache.run(cases, point_work, ctx.progress, "points"),
                          ref, how)  # fmt: skip
        sdf = steps = None
        if explicit_fem_refusal(scene) is None:
            n = scene.mesh.n_tets
            step_cases = [step_cost_case(s, k, n * k**3) for k in levels]
            steps = ctx.cache.run(step_cases, step_cost_work, ctx.progress, "step cost")
            sdf = step_frame(s, levels, steps)
        finest = level_label(s.table, levels[-1])
        findings, headline, front = report_findings(
            df, steps[-1] if steps else None, how, finest, s.label, settings.max_error, cases
        )
        if notes:
            findings.insert(0, f"{s.label}: {'; '.join(notes)}.")
        out.findings += findings
        out.tables += write_tables(ctx, s, df, sdf, ref, ref_text, how, suffix)
        ref_seconds = float(ref.get("cpu_seconds", ref["seconds"]))
        out.figures.append(
            pareto_figure(ctx, df, how.column, ref_text, front, s.label, suffix, ref_seconds)
        )
        out.headline.update({f"{k}{suffix}": v for k, v in headline.items()})
    out.title = f"Speed against accuracy ({', '.join(s.label for s in scenes)})"
    return out
