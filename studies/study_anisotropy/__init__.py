"""Study ``anisotropy``: effective modulus of a transversely isotropic block against fiber angle.

The bundled ``stretch-fiber`` scene (a cube of transversely isotropic material, E_f = 30 kPa,
E_c = 10 kPa, G_f = 5 kPa, ν_fc = 0.3, ν_c = 0.4) with its fiber rotated by θ in the x-y plane
(fiber ``(cos θ, sin θ, 0)``, sheet ``(-sin θ, cos θ, 0)``) and pulled along x by a uniform
traction σ on ``x_max``. The scene's boundary conditions only remove rigid motion: the
``x_min`` face is held in x alone (it slides in y and z), the origin is pinned in y and z and
the corner ``(0, L, 0)`` in z. A homogeneous strain with any shear is compatible with them
(the body rotates rigidly so that ``x_min`` stays at x = 0), so the state is uniaxial
stress, the coupled shear ``γ_xy`` is free, and the off-axis formula

    1/E(θ) = cos⁴θ/E_f + sin⁴θ/E_c + (1/G_f − 2ν_fc/E_f) sin²θ cos²θ

is exact for the continuum and for P1/P2 (a homogeneous field is in both spaces).

Measured: ``E_eff = σ / ε_xx`` with ``ε_xx`` the mean x displacement of the ``x_max`` nodes
over L, for the spring model (analytic and nnls calibration), FEM P1 and P2; and the shear
coupling ``γ_xy / ε_xx`` from a least-squares affine fit of the nodal displacements,
against the rotated compliance.

The study is split into :mod:`.cases` (scene, off-axis formula, one measurement,
settings), :mod:`.tables`, :mod:`.figures` and :mod:`.findings`.

On a user's scene (``springfem study anisotropy --scene FILE``) the study runs as described in
:mod:`.scene`.

Examples
--------
>>> round(off_axis_modulus(fiber_scene(0.0, 1).material, 0.0))
30000
"""

from __future__ import annotations

from ..registry import StudyContext, StudyOutput, study
from .cases import (
    MODELS,
    Settings,
    affine_fit,
    applied_stress,
    compliance_voigt,
    fiber_scene,
    fiber_table,
    modulus_case,
    off_axis_modulus,
    off_axis_strain,
)
from .figures import modulus_figure
from .findings import report_findings
from .tables import modulus_frame, modulus_table, ratio_frame, ratio_table, worst_errors

__all__ = [
    "MODELS",
    "Settings",
    "affine_fit",
    "applied_stress",
    "compliance_voigt",
    "fiber_scene",
    "fiber_table",
    "modulus_case",
    "off_axis_modulus",
    "off_axis_strain",
    "run",
]


@study("anisotropy", Settings)
def run(ctx: StudyContext, settings: Settings) -> StudyOutput:
    """Run the anisotropy study (see the module docstring).

    Parameters
    ----------
    ctx
        Output folder, cache and preset.
    settings
        Angles and mesh.

    Returns
    -------
    StudyOutput
        Findings, modulus and ratio tables, the modulus figure, headline errors.
    """
    if settings.scene is not None:
        from .scene import run_on_scene

        return run_on_scene(ctx, settings)
    n = settings.n
    scene0 = fiber_scene(0.0, n)
    mat = scene0.material
    sigma = applied_stress(scene0)
    cases = []
    for label, (kind, setting) in MODELS.items():
        for a in settings.angles:
            c = {"angle": a, "n": n, "model": kind}
            c["calibration" if kind == "spring" else "order"] = setting
            cases.append((label, c))
    res = ctx.cache.run([c for _, c in cases], modulus_case, ctx.progress, "angles")
    df = modulus_frame(cases, res, mat, sigma)
    ratios, ratio_an = ratio_frame(df, mat)
    spring_err, worst_angle = worst_errors(df)
    findings, headline = report_findings(df, ratios, ratio_an, mat, spring_err, worst_angle)
    return StudyOutput(
        name=ctx.name,
        title="Anisotropy: effective modulus against fiber angle",
        findings=findings,
        tables=[modulus_table(ctx, df, mat, sigma, n), ratio_table(ctx, ratios)],
        figures=[modulus_figure(ctx, df, mat, sigma, n, spring_err, worst_angle)],
        headline=headline,
    )
