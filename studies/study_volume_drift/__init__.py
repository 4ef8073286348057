"""Study ``volume_drift``: how well each volume treatment holds volume.

A nearly incompressible block (ν = 0.49, E = 5 kPa) in uniaxial stress along z (the base
slides freely, one point and one edge pinned against rigid motion) is compressed and pulled,
and the bundled ``sag`` scene (ν = 0.45, neo-Hookean, clamped at one end) sags under its own
weight. The spring model runs with

* ``volume off``: axial + torsion (energy) springs only,
* ``volume on``: + barycentric volume springs (2.76–2.77, gradient form),
* ``LMS spec``: + adaptive volume stiffness, eq. 2.81 as written (``k += mu dV sum|xi|``),
* ``LMS abs``: + the sign-consistent rule (``k += mu |dV| sum|xi|``),
* ``volume on (nnls)``: volume springs with the per-element least-squares calibration,

through explicit dynamics (:func:`springfem.mechanics.explicit`, LMS applied by the model's
``post_step`` once per step): a suddenly applied load (drift against time) and a slow load
ramp (drift against load factor). The FEM reference (P1, linear and neo-Hookean, static) and
the small-strain analytic volume change ``tr eps = (1 - 2 nu) sigma / E`` give what the
material itself does.

All explicit runs of one scene use the same time step, ``0.5 dt_crit / sqrt(k_max)`` with
``dt_crit`` of the ``volume on`` model: LMS may stiffen a volume spring up to ``k_max`` times,
which raises ``omega_max`` by up to ``sqrt(k_max)``.

Drift measures: ``|dV|/V0`` of the whole body, and the element drift
``sum_k |V_k - V0_k| / V0`` (in bending, compressed and stretched elements cancel in the
total). ``|dL|/L0`` is the mean relative change of the radial sums ``sum_j |xi_j|``, the
quantity a volume spring actually restores.

The study is split into :mod:`.cases` (scenes, settings, one run), :mod:`.tables`
(the runs' outcomes, the numbers quoted and the two tables), :mod:`.figures` and
:mod:`.findings`.

On a user's scene (``springfem study volume-drift --scene FILE``) the study runs as described in
:mod:`.scene`.

Examples
--------
>>> Settings.quick().n
2
"""

from __future__ import annotations

from typing import Any

from ..registry import StudyContext, StudyOutput, study
from .cases import (
    CUBE_E,
    CUBE_STRESS,
    K_MAX,
    K_MIN,
    VARIANTS,
    Settings,
    analytic_drift,
    cube_scene,
    cube_table,
    drift_measures,
    dynamic_case,
    sag_fem_case,
    sag_scene,
    static_case,
)
from .figures import load_figure, time_figure
from .findings import report_findings
from .tables import Runs, final_table, static_frame, static_table

__all__ = [
    "CUBE_E",
    "CUBE_STRESS",
    "K_MAX",
    "K_MIN",
    "VARIANTS",
    "Settings",
    "analytic_drift",
    "cube_scene",
    "cube_table",
    "drift_measures",
    "dynamic_case",
    "run",
    "sag_scene",
    "static_case",
]

#: Poisson's ratio of the cube (nearly incompressible).
NU = 0.49


def dynamic_cases(s: Settings, nu: float = NU) -> list[tuple[dict[str, Any], str, str]]:
    """The explicit runs: ``(case, label, kind)`` for the cube (compressed and pulled, sudden
    step and slow ramp) and the sag scene, each for every variant.

    Parameters
    ----------
    s
        The study's settings.
    nu
        Poisson's ratio of the cube.

    Returns
    -------
    list
        ``(case for dynamic_case, "compressed" | "pulled" | "sag", "step" | "ramp")``.
    """
    cube = {"scene": "cube", "n": s.n, "nu": nu}
    runs = []
    for sign, label in ((-1.0, "compressed"), (1.0, "pulled")):
        for kind, ramp, periods, damping in (
            ("step", 0.0, s.periods, 0.3),
            ("ramp", s.ramp_periods, s.ramp_periods + 1.0, 0.5),
        ):
            for v in VARIANTS:
                case = {
                    **cube,
                    "stress": sign * CUBE_STRESS,
                    "variant": v,
                    "ramp": ramp,
                    "periods": periods,
                    "damping": damping,
                    "records": s.records,
                }
                runs.append((case, label, kind))
    if s.sag:
        for v in VARIANTS:
            case = {
                "scene": "sag",
                "divisions": list(s.sag),
                "variant": v,
                "ramp": 0.0,
                "periods": 2.0,
                "damping": 0.4,
                "records": s.records,
            }
            runs.append((case, "sag", "step"))
    return runs


def static_cases(s: Settings, nu: float = NU) -> list[dict[str, Any]]:
    """The static equilibria of the cube: FEM P1 (linear, neo-Hookean) at every load factor,
    the spring variants without LMS at full load, both signs.

    Parameters
    ----------
    s
        The study's settings.
    nu
        Poisson's ratio of the cube.

    Returns
    -------
    list of dict
        Cases for :func:`~.cases.static_case`.
    """
    cube = {"scene": "cube", "n": s.n, "nu": nu}
    cases = []
    for sign in (-1.0, 1.0):
        for f in s.loads:
            base = {**cube, "stress": sign * CUBE_STRESS, "load": f}
            for law in ("linear", "neo-hookean"):
                cases.append({**base, "model": "fem", "law": law, "order": 1})
            if f == 1.0:
                for v in ("volume off", "volume on", "volume on (nnls)", "axis-volume (exact)"):
                    cases.append({**base, "model": "spring", "variant": v})
    return cases


@study("volume_drift", Settings)
def run(ctx: StudyContext, s: Settings) -> StudyOutput:
    """Run the volume-drift study (see the module docstring).

    Parameters
    ----------
    ctx
        Output folder, cache and preset.
    s
        Meshes, run lengths and loads.

    Returns
    -------
    StudyOutput
        Findings, drift tables, the drift figures, headline drifts.
    """
    if s.scene is not None:
        from .scene import run_on_scene

        return run_on_scene(ctx, s)
    grid = dynamic_cases(s)
    res = ctx.cache.run([g[0] for g in grid], dynamic_case, ctx.progress, "dynamic runs")
    dyn = [(c, label, kind, r) for (c, label, kind), r in zip(grid, res)]

    stat_cases = static_cases(s)
    stat_res = ctx.cache.run(stat_cases, static_case, ctx.progress, "statics")
    sag_ref = None
    if s.sag:
        sag_ref = ctx.cache.run(
            [{"scene": "sag", "divisions": list(s.sag), "model": "fem-neo-hookean"}],
            sag_fem_case,
            ctx.progress,
            "sag FEM",
        )[0]
    runs = Runs(dyn, static_frame(stat_cases, stat_res), sag_ref, NU)

    findings, headline = report_findings(runs, s)
    return StudyOutput(
        name=ctx.name,
        title="Volume drift: volume springs, LMS rules and FEM",
        findings=findings,
        tables=[final_table(ctx, runs, s), static_table(ctx, runs)],
        figures=[time_figure(ctx, runs, s), load_figure(ctx, runs)],
        headline=headline,
    )
