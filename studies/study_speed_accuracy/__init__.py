"""Study ``speed_accuracy``: wall time against error, one point per method, mesh and setting.

The bundled cantilever (0.1 x 0.01 x 0.01 m, E = 1e4 Pa, nu = 0.3, end shear) on meshes of
``nx x ny x ny`` hexahedra (six tets each). Every point is one solve from the scene to the
tip displacement; its error is the relative error of the tip displacement vector against a
P2 solution on a finer mesh (Timoshenko's beam value is given for context). Methods:

- spring model (energy-consistent torsion, volume springs): ``static`` Newton, ``implicit``
  backward-Euler pseudo-time stepping to equilibrium (``dt`` a multiple of the critical
  step), ``explicit`` dynamic relaxation (:func:`springfem.mechanics.explicit_static`,
  kinetic damping) at two tolerances and two time-step safety factors;
- FEM P1 and P2, linear and coupled neo-Hookean, static (:func:`reference_fem.solve`);
- explicit P1 FEM, coupled neo-Hookean (:class:`reference_fem.explicit.ExplicitFem`), to
  equilibrium with the same solver and settings as the spring model.

The non-dominated (Pareto) points are those no other point beats in both time and error.
A separate case measures, on each mesh, the cost of one explicit step of the spring model
and of the explicit P1 FEM (median of repeats, both in the same run, same solver loop).
Timings are noisy on a shared machine: they appear in tables and findings, never in the
headline numbers.

The study is split into :mod:`.cases` (settings, scenes, one timed solve), :mod:`.tables`
(points with the Pareto front, step costs), :mod:`.figures` and :mod:`.findings`.

On a user's scene (``springfem study speed-accuracy --scene FILE``) the study runs as described in
:mod:`.scene`.

Examples
--------
>>> Settings.quick().reference
(40, 4)
"""

from __future__ import annotations

from ..registry import StudyContext, StudyOutput, study
from .cases import (
    STEP_REPEATS,
    TORSION,
    Settings,
    cantilever_table,
    cases_for,
    point_case,
    reference_case,
    step_cost_case,
    step_count,
    timoshenko_tip,
)
from .figures import pareto_figure
from .findings import report_findings
from .tables import pareto_front, points_frame, step_frame, write_tables

__all__ = [
    "TORSION",
    "Settings",
    "cantilever_table",
    "cases_for",
    "pareto_front",
    "point_case",
    "reference_case",
    "run",
    "timoshenko_tip",
]


@study("speed_accuracy", Settings)
def run(ctx: StudyContext, p: Settings) -> StudyOutput:
    """Run the speed-accuracy study (see the module docstring).

    Parameters
    ----------
    ctx
        Output folder, cache and preset.
    p
        Meshes and solver settings.

    Returns
    -------
    StudyOutput
        Findings, points and step-cost tables, the Pareto figure, headline numbers.
    """
    if p.scene is not None:
        from .scene import run_on_scene

        return run_on_scene(ctx, p)
    rx, ry = p.reference
    ref_case = {
        "kind": "reference",
        "mesh": [rx, ry],
        "scene": cantilever_table(rx, ry),
        "torsion": TORSION,
    }
    ref = ctx.cache.run([ref_case], reference_case, ctx.progress, "reference P2")[0]
    cases = cases_for(p)
    df = points_frame(cases, ctx.cache.run(cases, point_case, ctx.progress, "points"), ref)
    step_cases = [
        {
            "kind": "step_cost",
            "mesh": [nx, ny],
            "scene": cantilever_table(nx, ny),
            "torsion": TORSION,
            "repeats": STEP_REPEATS,
            "steps": step_count(6 * nx * ny * ny),
        }
        for nx, ny in p.meshes
    ]
    steps = ctx.cache.run(step_cases, step_cost_case, ctx.progress, "step cost")
    tables = write_tables(ctx, df, step_frame(p.meshes, steps), ref, p)
    findings, headline, front_text = report_findings(df, steps, p)
    return StudyOutput(
        name=ctx.name,
        title="Speed against accuracy",
        findings=findings,
        tables=tables,
        figures=[pareto_figure(ctx, df, p, front_text)],
        headline=headline,
    )
