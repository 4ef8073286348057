"""Findings of the accuracy study: the sentences of the report."""

from __future__ import annotations

import numpy as np
import pandas as pd

from .cases import nan_float


def report_findings(
    res: dict, errors: pd.DataFrame, probes: pd.DataFrame, quick: bool
) -> list[str]:
    """The report's sentences on the accuracy study, one finding each (``res``: scene name ->
    :func:`~.cases.work` result; ``quick``: said in the first sentence).
    """
    f = []
    e = errors.set_index("scene")
    p = probes.set_index("scene")
    lo, hi = e["model err L2"].idxmin(), e["model err L2"].idxmax()
    if len(e) == 1:
        f.append(
            f"On {lo} ({int(e.at[lo, 'tets'])} tets, reference {e.at[lo, 'reference']}) the "
            f"spring element's model error (spring vs {e.at[lo, 'same-mesh P1']} on the same "
            f"mesh, relative L2 over vertices) is {e.at[lo, 'model err L2']:.2%}, its total "
            f"error {e.at[lo, 'total err L2']:.1%}, the same-mesh P1's discretisation error "
            f"{e.at[lo, 'discretisation err L2']:.1%}."
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
        soft = "softer" if pc["spring (m)"] / pc["P1 (m)"] > 1 else "stiffer"
        f.append(
            f"Bending (cantilever, {int(c['tets'])} tets): the spring tip deflection is "
            f"{abs(pc['spring (m)'] / pc['P1 (m)'] - 1):.1%} {soft} than P1 on the same mesh and "
            f"{pc['spring / ref − 1']:+.1%} from P2 (P1: {pc['P1 / ref − 1']:+.1%}, P2 vs "
            f"Timoshenko {pc['ref / analytic − 1']:+.1%}); "
            + (
                "the spring model's extra softness partly cancels P1's bending stiffness on "
                f"this coarse mesh, so its total error ({c['total err L2']:.1%}) is below P1's "
                f"discretisation error ({c['discretisation err L2']:.1%}) — an accident of "
                "the mesh, not accuracy."
                if c["total err L2"] < c["discretisation err L2"]
                else f"its total error is {c['total err L2']:.1%} (P1 "
                f"{c['discretisation err L2']:.1%})."
            )
        )
    for name, fiber in (("stretch-fiber", "along"), ("stretch-cross", "across")):
        if name not in e.index:
            continue
        c, pc = e.loc[name], p.loc[name]
        lateral = pc["lateral spring / ref − 1"]
        f.append(
            f"Uniaxial stretch {fiber} the fibers ({name}): P1 and P2 reproduce σL/E exactly "
            f"(P1 error {c['discretisation err L2']:.0e}); the spring model's stretch "
            f"displacement is off by {pc['spring / analytic − 1']:+.1%} and its lateral "
            f"(Poisson) contraction by {lateral:+.0%}, which gives a {c['model err L2']:.1%} "
            "L2 error"
            + (
                ": the calibrated springs cannot reproduce the transversely isotropic Poisson "
                "ratios on this mesh."
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
    f += exact_findings(e)
    return f + peer_findings(e)


def peer_findings(e: pd.DataFrame) -> list[str]:
    """One sentence per plug-in model (``<name> total err L2`` columns): its total error
    per scene beside the same-mesh P1's (and against P1-NH, the finite-strain P1)."""
    from .. import models

    out = []
    for name in [m.name for m in models.sync_plugins()]:
        col = f"{name} total err L2"
        if col not in e.columns:
            continue
        parts = []
        for scene, row in e.iterrows():
            if not np.isfinite(row[col]):
                continue
            nh = row.get(f"{name} vs P1-NH err L2", float("nan"))
            vs_nh = f", {nh:.2%} off P1-NH" if np.isfinite(nh) else ""
            parts.append(f"{scene} {row[col]:.1%} (P1 {row['discretisation err L2']:.1%}{vs_nh})")
        if parts:
            out.append(
                f"{name} (a plug-in model) against each scene's reference, relative L2: "
                + "; ".join(parts)
                + "."
            )
    return out


def shape_sentence(e: pd.DataFrame) -> str:
    """How the specification's and the exact element's errors depend on the element shapes."""
    meshes = [n for n in ("cantilever", "cantilever-unstructured", "cantilever-elongated")
              if n in e.index]  # fmt: skip
    if len(meshes) < 2:
        return ""
    seed = ", ".join(f"{n} {e.at[n, 'model err L2']:.1%}" for n in meshes)
    exact = max(e.at[n, "exact model nh err L2"] for n in meshes)
    return (
        f" The same cantilever on other meshes: the specification's element's error depends on "
        "the element "
        f"shapes ({seed}), the exact element's does not (at most {exact:.1e} against P1 "
        "neo-Hookean on each)."
    )


def is_exact(e: pd.DataFrame, name: str) -> bool:
    """Whether the spring element of scene ``name`` is the exact element: its model error
    equals the exact element's (to round-off)."""
    a, b = float(e.at[name, "model err L2"]), float(e.at[name, "exact model err L2"])
    return bool(np.isfinite(a) and np.isfinite(b) and abs(a - b) <= 1e-9 * max(abs(b), 1e-30))


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
    aniso = [n for n in rest if n not in iso]
    if iso:
        parts = "; ".join(
            f"{n} {e.at[n, 'model nh err L2']:.1%} → {e.at[n, 'exact model nh err L2']:.1e}"
            for n in iso
        )
        linear = ", ".join(f"{n} {e.at[n, 'exact model err L2']:.2%}" for n in iso)
        f.append(
            "With the exact element (axis-volume + energy torsion + exact calibration) the "
            "model error against the finite-strain P1 (neo-Hookean, same mesh) drops from the "
            f"specification's element's to: {parts}. Against linear P1 the exact element is "
            f"{linear} off: "
            "the geometric nonlinearity of the finite-strain spring model, not model error; "
            "the neo-Hookean comparison is the model error proper." + shape_sentence(e)
        )
    if aniso:
        parts = "; ".join(
            f"{n} {e.at[n, 'model err L2']:.1%} → {e.at[n, 'exact model err L2']:.2%}"
            for n in aniso
        )
        f.append(
            "Transversely isotropic stretches with the exact element plus Poisson-coupling "
            f"springs, model error vs linear P1: {parts} (reference_fem has no anisotropic "
            "finite-strain law, so the remainder — geometric nonlinearity at 1% strain — "
            "cannot be separated here)."
        )
    return f
