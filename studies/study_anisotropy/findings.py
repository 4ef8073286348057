"""Findings and headline numbers of the anisotropy study."""

from __future__ import annotations

import numpy as np
import pandas as pd

from springfem.scene import Material


def report_findings(
    df: pd.DataFrame,
    ratios: pd.DataFrame,
    ratio_an: float,
    mat: Material,
    spring_err: dict[str, float],
    worst_angle: dict[str, float],
) -> tuple[list[str], dict[str, float]]:
    """The findings and the headline ratios and errors.

    Parameters
    ----------
    df
        The (model, angle) rows.
    ratios, ratio_an
        The ratio table and the analytic ratio.
    mat
        The material.
    spring_err, worst_angle
        Largest error per model and its angle.

    Returns
    -------
    findings : list of str
    headline : dict
    """
    findings: list[str] = []
    headline: dict[str, float] = {}
    sa, sn = "spring (analytic cal.)", "spring (nnls cal.)"
    r = ratios.set_index("model")
    findings.append(
        f"Anisotropy ratio E(0)/E(90): analytic {ratio_an:.3g}; spring model "
        f"{r.loc[sa, 'E(0)/E(90)']:.3g} (analytic calibration, {r.loc[sa, 'ratio error']:+.1%})"
        f" and {r.loc[sn, 'E(0)/E(90)']:.3g} (nnls, {r.loc[sn, 'ratio error']:+.1%}); FEM P1 "
        f"{r.loc['FEM P1', 'E(0)/E(90)']:.4g}, P2 {r.loc['FEM P2', 'E(0)/E(90)']:.4g}."
    )
    findings.append(
        f"Along the fibers the spring model (analytic calibration) gives "
        f"E(0°) = {r.loc[sa, 'E(0°)']:.4g} Pa ({r.loc[sa, 'E(0°)'] / mat.E_fiber - 1:+.1%} "
        f"of E_f), across E(90°) = {r.loc[sa, 'E(90°)']:.4g} Pa "
        f"({r.loc[sa, 'E(90°)'] / mat.E_cross - 1:+.1%} of E_c); off-axis it is off by up to "
        f"{spring_err[sa]:.1%} (at {worst_angle.get(sa, 0):g}°). The nnls calibration is "
        f"off by up to {spring_err[sn]:.1%}."
    )
    gs = df[df.model == sa]
    gamma_err = float(np.nanmax(np.abs(gs["gamma_xy/eps_xx"] - gs["gamma_xy/eps_xx analytic"])))
    gmax = float(np.nanmax(np.abs(gs["gamma_xy/eps_xx analytic"])))
    g0 = gs.set_index("angle")["gamma_xy/eps_xx"]
    spurious = ", ".join(f"{g0.loc[a]:.2f} at {a:g}°" for a in (0.0, 90.0) if a in g0.index)
    findings.append(
        f"The boundary conditions remove only rigid motion, so the off-axis shear develops "
        f"freely: analytic |γ_xy/ε_xx| reaches {gmax:.2f} and FEM matches it; the spring "
        f"model (analytic calibration) deviates by up to {gamma_err:.2f}, including a "
        f"spurious coupling where the material has none ({spurious}): the six-tet split's "
        "anisotropic radial tensor couples the volume springs to shear."
    )
    headline["ratio_analytic"] = round(ratio_an, 4)
    headline["ratio_spring_analytic_cal"] = round(float(r.loc[sa, "E(0)/E(90)"]), 4)
    headline["ratio_spring_nnls_cal"] = round(float(r.loc[sn, "E(0)/E(90)"]), 4)
    headline["ratio_fem_p1"] = round(float(r.loc["FEM P1", "E(0)/E(90)"]), 4)
    headline["max_rel_error_spring_analytic_cal"] = round(spring_err[sa], 4)
    headline["max_rel_error_spring_nnls_cal"] = round(spring_err[sn], 4)
    headline["max_rel_error_fem_p1"] = round(spring_err["FEM P1"], 6)
    sx = "spring (exact + coupling)"
    if sx in spring_err and sx in r.index:
        headline["ratio_spring_exact_coupling"] = round(float(r.loc[sx, "E(0)/E(90)"]), 4)
        headline["max_rel_error_spring_exact_coupling"] = round(spring_err[sx], 6)
        findings.append(
            f"With the exact element and Poisson-coupling springs the spring model's effective "
            f"modulus follows the off-axis formula to {spring_err[sx]:.2%} at every angle "
            f"(analytic calibration: up to {spring_err[sa]:.1%}, nnls {spring_err[sn]:.1%}); "
            f"E(0)/E(90) = {r.loc[sx, 'E(0)/E(90)']:.4g} against the material's "
            f"{ratio_an:.4g}: the spring model's anisotropy error was its calibration, and "
            "with this element it is gone (the remainder is the finite-strain kinematics at "
            "the applied strain)."
        )
    return findings, headline
