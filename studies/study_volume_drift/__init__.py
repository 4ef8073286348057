"""Study ``volume_drift``: how well each volume treatment holds volume.

On every scene, under its own loads, the spring model runs with

* ``spring-volume-off``: axial + torsion springs only,
* ``spring-volume-on``: + barycentric volume springs (2.76–2.77, gradient form),
* ``spring-lms-spec``: + adaptive volume stiffness, eq. 2.81 as written
  (``k += mu dV sum|xi|``),
* ``spring-lms-abs``: + the sign-consistent rule (``k += mu |dV| sum|xi|``),
* ``spring-volume-nnls``: volume springs on the per-element least-squares calibration,
* ``spring-exact``: the exact element (axis-volume spring on ``J = det[ζ]/det[ζ⁰]``),

through damped explicit dynamics (:func:`springfem.mechanics.explicit`, LMS applied by the
model's ``post_step`` once per step): a suddenly applied load (drift against time) and a
slow load ramp (drift against load factor). Static equilibria give what the material
itself does: same-mesh P1 FEM (the scene's small-strain law, neo-Hookean for an isotropic
material, at several load factors), the scene's own FEM, and the spring variants without
LMS (Newton); a scene whose state has a closed form adds its volume change
(:func:`studies.analytic.volume_change`).

The bundled report runs it on the drift cube (``drift-cube``: ν = 0.49, E = 5 kPa, uniaxial
stress along z, compressed and pulled by 10 % of E, closed form ``(1 - 2ν) σ / E``) and the
``sag`` scene (ν = 0.45, neo-Hookean, sagging under its own weight; static and sudden-load
runs); ``springfem study volume-drift --scene FILE`` runs every series on the user's scene.

All explicit runs of one scene use the same time step, ``0.5 dt_crit / sqrt(k_max)`` with
``dt_crit`` of ``spring-volume-on``: LMS may stiffen a volume spring up to ``k_max`` times.
Run lengths and damping are in periods of the scene's time scale: the quarter-wave period
of a rod as long as the body, with the stiffest longitudinal modulus of the material; the
bundled scenes keep their own (:data:`~.cases.BUNDLED_TIME`).

Drift measures: ``|dV|/V0`` of the whole body, and the element drift
``sum_k |V_k - V0_k| / V0`` (in bending, compressed and stretched elements cancel in the
total). ``|dL|/L0`` is the mean relative change of the radial sums ``sum_j |xi_j|``, the
quantity a volume spring actually restores.

The study is split into :mod:`.cases` (settings, variants, scenes, the series' cases),
:mod:`.work` (one static solve or explicit run), :mod:`.tables` (the runs' outcomes and
the two tables), :mod:`.figures` and :mod:`.findings`.

Examples
--------
>>> [s.label for s in bundled_scenes(Settings.quick())]
['cube compressed', 'cube pulled']
"""

from __future__ import annotations

from ..analytic import volume_change
from ..registry import StudyContext, StudyOutput, study
from ..scenes import StudyScene, require
from .cases import Settings, bundled_scenes, grids
from .figures import load_figure, time_figure
from .findings import report_findings
from .tables import Runs, final_table, static_frame, static_table
from .work import WORK

__all__ = ["Settings", "bundled_scenes", "run"]


@study("volume_drift", Settings, bundled_scenes)
def run(ctx: StudyContext, scenes: list[StudyScene], s: Settings) -> StudyOutput:
    """Volume drift over time and under static load, per model."""
    require(scenes, ctx.name)
    cases = grids(scenes, s)
    res = {k: ctx.cache.run(cases[k], fn, ctx.progress, label) for k, (fn, label) in WORK.items()}
    dynamic = [(c, r) for k in ("step", "ramp") for c, r in zip(cases[k], res[k], strict=True)]
    volume = {sc.label: volume_change(sc, None) for sc in scenes}
    runs = Runs(scenes, static_frame(cases["static"], res["static"]), dynamic, volume)
    findings, headline = report_findings(runs)
    figures = []
    if cases["step"]:
        figures.append(time_figure(ctx, runs))
    if cases["ramp"]:
        figures.append(load_figure(ctx, runs))
    names = ", ".join(sc.label for sc in scenes)
    return StudyOutput(
        name=ctx.name,
        title=f"Volume drift: volume springs, LMS rules and FEM ({names})",
        findings=findings,
        tables=[final_table(ctx, runs), static_table(ctx, runs)],
        figures=figures,
        headline=headline,
    )
