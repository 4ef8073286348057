"""Study ``stability``: where each method fails.

1. Critical time step: the measured largest stable explicit step (bisection on runs from a
   perturbed rest state) against the predicted ``2 / omega_max``, for spring variants and
   the explicit P1 FEM step.
2. Largest load survived: a cantilever loaded ever harder, solved statically by the spring
   model (energy and cosine torsion), linear FEM (survives any load but its deformed mesh
   inverts) and neo-Hookean Newton (diverges or inverts); what fails is recorded.
3. Near-incompressibility: tip deflection against Poisson's ratio for P1 (locks), P2 and
   the spring model, with the spring model's volume change.
4. Failure map: load factor × time-step factor, explicit damped dynamics, per method.

The study is split into :mod:`.cases` (the bar, one run per series, settings and grids),
:mod:`.tables`, :mod:`.figures` and :mod:`.findings`.

On a user's scene (``springfem study stability --scene FILE``) the study runs as described in
:mod:`.scene`.

Examples
--------
>>> sorted(grids(Settings.quick()))
['dt', 'load', 'lock', 'map']
"""

from __future__ import annotations

from ..registry import StudyContext, StudyOutput, study
from .cases import (
    Settings,
    bar_scene,
    bar_table,
    critical_step_case,
    failure_map_case,
    grids,
    load_case,
    locking_case,
)
from .figures import failure_map_figure, locking_figure
from .findings import report_findings
from .tables import frames, write_tables

__all__ = [
    "Settings",
    "bar_scene",
    "bar_table",
    "critical_step_case",
    "failure_map_case",
    "grids",
    "load_case",
    "locking_case",
    "run",
]

#: Series -> (the work of one case, progress label).
WORK = {
    "dt": (critical_step_case, "critical dt"),
    "load": (load_case, "max load"),
    "lock": (locking_case, "locking"),
    "map": (failure_map_case, "failure map"),
}


@study("stability", Settings)
def run(ctx: StudyContext, settings: Settings) -> StudyOutput:
    """Run the stability study (see the module docstring).

    Parameters
    ----------
    ctx
        Output folder, cache and preset.
    settings
        Grids of the four series.

    Returns
    -------
    StudyOutput
        Findings, four tables, figures and headline numbers.
    """
    if settings.scene is not None:
        from .scene import run_on_scene

        return run_on_scene(ctx, settings)
    cases = grids(settings)
    results = {
        k: ctx.cache.run(cases[k], fn, ctx.progress, label) for k, (fn, label) in WORK.items()
    }
    f = frames(cases, results)
    findings, headline = report_findings(f, settings)
    return StudyOutput(
        name=ctx.name,
        title="Stability: where each method fails",
        findings=findings,
        tables=write_tables(ctx, f),
        figures=[
            locking_figure(ctx, f["lock"], settings),
            failure_map_figure(ctx, f["map"], settings),
        ],
        headline=headline,
    )
