"""Study ``accuracy``: how wrong is the spring model on a scene, and why.

Per scene (bundled: bending = ``cantilever``, stretch along fibers = ``stretch-fiber``,
across = ``stretch-cross``, sag under gravity = ``sag``, and the cantilever on unstructured
and elongated meshes; or the user's ``--scene``) the comparison of :mod:`studies.compare`
is run and three errors are separated (the manual's "model and discretisation error"):

- *model error*: spring vs P1 FEM on the same mesh with the reference's law (what the spring
  element itself gets wrong);
- *total error*: spring vs the reference (P2, neo-Hookean P2 for large strains);
- *discretisation error*: P1 vs the reference (what the mesh alone costs a P1 element).

The exact spring element and the plug-in models (:mod:`springfem.model_api`) are weighed
too. Probe displacements are checked against a scene's closed-form reference where it has
one (:mod:`studies.analytic`: Timoshenko for the cantilever, ``sigma L / E`` for the
uniaxial stretches).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from springfem.materials.tissue import TISSUE_LAWS

from . import analytic, metrics, models
from .compare import COMPONENTS, MODELS, Comparison, compare_scene, max_principal_strain
from .compare_output import error_figure, figure_fields
from .plots import grouped_bars
from .registry import Figure, StudyContext, StudyOutput, study
from .scenes import COMPARISON_SCENES, StudyScene, case_scene, comparison_scenes
from .tables import pyplot

SCENES = tuple(COMPARISON_SCENES)
DISCRETISATION_HEADLINE = ("cantilever", "sag")  # P1 is exact on the uniaxial stretches
ERROR_KINDS = ("model", "total", "discretisation")
#: Errors of the exact element and the specification's against the finite-strain P1.
EXACT_KINDS = ("exact_model", "exact_model_nh", "exact_total", "model_nh")
VERSION = 3
#: The length unit of each unit system (:data:`springfem.scene.types.UNIT_SYSTEMS`).
LENGTH_UNIT = {"SI": "m", "mm-kPa": "mm", "mm-MPa": "mm"}


@dataclass(frozen=True)
class Settings:
    """Meshes of the accuracy study: bundled scene -> box ``divisions`` (``None``: its own
    mesh), the ``figure_scenes`` with an error-field figure (a user's scene always has one),
    the cantilever's ``extra`` meshes (``cantilever-unstructured``: jittered Delaunay tets of
    a grid of these divisions; ``cantilever-elongated``), and whether to solve the ``exact``
    spring element too (and the finite-strain P1 it is exact against)."""

    divisions: dict[str, tuple[int, int, int] | None] = field(
        default_factory=lambda: dict.fromkeys(SCENES)
    )
    figure_scenes: tuple[str, ...] = ("cantilever", "sag")
    extra: dict[str, tuple[int, int, int]] = field(
        default_factory=lambda: {
            "cantilever-unstructured": (40, 4, 4),
            "cantilever-elongated": (20, 4, 4),
        }
    )
    exact: bool = True

    @classmethod
    def full(cls) -> Settings:
        """The bundled scenes' meshes, the unstructured cantilever and 20 x 4 x 4 cells."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """Coarse meshes (``springfem report --quick``)."""
        div = {"cantilever": (20, 2, 2), "stretch-fiber": (3, 3, 3),
               "stretch-cross": (3, 3, 3), "sag": (8, 4, 2)}  # fmt: skip
        extra = {"cantilever-unstructured": (20, 2, 2), "cantilever-elongated": (10, 2, 2)}
        return cls(divisions=div, extra=extra)


def bundled_scenes(settings: Settings) -> list[StudyScene]:
    """The bundled scenes, then the cantilever's extra meshes (roles ``compare``, ``figure``).

    Examples
    --------
    >>> [s.label for s in bundled_scenes(Settings.quick())][-2:]
    ['cantilever-unstructured', 'cantilever-elongated']
    """

    def roles(name: str) -> tuple[str, ...]:
        return ("compare", "figure") if name in settings.figure_scenes else ("compare",)

    return comparison_scenes(settings.divisions, settings.extra, roles)


# -- cases -------------------------------------------------------------------------------


def scene_case(scene: StudyScene, settings: Settings) -> dict[str, Any]:
    """The cache case of one scene (with the plug-in models it weighs too)."""
    return scene.case("accuracy", VERSION, fields=scene.serves("figure"),
                      exact=bool(settings.exact), peers=models.plugins())  # fmt: skip


def work(case: dict[str, Any]) -> dict[str, Any]:
    """Compare spring, P1 and P2 on one scene case, plus the exact element and the case's
    plug-in models that apply to the scene; the JSON-able numbers."""
    scene = case_scene(case)
    cmp = compare_scene(scene, locking_free=False)
    extra = ["spring-exact"] if case.get("exact") else []
    if (case.get("exact") or case.get("peers")) and "P1-NH" not in cmp.solutions:
        if models.P1_NH.applies(scene) is None:
            extra.append("P1-NH")  # the finite-strain P1: the exact element's model error
    extra += [n for n in case.get("peers", ()) if models.get(n).applies(scene) is None]
    for name in extra:
        got = models.run(scene, name)
        if got.ok:
            cmp.solutions[name] = got.solution
        else:
            cmp.failures[name] = got.message
    return summarize(cmp, fields=case["fields"])


def summarize(cmp: Comparison, fields: bool = False) -> dict[str, Any]:
    """JSON-able numbers of a comparison (and the vertex fields if ``fields``)."""
    p1, sol = cmp.same_mesh_p1, cmp.solutions
    errors = {
        "model": cmp.errors("spring", p1) if p1 else {},
        "total": cmp.errors("spring"),
        "discretisation": cmp.errors(p1) if p1 else {},
    }
    if p1 == "P1-NH":  # a finite-strain reference: what a small-strain analysis would give
        errors["small_strain_p2"] = cmp.errors("P2")
    if "spring-exact" in sol:
        errors["exact_model"] = cmp.errors("spring-exact", "P1")
        errors["exact_model_nh"] = cmp.errors("spring-exact", "P1-NH")
        errors["exact_total"] = cmp.errors("spring-exact")
        errors["model_nh"] = cmp.errors("spring", "P1-NH")
    peers = {m.name for m in models.sync_plugins()}  # the plug-in models
    for name in [n for n in sol if n in peers]:
        errors[f"peer_total:{name}"] = cmp.errors(name)
        if "P1-NH" in sol:
            errors[f"peer_model_nh:{name}"] = cmp.errors(name, "P1-NH")
    out: dict[str, Any] = {
        "reference": cmp.reference,
        "p1": p1,
        "strain": cmp.strain,
        "strain_ref": max_principal_strain(cmp.scene, sol[cmp.reference].u),
        "notes": cmp.notes,
        "failures": cmp.failures,
        "nodes": cmp.scene.mesh.n_points,
        "tets": cmp.scene.mesh.n_tets,
        "units": cmp.scene.units,
        "errors": errors,
        "probes": {n: s.result.probes for n, s in sol.items()},
        "volume": {n: s.result.volume["relative_change"] for n, s in sol.items()},
        "wall": {n: s.result.wall_time for n, s in sol.items()},
        "laws": {n: s.result.law for n, s in sol.items()},
    }
    if fields:
        out["u"] = {n: s.u for n, s in sol.items()}
    return out


def nan_float(v: Any) -> float:
    """``v`` as a float, ``None`` as NaN."""
    return float("nan") if v is None else float(v)


# -- tables ------------------------------------------------------------------------------


def error_table(res: dict[str, dict]) -> pd.DataFrame:
    """Model, total and discretisation errors (L2, max) and volume changes per scene, with
    the exact element's and the plug-in models' columns when run."""
    rows = []
    for name, r in res.items():
        row: dict[str, Any] = {
            "scene": name,
            "tets": r["tets"],
            "reference": r["reference"],
            "same-mesh P1": r["p1"],
            "law": r.get("laws", {}).get(r["p1"], ""),
            "max strain (ref)": nan_float(r["strain_ref"]),
        }
        for kind in ERROR_KINDS:
            row[f"{kind} err L2"] = nan_float(r["errors"][kind].get("rel_l2"))
            row[f"{kind} err max"] = nan_float(r["errors"][kind].get("rel_max"))
        for kind in EXACT_KINDS:
            if kind in r["errors"]:
                row[f"{kind.replace('_', ' ')} err L2"] = nan_float(r["errors"][kind].get("rel_l2"))
        for key, e in r["errors"].items():
            kind, _, peer = key.partition(":")
            if kind == "peer_total":
                row[f"{peer} total err L2"] = nan_float(e.get("rel_l2"))
            elif kind == "peer_model_nh":
                row[f"{peer} vs P1-NH err L2"] = nan_float(e.get("rel_l2"))
        row["spring volume change"] = nan_float(r["volume"].get("spring"))
        if "spring-exact" in r["volume"]:
            row["exact volume change"] = nan_float(r["volume"]["spring-exact"])
        row["ref volume change"] = nan_float(r["volume"].get(r["reference"]))
        rows.append(row)
    return pd.DataFrame(rows)


def probe_table(res: dict[str, dict], refs: dict, lateral: dict) -> pd.DataFrame:
    """The main probe component per scene: analytic value (``refs``:
    :func:`studies.analytic.reference`), each model, ratios to the reference, and the
    ``lateral`` (Poisson) component's ratio where a scene names one."""
    rows = []
    for name, r in res.items():
        ref, an = r["reference"], refs[name]
        if not an and not r["probes"][ref]:
            continue  # a user scene without probes
        probe = an[0] if an else next(iter(r["probes"][ref]))
        comp = an[1] if an else int(np.argmax(np.abs(r["probes"][ref][probe])))

        def value(m: str, r=r, probe=probe, comp=comp) -> float:
            return nan_float(r["probes"].get(m, {}).get(probe, [None] * 3)[comp])

        row = {"scene": name, "probe": f"{probe} u{COMPONENTS[comp]}",
               "analytic (m)": an[2] if an else float("nan"),
               "analytic source": an[3] if an else "", "spring (m)": value("spring"),
               "P1 (m)": value(r["p1"]), "reference (m)": value(ref)}  # fmt: skip
        exact = "spring-exact" in r["probes"]
        if exact:
            row["exact (m)"] = value("spring-exact")
        row["spring / ref − 1"] = row["spring (m)"] / row["reference (m)"] - 1
        if exact:
            row["exact / ref − 1"] = row["exact (m)"] / row["reference (m)"] - 1
        row["P1 / ref − 1"] = row["P1 (m)"] / row["reference (m)"] - 1
        for key in r["errors"]:
            kind, _, peer = key.partition(":")
            if kind == "peer_total":
                row[f"{peer} (m)"] = value(peer)
                row[f"{peer} / ref − 1"] = row[f"{peer} (m)"] / row["reference (m)"] - 1
        a = row["analytic (m)"]
        row["ref / analytic − 1"] = row["reference (m)"] / a - 1 if an else float("nan")
        row["spring / analytic − 1"] = row["spring (m)"] / a - 1 if an else float("nan")
        lat = lateral[name]
        row["lateral spring / ref − 1"] = (
            nan_float(r["probes"]["spring"][probe][lat]) / nan_float(r["probes"][ref][probe][lat])
            - 1
            if lat is not None
            else float("nan")
        )
        rows.append(row)
    df = pd.DataFrame(rows)
    units = {res[n].get("units", "SI") for n in res}
    if len(units) == 1 and (unit := LENGTH_UNIT.get(units.pop(), "m")) != "m":
        df.columns = [c.replace("(m)", f"({unit})") for c in df.columns]  # the scene's units
    return df


# -- figures -----------------------------------------------------------------------------


def bar_figure(ctx: StudyContext, errors: pd.DataFrame, probes: pd.DataFrame) -> Figure:
    """Errors per scene (left) and the main probe's signed error (right)."""
    plt = pyplot()
    fig, (a, b) = plt.subplots(1, 2, figsize=(12, 4.8), layout="constrained")
    groups = list(errors["scene"])
    grouped_bars(a, groups, {"model (spring vs P1)": errors["model err L2"],
                             "total (spring vs ref)": errors["total err L2"],
                             "discretisation (P1 vs ref)": errors["discretisation err L2"]},
                 "relative L2 error over vertices", log=False)  # fmt: skip
    a.set_title("displacement error per scene", fontsize=10)
    grouped_bars(b, groups, {"spring / ref − 1": probes["spring / ref − 1"],
                             "P1 / ref − 1": probes["P1 / ref − 1"],
                             "lateral: spring / ref − 1": probes["lateral spring / ref − 1"]},
                 "signed relative difference", log=False)  # fmt: skip
    b.axhline(0.0, color="k", lw=0.8)
    b.set_title("main probe component vs reference (negative = stiffer)", fontsize=10)
    worst = errors.loc[errors["model err L2"].idxmax()]
    return ctx.figure(
        fig,
        "accuracy_errors.png",
        "Left: relative L2 displacement error per scene, split into the spring element's model "
        "error, its total error and P1's discretisation error. Right: signed error of the main "
        "probe component (and the stretch scenes' lateral contraction) against the reference. "
        f"The spring model's largest model error is in {worst['scene']} "
        f"({worst['model err L2']:.1%}).",
    )


def field_figure(ctx: StudyContext, scene: Any, name: str, r: dict) -> Figure:
    """The deformed meshes coloured by the error, captioned with where the spring model's
    error peaks and its three errors."""
    names = dict.fromkeys((*MODELS, r["reference"]))  # the reference may be P2/P1 mixed
    fields = {n: np.asarray(r["u"][n], float) for n in names if n in r["u"]}
    fields, note = figure_fields(fields, r["reference"])
    path = error_figure(scene, fields, r["reference"], ctx.path(f"error_field_{name}.png"),
                        laws=r["laws"], note=note)  # fmt: skip
    model, total, disc = (nan_float(r["errors"][k].get("rel_l2")) for k in ERROR_KINDS)
    ref = np.asarray(r["u"][r["reference"]], float)
    err = metrics.nodal_error(np.asarray(r["u"]["spring"], float), ref)
    lo, hi = scene.mesh.bounding_box()
    at = (scene.mesh.points[int(np.argmax(err))] - lo) / np.where(hi > lo, hi - lo, 1.0)
    return Figure(
        path,
        f"{name}: deformed meshes coloured by the displacement error against "
        f"{r['reference']} (one colour scale). The spring model's error peaks at "
        f"{err.max():.3g} {'m' if scene.units == 'SI' else 'mm'}, at ({at[0]:.2f}, "
        f"{at[1]:.2f}, {at[2]:.2f}) of the box (fractions of its size); its total error is "
        f"{total:.1%} (L2) against {r['p1']}'s discretisation error {disc:.1%}, its model "
        f"error (vs {r['p1']}) {model:.1%}.",
    )


# -- the study ---------------------------------------------------------------------------


@study("accuracy", Settings, bundled_scenes)
def run(ctx: StudyContext, scenes: list[StudyScene], settings: Settings) -> StudyOutput:
    """Spring, P1 and reference solves per scene; the three errors and the probes."""
    names = [s.label for s in scenes]
    results = ctx.cache.run([scene_case(s, settings) for s in scenes], work,
                            progress=ctx.progress, desc="accuracy")  # fmt: skip
    res = dict(zip(names, results, strict=True))
    built = {s.label: s.build() for s in scenes}
    refs = {s.label: analytic.reference(s, built[s.label]) for s in scenes}
    lateral = {s.label: analytic.LATERAL.get(s.analytic or "") for s in scenes}
    errors, probes = error_table(res), probe_table(res, refs, lateral)
    tables = [
        ctx.table(errors, "accuracy_errors",
                  "Relative errors over the mesh vertices per scene: model error = spring vs P1 "
                  "on the same mesh (same law as the reference), total = spring vs the "
                  "reference, discretisation = P1 vs the reference; L2 = ‖u − u_ref‖/‖u_ref‖, "
                  "max = largest nodal error / largest reference displacement."),
        ctx.table(probes, "accuracy_probes",
                  "Main probe displacement component per scene: analytic value (Timoshenko "
                  "beam, uniaxial stress σL/E), spring model, same-mesh P1 and the reference; "
                  "'lateral' is the transverse (Poisson) displacement at the stretch probes "
                  "(u_y for stretch-fiber, u_z for stretch-cross)."),
    ]  # fmt: skip
    figures = [bar_figure(ctx, errors, probes)]
    figures += [field_figure(ctx, built[s.label], s.label, res[s.label]) for s in scenes
                if s.serves("figure") and "u" in res.get(s.label, {})]  # fmt: skip

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
        findings=findings(res, errors.set_index("scene"), probes.set_index("scene"), ctx.quick),
        tables=tables,
        figures=figures,
        headline=headline,
    )


def findings(res: dict, e: pd.DataFrame, p: pd.DataFrame, quick: bool) -> list[str]:
    """The report's sentences (``e``, ``p``: the error and probe tables by scene)."""
    f = []
    lo, hi = e["model err L2"].idxmin(), e["model err L2"].idxmax()
    if len(e) == 1:
        c = e.loc[lo]
        f.append(
            f"On {lo} ({int(c['tets'])} tets, reference {c['reference']}) the spring element's "
            f"model error (spring vs {c['same-mesh P1']} on the same mesh, relative L2 over "
            f"vertices) is {c['model err L2']:.2%}, its total error {c['total err L2']:.1%}, "
            f"the same-mesh P1's discretisation error {c['discretisation err L2']:.1%}."
        )
        return f + exact_findings(e) + peer_findings(e)
    f.append(
        f"The spring element's model error (spring vs P1 on the same mesh, relative L2 over "
        f"vertices) ranges from {e.at[lo, 'model err L2']:.1%} ({lo}) to "
        f"{e.at[hi, 'model err L2']:.1%} ({hi}); its total error against the reference ranges "
        f"from {e['total err L2'].min():.1%} to {e['total err L2'].max():.1%}"
        + (" (quick: coarse meshes)." if quick else ".")
    )
    if "cantilever" in e.index:
        c, pc = e.loc["cantilever"], p.loc["cantilever"]
        ratio = pc["spring (m)"] / pc["P1 (m)"]
        total, disc = c["total err L2"], c["discretisation err L2"]
        f.append(
            f"Bending (cantilever, {int(c['tets'])} tets): the spring tip deflection is "
            f"{abs(ratio - 1):.1%} {'softer' if ratio > 1 else 'stiffer'} than P1 on the same "
            f"mesh and {pc['spring / ref − 1']:+.1%} from P2 (P1: {pc['P1 / ref − 1']:+.1%}, "
            f"P2 vs Timoshenko {pc['ref / analytic − 1']:+.1%}); "
            + (
                "the spring model's extra softness partly cancels P1's bending stiffness on "
                f"this coarse mesh, so its total error ({total:.1%}) is below P1's "
                f"discretisation error ({disc:.1%}) — an accident of the mesh, not accuracy."
                if total < disc
                else f"its total error is {total:.1%} (P1 {disc:.1%})."
            )
        )
    for name, fiber in (("stretch-fiber", "along"), ("stretch-cross", "across")):
        if name in e.index:
            c, pc = e.loc[name], p.loc[name]
            lateral = pc["lateral spring / ref − 1"]
            f.append(
                f"Uniaxial stretch {fiber} the fibers ({name}): P1 and P2 reproduce σL/E "
                f"exactly (P1 error {c['discretisation err L2']:.0e}); the spring model's "
                f"stretch displacement is off by {pc['spring / analytic − 1']:+.1%} and its "
                f"lateral (Poisson) contraction by {lateral:+.0%}, which gives a "
                f"{c['model err L2']:.1%} L2 error"
                + (
                    ": the calibrated springs cannot reproduce the transversely isotropic "
                    "Poisson ratios on this mesh."
                    if abs(lateral) > 0.1
                    else "."
                )
            )
    if "sag" in e.index:
        c, r = e.loc["sag"], res["sag"]
        small = nan_float(r["errors"].get("small_strain_p2", {}).get("rel_l2"))
        text = (
            f"Sag under gravity (neo-Hookean, ν = 0.45, {int(c['tets'])} tets, reference "
            f"strain up to {c['max strain (ref)']:.0%}): spring total error "
            f"{c['total err L2']:.1%} against {r['reference']} ({r['p1']} on the same mesh: "
            f"{c['discretisation err L2']:.1%}, spring model error {c['model err L2']:.1%}); "
            f"the spring model changes the volume by {c['spring volume change']:+.2%} where "
            f"the reference changes it by {c['ref volume change']:+.2%}."
        )
        if np.isfinite(small):
            text += f" A small-strain P2 analysis would be {small:.1%} off" + (
                ", more than the geometrically nonlinear spring model."
                if small > c["total err L2"]
                else ", less than the spring model's own error."
            )
        f.append(text)
    return f + exact_findings(e) + peer_findings(e)


def peer_findings(e: pd.DataFrame) -> list[str]:
    """One sentence per plug-in model: its total error per scene beside the same-mesh P1's
    (and against P1-NH, the finite-strain P1)."""
    out = []
    for name in [m.name for m in models.sync_plugins()]:
        col = f"{name} total err L2"
        if col not in e.columns:
            continue
        parts = []
        for scene, row in e.iterrows():
            if np.isfinite(row[col]):
                nh = row.get(f"{name} vs P1-NH err L2", float("nan"))
                parts.append(
                    f"{scene} {row[col]:.1%} (same-mesh {row['same-mesh P1']} "
                    f"{row['discretisation err L2']:.1%}"
                    + (f", {nh:.2%} off P1-NH" if np.isfinite(nh) else "")
                    + ")"
                )
        if parts:
            out.append(f"{name} (a plug-in model) against each scene's reference, relative "
                       "L2: " + "; ".join(parts) + ".")  # fmt: skip
    return out


def is_exact(e: pd.DataFrame, name: str) -> bool:
    """Whether scene ``name``'s spring element is the exact element: its model errors (vs P1,
    and vs P1-NH where solved) equal the exact element's to 1e-4 of their size, far below
    what two different elements differ by and above the solvers' tolerance."""
    out = False
    for col in ("model err L2", "model nh err L2"):
        if col in e.columns and f"exact {col}" in e.columns:
            a, b = float(e.at[name, col]), float(e.at[name, f"exact {col}"])
            if np.isfinite(a) and np.isfinite(b):
                if abs(a - b) > 1e-4 * max(abs(b), 1e-30):
                    return False
                out = True
    return out


def exact_findings(e: pd.DataFrame) -> list[str]:
    """Where the exact element changes the conclusions (one sentence per scene group)."""
    if "exact model err L2" not in e.columns:
        return []
    f = []
    same = [n for n in e.index if is_exact(e, n)]
    if same:
        errors = "; ".join(f"{n} {e.at[n, 'model err L2']:.2%}" for n in same)
        f.append(
            f"The spring element of {', '.join(same)} is the exact element (the default for a "
            'new scene; [spring] element = "seed" gives the specification\'s): its model '
            f"error against P1 on the same mesh is {errors}."
        )
    rest = [n for n in e.index if n not in same]
    iso = [n for n in rest if np.isfinite(e.at[n, "exact model nh err L2"])]
    if iso:
        parts = "; ".join(
            f"{n} {e.at[n, 'model nh err L2']:.1%} → {e.at[n, 'exact model nh err L2']:.1e}"
            for n in iso
        )
        linear = ", ".join(f"{n} {e.at[n, 'exact model err L2']:.2%}" for n in iso)
        text = (
            "With the exact element (axis-volume + energy torsion + exact calibration) the "
            "model error against the finite-strain P1 (neo-Hookean, same mesh) drops from the "
            f"specification's element's to: {parts}. Against linear P1 the exact element is "
            f"{linear} off: the geometric nonlinearity of the finite-strain spring model, not "
            "model error; the neo-Hookean comparison is the model error proper."
        )
        meshes = [n for n in ("cantilever", "cantilever-unstructured", "cantilever-elongated")
                  if n in e.index]  # fmt: skip
        if len(meshes) >= 2:
            seed = ", ".join(f"{n} {e.at[n, 'model err L2']:.1%}" for n in meshes)
            exact = max(e.at[n, "exact model nh err L2"] for n in meshes)
            text += (
                " The same cantilever on other meshes: the specification's element's error "
                f"depends on the element shapes ({seed}), the exact element's does not (at "
                f"most {exact:.1e} against P1 neo-Hookean on each)."
            )
        f.append(text)
    law = e["law"] if "law" in e.columns else pd.Series("", index=e.index)
    aniso = [n for n in rest if n not in iso]
    linear = [n for n in aniso if law[n] not in TISSUE_LAWS]
    if linear:
        parts = "; ".join(
            f"{n} {e.at[n, 'model err L2']:.1%} → {e.at[n, 'exact model err L2']:.2%}"
            for n in linear
        )
        strain = max(float(e.at[n, "max strain (ref)"]) for n in linear)
        f.append(
            "Transversely isotropic scenes with the exact element plus Poisson-coupling "
            f"springs, model error vs linear P1: {parts} (reference_fem has no "
            "finite-strain form of the transverse-linear law, so the remainder — geometric "
            f"nonlinearity at up to {strain:.1%} strain, the reference's largest principal "
            "strain — cannot be separated here)."
        )
    for n in [n for n in aniso if law[n] in TISSUE_LAWS]:
        f.append(
            f"{n} ({law[n]}): with the exact element plus Poisson-coupling springs the model "
            f"error against P1 of the scene's own {law[n]} law on the same mesh goes from "
            f"{e.at[n, 'model err L2']:.1%} to {e.at[n, 'exact model err L2']:.2%}, at up to "
            f"{float(e.at[n, 'max strain (ref)']):.1%} strain (the reference's largest "
            "principal strain); the tissue element (spring-tissue) is the law itself under "
            "homogeneous deformation (docs/tissue.rst)."
        )
    return f
