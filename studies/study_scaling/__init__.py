"""Study ``scaling``: cost per explicit step and per static solve against the number of tets.

The benchmark block of :func:`.cases.bench_table` (2:1:1, clamped at one end,
end traction, six tets per hexahedron) from about 1e3 to 1e5 tets:

- one explicit step (forces + symplectic-Euler update through
  :func:`springfem.mechanics.explicit`) of the spring model and of the explicit P1
  neo-Hookean FEM, serial kernels (the work per element; the parallel speed-up on this
  machine is what ``springfem bench forces`` measures), median of repeats, both in one case;
- the set-up of each (spring elements: ray casting and calibration; FEM: shape gradients);
- one static solve: the spring model's Newton (energy-consistent torsion, analytic Hessian,
  AMG above 30k DOFs) and reference FEM P1, linear and coupled neo-Hookean.

Costs are CPU (process) times, which on a shared machine are what the wall time would be
on an idle one for these serial codes; wall times are in the tables. The log-log slopes
(:func:`studies.metrics.fitted_rate`) are the headline numbers, rounded.

The study is split into :mod:`.cases` (the block, one step or static case, settings),
:mod:`.tables`, :mod:`.figures` and :mod:`.findings`.

Examples
--------
>>> Settings.quick().neo_max
10000
"""

from __future__ import annotations

from ..registry import StudyContext, StudyOutput, study_run
from ..scenes import StudyScene
from .cases import (
    Settings,
    bundled_scenes,
    grids,
    static_case,
    step_case,
)
from .figures import scaling_figure
from .findings import report_findings
from .tables import frames, slopes, write_tables

__all__ = ["Settings", "bundled_scenes", "run"]


#: Why the study does not run on a user's scene.
NO_USER_SCENES = (
    "it times generated box meshes of chosen sizes (a cost curve), not one scene; "
    "`springfem bench` times a model"
)


@study_run(
    "scaling",
    Settings,
    bundled_scenes,
    scenes_doc="The benchmark blocks (roles ``step`` and ``static``).",
    settings_doc="Tet counts.",
    returns="Findings, step/solve/slope tables, the scaling figure, headline slopes.",
    user_scenes=NO_USER_SCENES,
    serial=True,
)
def run(ctx: StudyContext, scenes: list[StudyScene], p: Settings) -> StudyOutput:
    step_cases, static_cases = grids(scenes, p)
    steps = ctx.cache.run(step_cases, step_case, ctx.progress, "explicit steps")
    static = ctx.cache.run(static_cases, static_case, ctx.progress, "static solves")
    sdf, tdf = frames(steps, static_cases, static)
    slope = slopes(sdf, tdf)
    findings, headline = report_findings(sdf, tdf, slope)
    caption = (
        f"Left: CPU time per explicit step against tet count (log-log, fitted slopes in the "
        f"legend); right: CPU time per static solve. {findings[0]}"
    )
    return StudyOutput(
        name=ctx.name,
        title="Cost against mesh size",
        findings=findings,
        tables=write_tables(ctx, sdf, tdf, slope),
        figures=[scaling_figure(ctx, sdf, tdf, slope, caption)],
        headline=headline,
    )
