"""Study ``stability``: where each method fails.

1. Critical time step: the measured largest stable explicit step (bisection on runs from a
   perturbed rest state, loads off) against the predicted ``2 / omega_max``, for the spring
   variants, the explicit P1 FEM and the plug-in models with a mechanical system (the
   mass-spring network); for XPBD (Gauss–Seidel and Jacobi) the largest substep it
   survives, against ``2 / omega_max`` of its own energy (its ``largest_step``).
2. Largest load survived: the scene's loads times growing factors, solved statically by the
   spring model (energy, cosine torsion, the exact element), small-strain FEM (survives any
   load, but past 10 % of the body's size its solution is no solution: ``unphysical``) and
   neo-Hookean Newton (diverges or inverts) and the plug-in models (XPBD's run to rest, and
   its Jacobi variant's);
   what fails is recorded. A summary table and figure (``survival``) give every method's
   largest step and largest load.
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
from .figures import failure_map_figure, locking_figure, survival_figure
from .findings import report_findings
from .tables import frames, survival, write_tables

__all__ = ["Settings", "bundled_scenes", "run"]


@study("stability", Settings, bundled_scenes)
def run(ctx: StudyContext, scenes: list[StudyScene], settings: Settings) -> StudyOutput:
    """Critical steps, largest loads, locking and the failure map."""
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
    if len(f["dt"]) and len(f["load"]):
        figures.insert(0, survival_figure(ctx, survival(f), f["dt"]))
    findings, headline = report_findings(f, settings)
    return StudyOutput(
        name=ctx.name,
        title=f"Stability: where each method fails ({names})",
        findings=findings,
        tables=write_tables(ctx, f),
        figures=figures,
        headline=headline,
    )
