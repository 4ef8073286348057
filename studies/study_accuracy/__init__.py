"""Study ``accuracy``: how wrong is the spring model on a scene, and why.

Per scene (bundled: bending = ``cantilever``, stretch along fibers = ``stretch-fiber``,
across = ``stretch-cross``, sag under gravity = ``sag``, and the cantilever on unstructured
and elongated meshes; or the user's ``--scene``) the comparison of :mod:`studies.compare`
is run and three errors are separated (the manual's "model and discretisation error"):

- *model error*: spring vs P1 FEM on the same mesh with the reference's law (what the spring
  element itself gets wrong);
- *total error*: spring vs the reference (P2, neo-Hookean P2 for large strains);
- *discretisation error*: P1 vs the reference (what the mesh alone costs a P1 element).

Probe displacements are also checked against a scene's closed-form reference where it has
one (:mod:`studies.analytic`: Timoshenko for the cantilever, ``sigma L / E`` for the
uniaxial stretches).
"""

from __future__ import annotations

import numpy as np

from .. import analytic
from ..compare import MODELS
from ..compare_output import error_figure, figure_fields
from ..registry import Figure, StudyContext, StudyOutput, study
from ..scenes import StudyScene
from .cases import (
    DISCRETISATION_HEADLINE,
    ERROR_KINDS,
    EXACT_KINDS,
    SCENES,
    Settings,
    bundled_scenes,
    nan_float,
    scene_case,
    work,
)
from .figures import bar_figure, field_conclusion
from .findings import report_findings
from .tables import error_table, probe_table

__all__ = ["DISCRETISATION_HEADLINE", "SCENES", "Settings", "bundled_scenes", "run", "work"]


@study("accuracy", Settings, bundled_scenes)
def run(ctx: StudyContext, scenes: list[StudyScene], settings: Settings) -> StudyOutput:
    """Spring, P1 and reference solves per scene; the three errors and the probes."""
    names = [s.label for s in scenes]
    cases = [scene_case(s, settings) for s in scenes]
    results = ctx.cache.run(cases, work, progress=ctx.progress, desc="accuracy")
    built = {s.label: s.build() for s in scenes}
    refs = {s.label: analytic.reference(s, built[s.label]) for s in scenes}
    lateral = {s.label: analytic.LATERAL.get(s.analytic or "") for s in scenes}
    res = dict(zip(names, results, strict=True))

    errors = error_table(res)
    t_err = ctx.table(
        errors,
        "accuracy_errors",
        "Relative errors over the mesh vertices per scene: model error = spring vs P1 on the "
        "same mesh (same law as the reference), total = spring vs the reference, "
        "discretisation = P1 vs the reference; L2 = ‖u − u_ref‖/‖u_ref‖, max = largest nodal "
        "error / largest reference displacement.",
    )

    probes = probe_table(res, refs, lateral)
    t_probe = ctx.table(
        probes,
        "accuracy_probes",
        "Main probe displacement component per scene: analytic value (Timoshenko beam, "
        "uniaxial stress σL/E), spring model, same-mesh P1 and the reference; 'lateral' is the "
        "transverse (Poisson) displacement at the stretch probes (u_y for stretch-fiber, "
        "u_z for stretch-cross).",
    )

    # -- figures -------------------------------------------------------------------------
    figures = [bar_figure(ctx, errors, probes)]
    for name in (s.label for s in scenes if s.serves("figure")):
        r = res.get(name, {})
        if "u" not in r:
            continue
        fields = {n: np.asarray(r["u"][n], float) for n in MODELS if n in r["u"]}
        fields, note = figure_fields(fields, r["reference"])
        path = error_figure(
            built[name],
            fields,
            r["reference"],
            ctx.path(f"error_field_{name}.png"),
            laws=r["laws"],
            note=note,
        )
        e = r["errors"]
        figures.append(
            Figure(
                path,
                f"{name}: deformed meshes coloured by the displacement error against "
                f"{r['reference']} (one colour scale). " + field_conclusion(built[name], r, e),
            )
        )

    findings = report_findings(res, errors, probes, ctx.quick)
    headline = {}
    for name in names:
        key = name.replace("-", "_")
        for kind in ERROR_KINDS + EXACT_KINDS:
            if kind == "discretisation" and name not in DISCRETISATION_HEADLINE:
                continue  # P1 is exact there: round-off, not a stable number
            if kind not in res[name]["errors"]:
                continue
            value = nan_float(res[name]["errors"][kind].get("rel_l2"))
            if kind in EXACT_KINDS and not np.isfinite(value):
                continue  # no finite-strain P1 for an anisotropic material
            headline[f"{kind}_l2_{key}"] = value
        for kind_name, e in res[name]["errors"].items():  # the plug-in models
            kind, _, peer = kind_name.partition(":")
            if peer:
                headline[f"{peer.replace('-', '_')}_{kind}_l2_{key}"] = nan_float(e.get("rel_l2"))
    return StudyOutput(
        name=ctx.name,
        title="Accuracy: spring model vs FEM per scene (model, total, discretisation error)"
        + ("" if not scenes[0].user else f" on {names[0]}"),
        findings=findings,
        tables=[t_err, t_probe],
        figures=figures,
        headline=headline,
    )
