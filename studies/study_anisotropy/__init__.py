"""Study ``anisotropy``: the spring model's response along and across the fibre.

On every scene, under its own loads, the spring model (analytic and nnls calibration, and
the exact element with Poisson-coupling springs) and FEM P1 and P2 with the scene's law;
each model's displacement error against P2 (total) and against P1 on the same mesh (model
error) is split into the fibre direction and across it, at every vertex (the fibre ``f``
there: the principal direction of ``sum f f^T`` over the tets around it, so a fibre's sign
does not matter): ``e·f`` and ``e - (e·f) f``, relative to ``||u_ref||``; and the fibre
strain ``f·εf`` and the mean cross-fibre normal strain per tet. The study needs a law with
a fibre and the fibre stated in ``[axes]``; it refuses another scene in one line.

A scene with the off-axis closed form (:func:`studies.analytic.off_axis_modulus`) also
gives the effective modulus. The bundled report runs the ``stretch-fiber`` block (E_f =
30 kPa, E_c = 10 kPa, G_f = 5 kPa, ν_fc = 0.3, ν_c = 0.4) with its fibre rotated by θ in the
x-y plane and pulled along x by a traction σ on ``x_max``. Its boundary conditions only
remove rigid motion (``x_min`` held in x alone, the origin pinned in y and z, the corner
``(0, L, 0)`` in z), so the state is uniaxial stress with the coupled shear ``γ_xy`` free,
and the off-axis formula

    1/E(θ) = cos⁴θ/E_f + sin⁴θ/E_c + (1/G_f − 2ν_fc/E_f) sin²θ cos²θ

is exact for the continuum and for P1/P2 (a homogeneous field is in both spaces). Measured:
``E_eff = σ / ε_xx`` with ``ε_xx`` the mean x displacement of the ``x_max`` vertices over L,
and the shear coupling ``γ_xy / ε_xx`` of a least-squares affine fit of the displacements,
against the rotated compliance (:func:`studies.analytic.off_axis_strain`).

The study is split into :mod:`.cases` (settings, scenes, one solve, the measures),
:mod:`.tables`, :mod:`.figures` and :mod:`.findings`.

Examples
--------
>>> [s.label for s in bundled_scenes(Settings.quick())]
['stretch-fiber 0°', 'stretch-fiber 30°', 'stretch-fiber 60°', 'stretch-fiber 90°']
"""

from __future__ import annotations

from springfem.errors import InputError

from ..registry import StudyContext, StudyOutput, study_run
from ..scenes import StudyScene, require
from .cases import (
    Settings,
    bundled_scenes,
    grid,
    refusal,
    solve_case,
)
from .figures import modulus_figure
from .findings import modulus_findings, split_findings
from .tables import frames, modulus_table, ratio_frame, ratio_table, split_table, worst_errors

__all__ = ["Settings", "bundled_scenes", "run"]


@study_run(
    "anisotropy",
    Settings,
    bundled_scenes,
    scenes_doc="The scenes (each needs a law with a fibre and ``[axes]``).",
    settings_doc="Angles and mesh of the bundled blocks (unused for other scenes).",
    returns=(
        "Findings, the error-split table (and on the blocks with a closed form "
        "the modulus and ratio tables and the modulus figure), headline errors. "
        "Raises ------ InputError If a scene has no fibre (one line, before any "
        "solve)."
    ),
)
def run(ctx: StudyContext, scenes: list[StudyScene], settings: Settings) -> StudyOutput:
    require(scenes, ctx.name)
    for s in scenes:
        why = refusal(s)
        if why is not None:
            raise InputError(f"study anisotropy cannot run on --scene: {why}")
    cases = grid(scenes)
    results = ctx.cache.run(cases, solve_case, ctx.progress, "models")
    split, modulus, failed = frames(scenes, cases, results)
    findings, headline = [], {}
    tables, figures = [], []
    if len(modulus):
        scene = next(s for s in scenes if s.label == modulus.scene.iloc[0]).build()
        sigma, n_tets = float(scene.loads[0].value[0]), scene.mesh.n_tets
        ratios, ratio_an = ratio_frame(modulus)
        worst, worst_angle = worst_errors(modulus)
        f, h = modulus_findings(modulus, ratios, ratio_an, scene.material, worst, worst_angle)
        findings, headline = findings + f, {**headline, **h}
        tables += [modulus_table(ctx, modulus, sigma, n_tets), ratio_table(ctx, ratios)]
        figures.append(
            modulus_figure(ctx, modulus, scene.material, sigma, n_tets, worst, worst_angle)
        )
    findings += split_findings(split, failed)[0]
    # the error split is the headline of the scenes without a closed form
    open_split = split[~split.scene.isin(set(modulus.scene) if len(modulus) else set())]
    if len(open_split):
        headline.update(split_findings(open_split, failed)[1])
    tables.append(split_table(ctx, split))
    names = ", ".join(dict.fromkeys(s.table.get("name") or s.label for s in scenes))
    return StudyOutput(
        name=ctx.name,
        title=f"Anisotropy: response along and across the fibre ({names})",
        findings=findings,
        tables=tables,
        figures=figures,
        headline=headline,
    )
