"""Findings and headline numbers of the volume-drift study."""

from __future__ import annotations

import re

import numpy as np

from .cases import DYNAMIC, K_MAX, SPEC_VARIANTS, STATIC_SPRINGS
from .tables import MEASURE_WORDS, Runs, compare_words


def slug(label: str) -> str:
    """``"cube compressed"`` -> ``"cube_compressed"`` (headline keys)."""
    return re.sub(r"[^a-z0-9]+", "_", label.lower()).strip("_")


def _at_full_load(runs: Runs, scene: str) -> str:
    """The run kind that ends at full load after a quasi-static approach, if any."""
    kinds = runs.kinds(scene)
    return "ramp" if "ramp" in kinds else "step"


def _scene_findings(runs: Runs, scene: str) -> list[str]:
    """The findings of one scene's runs."""
    key, kind = runs.measure(scene), _at_full_load(runs, scene)
    words = MEASURE_WORDS[key]
    d = {m: abs(runs.final(scene, kind, m, key)) for m in DYNAMIC}
    status = {m: (runs.run(scene, kind, m) or {}).get("status", "not run") for m in DYNAMIC}
    for m, st in status.items():  # a stopped run's last state is no final drift
        if st not in ("ok", "inverted"):
            d[m] = np.nan
    m = runs.material(scene)
    fem = abs(runs.stat(scene, m, key)) if m else np.nan
    how = "slow ramp" if kind == "ramp" else "after the sudden load"
    out = [
        f"{scene}, at full load ({how}): {words} = "
        + ", ".join(
            f"{v:.3g} ({x})" if np.isfinite(v) else f"{x} {status[x]}" for x, v in d.items()
        )
        + f"; the material ({m}, static) changes by {fem:.2g}. Volume springs cut the drift "
        f"{d['spring-volume-off'] / d['spring-volume-on']:.1f}× but leave it "
        f"{d['spring-volume-on'] / fem:.2g}× the material's; the nnls calibration ends at "
        f"{d['spring-volume-nnls']:.3g}, the exact element's axis-volume spring (an energy "
        f"of J = det[ζ]/det[ζ⁰], the true volume ratio) at {d['spring-exact']:.3g} "
        f"({d['spring-volume-on'] / max(d['spring-exact'], 1e-300):.2g}× less than the "
        "specification's volume springs)."
    ]
    k_spec = runs.final(scene, kind, "spring-lms-spec", "k_median")
    k_abs = runs.final(scene, kind, "spring-lms-abs", "k_median")
    out.append(
        f"{scene}, LMS: as written (eq. 2.81) it ends with median k_s/k_s0 = {k_spec:.3g} "
        f"and at {compare_words(d['spring-lms-spec'], d['spring-volume-on'])} of fixed "
        f"volume springs; the sign-consistent rule with {k_abs:.3g} and at "
        f"{compare_words(d['spring-lms-abs'], d['spring-volume-on'])}."
    )
    springs = {x: runs.stat(scene, x, key) for x in STATIC_SPRINGS}
    if m and any(np.isfinite(list(springs.values()))):
        gap = {x: abs(abs(v) - fem) for x, v in springs.items() if np.isfinite(v)}
        best = min(gap, key=gap.get)
        failed = [x for x, v in springs.items() if not np.isfinite(v)]
        out.append(
            f"{scene}, static equilibria: the closest spring variant to the material's "
            f"{words} is {best} (off by {gap[best]:.2g}; "
            + ", ".join(f"{x} {g:.2g}" for x, g in gap.items() if x != best)
            + (f"; not solved: {', '.join(failed)}" if failed else "")
            + ")."
        )
    if key == "element_drift":
        out.append(_sudden_load(runs, scene, fem, m))
    return out


def _sudden_load(runs: Runs, scene: str, fem: float, m: str | None) -> str:
    """The element drift after the sudden load, with the runs that inverted or diverged."""

    def describe(x: str) -> str:
        r = runs.run(scene, "step", x)
        if r is None:
            return f"{x} not run"
        if r["status"] == "diverged":
            return (
                f"{x} diverged (first inverted element at "
                f"{1e3 * r['first_inverted']:.0f} ms, run stopped)"
            )
        if "final" not in r:
            return f"{x} {r['status']}"
        inv = r["final"]["inverted"]
        return f"{x} {r['final']['element_drift']:.3g}" + (f", {inv} inverted" if inv else "")

    return (
        f"{scene}, element drift Σ|ΔV_k|/V0 at the end of the run after the sudden load: "
        + "; ".join(describe(x) for x in DYNAMIC)
        + f"; {m} (static) {fem:.3g}."
    )


def _radial_sums(runs: Runs, scene: str) -> str:
    """Why a stiffer volume spring barely helps: the radial sums against the volume."""
    kind, m = _at_full_load(runs, scene), runs.material(scene)
    return (
        f"Why a stiffer volume spring barely helps: it restores the radial sum Σ|ξ_j|, not "
        f"the volume. On {scene} with volume springs the mean |ΔL|/L0 at full load is "
        f"{runs.final(scene, kind, 'spring-volume-on', 'dL'):.2g} while |ΔV|/V0 is "
        f"{abs(runs.final(scene, kind, 'spring-volume-on')):.2g}; the material ({m}) changes "
        f"Σ|ξ_j| by {runs.stat(scene, m, 'dL'):.2g} at |ΔV|/V0 = {abs(runs.stat(scene, m)):.2g}"
        ". The volume spring fights a quantity the incompressible material does change, and "
        "leaves free the modes that lose volume at constant Σ|ξ_j|."
    )


def report_findings(runs: Runs) -> tuple[list[str], dict[str, float]]:
    """The findings (one paragraph each) and the headline drifts.

    Per scene ``<scene>`` (its label in lowercase with underscores) and model ``<m>``:
    ``<scene>_dV_<m>`` / ``<scene>_ramp_dV_<m>`` (final |dV| of the sudden-load / slow-ramp
    runs, on a scene with a closed-form volume change; 5 decimals), else
    ``<scene>_element_drift_<m>`` / ``<scene>_ramp_element_drift_<m>`` (final element drift
    of the runs that neither diverged nor blew up; 4 decimals); ``<scene>_analytic_dV``;
    ``<scene>_static_<measure>_<FEM>`` (the material's static FEM);
    ``<scene>_diverged_variants`` (variants of the specification's element whose sudden-load
    run diverged).
    """
    findings: list[str] = []
    headline: dict[str, float] = {}
    for sc in runs.scenes:
        scene = sc.label
        if not runs.kinds(scene):
            continue
        findings += _scene_findings(runs, scene)
        key, k = runs.measure(scene), slug(scene)
        digits = 5 if key == "dV" else 4
        for kind in runs.kinds(scene):
            tag = "_ramp" if kind == "ramp" else ""
            for m in DYNAMIC:
                r = runs.run(scene, kind, m)
                if r is None or (key == "element_drift" and r["status"] not in ("ok", "inverted")):
                    continue
                headline[f"{k}{tag}_{key}_{m}"] = round(
                    abs(runs.final(scene, kind, m, key)), digits
                )
        ref = runs.volume.get(scene)
        if ref:
            headline[f"{k}_analytic_dV"] = round(abs(ref[0]), 5)
        m = runs.material(scene)
        if m:
            headline[f"{k}_static_{key}_{m}"] = round(abs(runs.stat(scene, m, key)), digits)
        if "step" in runs.kinds(scene):
            status = [(runs.run(scene, "step", x) or {}).get("status") for x in SPEC_VARIANTS]
            headline[f"{k}_diverged_variants"] = float(status.count("diverged"))
    with_ref = [s.label for s in runs.scenes if runs.volume.get(s.label) and runs.kinds(s.label)]
    if with_ref:
        scene = with_ref[0]
        if runs.material(scene):
            findings.append(_radial_sums(runs, scene))
        ref = runs.volume[scene]
        p1 = [
            f"{abs(runs.stat(s, 'P1')):.2g} ({s})" for s in with_ref if runs.small_strain(s, "P1")
        ]
        nh = [f"{abs(runs.stat(s, 'P1-NH')):.2g}" for s in with_ref]
        if p1:
            findings.append(
                f"Same-mesh P1 with a small-strain law is not a volume reference at finite "
                f"strain: its field has tr ε = {abs(ref[0]):.2g} ({ref[1]}) but the deformed "
                f"mesh changes volume by {', '.join(p1)} (second-order terms of det F); "
                f"P1 neo-Hookean gives {' / '.join(nh)}."
            )
    findings.append(
        "LMS adapts per time step, not per unit time (mu multiplies |ΔV/V0| once per step), "
        f"so its rate depends on dt; and raising k_s up to {K_MAX:g}× forces a "
        f"{np.sqrt(K_MAX):.2g}× smaller explicit step (used here for every variant)."
    )
    return findings, headline
