"""Study ``stability``: where each method fails.

1. Critical time step: the measured largest stable explicit step (bisection on runs from a
   perturbed rest state, loads off) against the predicted ``2 / omega_max``, for the spring
   variants and the explicit P1 FEM.
2. Largest load survived: the scene's loads times growing factors, solved statically by the
   spring model (energy, cosine torsion, the exact element), small-strain FEM (survives any
   load, but past 10 % of the body's size its solution is no solution: ``unphysical``) and
   neo-Hookean Newton (diverges or inverts); what fails is recorded.
3. Near-incompressibility, on a scene with a beam-theory reference (the bundled bar): tip
   deflection against Poisson's ratio for P1 (locks), P2 and the spring model, with the
   spring model's volume change.
4. Failure map: load factor × time-step factor, explicit damped dynamics, per method.

The bundled report runs it on the cantilever bar (0.1 × 0.01 × 0.01 m) at the meshes of
the settings; ``springfem study stability --scene FILE`` on the user's scene, which serves
every series but the locking one (its reference is beam theory). The explicit FEM has
isotropic laws only: on an anisotropic scene the explicit series run the spring variants.

The study is split into :mod:`.cases` (settings, the bar, one run per series),
:mod:`.critical_step`, :mod:`.tables`, :mod:`.figures` and :mod:`.findings`.

Examples
--------
>>> [s.label for s in bundled_scenes(Settings.quick())]
['bar 10x1x1', 'bar 20x2x2']
"""

from __future__ import annotations

from ..registry import StudyContext, StudyOutput, study
from ..scenes import StudyScene
from .cases import WORK, Settings, bundled_scenes, grids
from .figures import failure_map_figure, locking_figure
from .findings import report_findings
from .tables import frames, write_tables

__all__ = ["Settings", "bundled_scenes", "run"]


@study("stability", Settings, bundled_scenes)
def run(ctx: StudyContext, scenes: list[StudyScene], settings: Settings) -> StudyOutput:
    """Run the stability study (see the module docstring).

    Parameters
    ----------
    ctx
        Output folder, cache and preset.
    scenes
        The scenes (each serves the series its ``roles`` name; a user's serves all).
    settings
        Grids of the four series.

    Returns
    -------
    StudyOutput
        Findings, tables (critical step, largest load, locking, failure map), figures and
        headline numbers.
    """
    cases = grids(scenes, settings)
    results = {
        k: ctx.cache.run(cases[k], fn, ctx.progress, label) for k, (fn, label) in WORK.items()
    }
    f = frames(cases, results)
    names = ", ".join(s.label for s in scenes)
    methods = tuple(dict.fromkeys(f["map"]["method"])) if len(f["map"]) else ()
    figures = [failure_map_figure(ctx, f["map"], settings, methods)] if len(f["map"]) else []
    if len(f["lock"]):
        figures.insert(0, locking_figure(ctx, f["lock"], settings))
    findings, headline = report_findings(f, settings)
    return StudyOutput(
        name=ctx.name,
        title=f"Stability: where each method fails ({names})",
        findings=findings,
        tables=write_tables(ctx, f),
        figures=figures,
        headline=headline,
    )
