"""Tables of the anisotropy study: moduli per model and angle, the anisotropy ratio."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from springfem.scene import Material

from ..registry import StudyContext, Table
from ..tables import write_table
from .cases import MODELS, off_axis_modulus, off_axis_strain


def modulus_frame(
    cases: list[tuple[str, dict]], results: list[dict[str, Any]], mat: Material, sigma: float
) -> pd.DataFrame:
    """One row per (model, angle): E_eff, the off-axis value, error, shear coupling.

    Parameters
    ----------
    cases
        ``(model label, case)`` pairs.
    results
        Their :func:`~.cases.modulus_case` results.
    mat
        The material.
    sigma
        The applied stress (Pa).

    Returns
    -------
    DataFrame
    """
    rows = []
    for (label, c), r in zip(cases, results):
        a = c["angle"]
        E_an = off_axis_modulus(mat, a)
        eps_an = off_axis_strain(mat, a, sigma)
        g_an = 2.0 * eps_an[0, 1] / eps_an[0, 0]
        rows.append(
            {
                "model": label,
                "angle": a,
                "E_eff": r["E_eff"],
                "E_analytic": E_an,
                "rel_error": r["E_eff"] / E_an - 1.0,
                "gamma_xy/eps_xx": r.get("gamma_xy", np.nan) / r.get("eps_xx", np.nan),
                "gamma_xy/eps_xx analytic": g_an,
                "status": r["status"],
            }
        )
    df = pd.DataFrame(rows)
    return df


def modulus_table(ctx: StudyContext, df: pd.DataFrame, mat: Material, sigma: float, n: int):
    """Write the wide table of E_eff per model and angle.

    Parameters
    ----------
    ctx
        Where to write.
    df
        :func:`modulus_frame`.
    mat, sigma, n
        Material, applied stress and divisions (for the caption).

    Returns
    -------
    Table
    """
    wide = df.pivot(index="angle", columns="model", values="E_eff")[list(MODELS)]
    wide.insert(0, "analytic", [off_axis_modulus(mat, a) for a in wide.index])
    for label in MODELS:
        if label.startswith("spring"):
            wide[f"{label} error"] = wide[label] / wide["analytic"] - 1.0
    wide = wide.reset_index().rename(columns={"angle": "θ (deg)"})
    return Table(
        write_table(wide, ctx.path("modulus")),
        f"Effective modulus E_eff = σ/ε_xx (Pa) against fiber angle θ on the {n}³×6-tet "
        f"cube (σ = {sigma:g} Pa): off-axis formula, spring model (analytic and nnls "
        "calibration), FEM P1 and P2, and the spring model's relative error.",
    )


def ratio_frame(df: pd.DataFrame, mat: Material) -> tuple[pd.DataFrame, float]:
    """E(0°), E(90°) and their ratio per model, with the analytic row first.

    Parameters
    ----------
    df
        :func:`modulus_frame`.
    mat
        The material.

    Returns
    -------
    ratios : DataFrame
    ratio_an : float
        The analytic ``E_f / E_c``.
    """

    def E_at(label: str, a: float) -> float:
        g = df[(df.model == label) & (df.angle == a)]
        return float(g.E_eff.iloc[0]) if len(g) else float("nan")

    ratio_an = off_axis_modulus(mat, 0.0) / off_axis_modulus(mat, 90.0)
    rrows = [
        {
            "model": "analytic",
            "E(0°)": mat.E_fiber,
            "E(90°)": mat.E_cross,
            "E(0)/E(90)": ratio_an,
            "ratio error": 0.0,
        }
    ]
    for label in MODELS:
        e0, e90 = E_at(label, 0.0), E_at(label, 90.0)
        rrows.append(
            {
                "model": label,
                "E(0°)": e0,
                "E(90°)": e90,
                "E(0)/E(90)": e0 / e90,
                "ratio error": (e0 / e90) / ratio_an - 1.0,
            }
        )
    ratios = pd.DataFrame(rrows)
    return ratios, ratio_an


def ratio_table(ctx: StudyContext, ratios: pd.DataFrame) -> Table:
    """Write the anisotropy-ratio table.

    Parameters
    ----------
    ctx
        Where to write.
    ratios
        :func:`ratio_frame`.

    Returns
    -------
    Table
    """
    return Table(
        write_table(ratios, ctx.path("anisotropy_ratio")),
        "Stiffness along (0°) and across (90°) the fibers and the anisotropy ratio "
        "E(0)/E(90) of each model against the analytic E_f/E_c.",
    )


def worst_errors(df: pd.DataFrame) -> tuple[dict[str, float], dict[str, float]]:
    """Largest |relative error| of E_eff per model and the angle where it occurs.

    Parameters
    ----------
    df
        :func:`modulus_frame`.

    Returns
    -------
    spring_err, worst_angle : dict
    """
    spring_err = {
        label: float(np.nanmax(np.abs(df[df.model == label].rel_error))) for label in MODELS
    }
    worst_angle = {
        label: float(df[df.model == label].set_index("angle").rel_error.abs().idxmax())
        for label in MODELS
        if df[df.model == label].rel_error.notna().any()
    }
    return spring_err, worst_angle
