"""Findings and headline slopes of the scaling study."""

from __future__ import annotations

import numpy as np
import pandas as pd

from .cases import STATIC_METHODS


def _amg_threshold() -> int:
    from springfem.mechanics import DIRECT_MAX_DOFS as AMG_THRESHOLD

    return int(AMG_THRESHOLD)


def report_findings(
    sdf: pd.DataFrame, tdf: pd.DataFrame, slope: dict[str, float]
) -> tuple[list[str], dict[str, float]]:
    """The findings and the headline slopes (set-up slopes excepted: too noisy)."""
    findings: list[str] = []
    headline: dict[str, float] = {}
    for key, value in slope.items():
        if not key.startswith("setup"):  # set-up times of a few ms are too noisy
            headline[f"slope_{key}"] = round(float(value), 1)
    n_step = sdf["tets"].to_numpy(float)
    decades = np.log10(n_step.max() / n_step.min())
    last = sdf.iloc[-1]
    findings.append(
        f"Per explicit step the cost grows like N^{slope['step_spring']:.2f} (spring model) and "
        f"N^{slope['step_fem']:.2f} (explicit P1 FEM) over {decades:.1f} decades "
        f"({int(n_step.min())}-{int(n_step.max())} tets); at {int(last['tets'])} tets a spring "
        f"step costs {last['spring_ms_per_step']:.1f} ms, an FEM step "
        f"{last['fem_ms_per_step']:.1f} ms ({last['spring_over_fem']:.2f}x, CPU time, serial)."
    )
    big = tdf[tdf["tets"] == tdf["tets"].max()].set_index("method")
    parts = [f"{STATIC_METHODS[m]} {big.loc[m, 'cpu_s']:.1f} s" for m in big.index]
    findings.append(
        f"A static solve scales like N^{slope['static_spring']:.2f} (spring Newton), "
        f"N^{slope['static_P1']:.2f} (FEM P1 linear) and "
        f"N^{slope['static_P1-NH']:.2f} (FEM P1 neo-Hookean Newton); at "
        f"{int(tdf['tets'].max())} tets: {', '.join(parts)}."
    )
    both = tdf.pivot(index="tets", columns="method", values="cpu_s").dropna(subset=["spring", "P1"])
    ratio = both["spring"] / both["P1"]
    worst = int(ratio.idxmax())
    solver_at = tdf[(tdf["method"] == "spring") & (tdf["tets"] == worst)]["linear_solver"].iloc[0]
    findings.append(
        f"The spring model's static Newton solve costs {ratio.min():.1f}-{ratio.max():.1f}x the "
        f"linear FEM P1 solve on the same mesh, most at {worst} tets (linear solver there: "
        f"{solver_at}; the spring solver switches from SuperLU to AMG above "
        f"{_amg_threshold()} free DOFs, the FEM reference uses AMG throughout)."
    )
    setup_steps = last["spring_setup_s"] / last["spring_ms_per_step"] * 1e3
    findings.append(
        f"Set-up (spring: ray casting and calibration; FEM: shape gradients) scales like "
        f"N^{slope['setup_spring']:.2f} and N^{slope['setup_fem']:.2f}; at "
        f"{int(last['tets'])} tets it costs {last['spring_setup_s']:.2f} s vs "
        f"{last['fem_setup_s']:.2f} s, i.e. {setup_steps:.0f} spring steps."
    )
    return findings, headline
