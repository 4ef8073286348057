"""Tables of the anisotropy study: the fibre / cross-fibre error split of every scene, and
on the scenes with the off-axis closed form the moduli per model and angle and the
anisotropy ratio."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from springfem.errors import SolverError

from ..analytic import fibre_angle, off_axis_strain, reference
from ..registry import StudyContext, Table
from ..scenes import StudyScene
from .cases import MODELS, REFERENCES, split_errors, stretch_measures

SPLIT_COLUMNS = {
    "fibre": "fibre err (displ.)",
    "cross": "cross err (displ.)",
    "total": "L2 err",
    "strain_fibre": "fibre strain err",
    "strain_cross": "cross strain err",
}


def frames(
    scenes: list[StudyScene], cases: list[dict[str, Any]], results: list[dict[str, Any]]
) -> tuple[pd.DataFrame, pd.DataFrame, dict[str, list[str]]]:
    """The error-split rows of every scene and the modulus rows of the scenes with the
    off-axis closed form.

    Returns ``split`` (one row per (scene, model, reference): :data:`SPLIT_COLUMNS`),
    ``modulus`` (one row per (scene, model) with a closed form: angle, ``E_eff``,
    ``E_analytic``, ``rel_error``, shear coupling and its closed form, status) and ``failed``
    (scene -> the models that did not solve); raises :class:`SolverError` if a reference (P2
    or P1) did not solve.
    """
    split, modulus, failed = [], [], {}
    for s in scenes:
        scene = s.build()
        res = {c["model"]: r for c, r in zip(cases, results, strict=True) if c["scene"] == s.label}
        for ref in REFERENCES:
            if res[ref]["status"] != "ok":
                raise SolverError(f"{s.label}: the reference {ref} failed: {res[ref]['message']}")
        failed[s.label] = [m for m in MODELS if res[m]["status"] != "ok"]
        u = {m: np.asarray(r["u"], float) for m, r in res.items() if r["status"] == "ok"}
        for m in u:
            for against in REFERENCES:
                if m == against or (m == "P2" and against == "P1"):
                    continue
                err = split_errors(scene, u[m], u[against])
                split.append(
                    {
                        "scene": s.label,
                        "model": m,
                        "against": against,
                        **{SPLIT_COLUMNS[k]: v for k, v in err.items()},
                    }
                )
        closed = reference(s, scene)
        if closed is None:
            continue
        _, component, value, _ = closed
        extent = np.ptp(scene.mesh.points[:, component])
        sigma = float(scene.loads[0].value[component])
        E_an = sigma * extent / value
        angle = round(fibre_angle(scene), 9)
        eps_an = off_axis_strain(scene.material, angle, sigma)
        for m in MODELS:
            r = stretch_measures(scene, u[m]) if m in u else {}
            modulus.append(
                {
                    "scene": s.label,
                    "model": m,
                    "angle": angle,
                    "E_eff": r.get("E_eff", np.nan),
                    "E_analytic": E_an,
                    "rel_error": r.get("E_eff", np.nan) / E_an - 1.0,
                    "gamma_xy/eps_xx": r.get("gamma_xy", np.nan) / r.get("eps_xx", np.nan),
                    "gamma_xy/eps_xx analytic": 2.0 * eps_an[0, 1] / eps_an[0, 0],
                    "status": res[m]["status"],
                }
            )
    return pd.DataFrame(split), pd.DataFrame(modulus), failed


def split_table(ctx: StudyContext, split: pd.DataFrame) -> Table:
    """Write the error-split table."""
    return ctx.table(
        split,
        "fibre_split",
        "Each model's displacement error against P2 and against same-mesh P1, split into "
        "the fibre direction and across it (relative to ‖u_ref‖; the two add in quadrature "
        "to the L2 error), and the L2 errors of the fibre strain f·εf and of the mean "
        "cross-fibre normal strain per tet, relative to the reference's strain.",
    )


def modulus_table(ctx: StudyContext, df: pd.DataFrame, sigma: float, n_tets: int) -> Table:
    """Write the wide table of E_eff per model and angle."""
    wide = df.pivot(index="angle", columns="model", values="E_eff")[list(MODELS)]
    wide.insert(0, "analytic", df.groupby("angle")["E_analytic"].first())
    for m in MODELS:
        if m.startswith("spring"):
            wide[f"{m} error"] = wide[m] / wide["analytic"] - 1.0
    wide = wide.reset_index().rename(columns={"angle": "θ (deg)"})
    return ctx.table(
        wide,
        "modulus",
        f"Effective modulus E_eff = σ/ε_xx (Pa) against fibre angle θ on the {n_tets}-tet "
        f"block (σ = {sigma:g} Pa): off-axis formula, spring model (analytic and nnls "
        "calibration, exact element with coupling), FEM P1 and P2, and the spring models' "
        "relative error.",
    )


def ratio_frame(df: pd.DataFrame) -> tuple[pd.DataFrame, float]:
    """E(0°), E(90°) and their ratio per model, with the analytic row first, and the analytic
    ``E_f / E_c`` (``nan`` without both angles).
    """

    def at(m: str | None, a: float) -> float:
        g = df[(df.model == (m or MODELS[0])) & (df.angle == a)]
        return float(g["E_analytic" if m is None else "E_eff"].iloc[0]) if len(g) else np.nan

    ratio_an = at(None, 0.0) / at(None, 90.0)
    rows = [
        {
            "model": "analytic",
            "E(0°)": at(None, 0.0),
            "E(90°)": at(None, 90.0),
            "E(0)/E(90)": ratio_an,
            "ratio error": 0.0,
        }
    ]
    for m in MODELS:
        e0, e90 = at(m, 0.0), at(m, 90.0)
        rows.append(
            {
                "model": m,
                "E(0°)": e0,
                "E(90°)": e90,
                "E(0)/E(90)": e0 / e90,
                "ratio error": (e0 / e90) / ratio_an - 1.0,
            }
        )
    return pd.DataFrame(rows), ratio_an


def ratio_table(ctx: StudyContext, ratios: pd.DataFrame) -> Table:
    """Write the anisotropy-ratio table."""
    return ctx.table(
        ratios,
        "anisotropy_ratio",
        "Stiffness along (0°) and across (90°) the fibres and the anisotropy ratio "
        "E(0)/E(90) of each model against the analytic E_f/E_c.",
    )


def worst_errors(df: pd.DataFrame) -> tuple[dict[str, float], dict[str, float]]:
    """Largest |relative error| of E_eff per model and the angle where it occurs."""
    worst = {m: float(np.nanmax(np.abs(df[df.model == m].rel_error))) for m in MODELS}
    worst_angle = {
        m: float(df[df.model == m].set_index("angle").rel_error.abs().idxmax())
        for m in MODELS
        if df[df.model == m].rel_error.notna().any()
    }
    return worst, worst_angle
