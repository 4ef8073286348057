"""Study ``convergence``: h-refinement of the cantilever for the spring model, P1 and P2.

The bundled cantilever (0.1 × 0.01 × 0.01 m, end shear) is meshed with ``[10, 1, 1] * k``
hexahedra split into six tets each. Errors are measured against a fine P2 solution (level
``k_ref``): the relative tip-deflection error and the relative L2 error at the vertices of
the coarsest mesh (which every finer mesh contains). Rates are slopes of ``log err`` over
``log h`` (:func:`studies.metrics.fitted_rate`), ``h = 0.01 m / k`` the hexahedron edge.

The spring model need not converge to the FEM limit: its calibration cannot match the
material on 6-tet meshes (DESIGN §4). The study tracks ``spring / P1 − 1`` on the same
meshes (does the gap close under refinement?) and extrapolates each model's limit from its
three finest levels (P1's extrapolation, whose true limit is the reference, shows how far the
extrapolation itself can be trusted).

The spring model runs with ``torsion = "energy"`` (the energy-consistent torsion of DESIGN §3,
which has an analytic Hessian) instead of the scene's default ``cosine`` (spec eqs.
2.44–2.45, finite-difference Jacobian, ~4× slower per Newton solve); one extra case at
``Settings.cosine_check_level`` measures the difference between the two.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .. import metrics
from ..registry import StudyContext, StudyOutput, Table, study
from ..tables import write_table
from .cases import MODELS, SIZE, Settings, case, divisions, richardson_limit, work
from .figures import rate_figure, tip_figure
from .findings import report_findings

__all__ = ["Settings", "case", "divisions", "richardson_limit", "run", "work"]


@study("convergence", Settings)
def run(ctx: StudyContext, cfg: Settings) -> StudyOutput:
    """Run the convergence study (see the module docstring).

    Parameters
    ----------
    ctx
        Output folder, cache and preset.
    cfg
        Refinement levels.

    Returns
    -------
    StudyOutput
        Findings, level and rate tables, two figures, headline rates and gaps.
    """
    if cfg.scene is not None:
        from .scene import run_on_scene

        return run_on_scene(ctx, cfg)
    cases = [case(m, k) for m in ("spring", "P1") for k in cfg.levels]
    cases += [case("spring-exact", k) for k in cfg.levels]
    cases += [case("P2", k) for k in cfg.p2_levels]
    ref_case = case("P2", cfg.ref)
    cosine_case = case("spring", cfg.cosine_check_level, torsion="cosine")
    results = ctx.cache.run(
        [*cases, cosine_case, ref_case], work, progress=ctx.progress, desc="convergence"
    )
    ref, cosine = results[-1], results[-2]
    results = results[:-2]
    w_ref = float(ref["tip"][2])
    u_ref = np.asarray(ref["u_coarse"], float)

    rows = []
    for c, r in zip(cases, results, strict=True):
        w = float(r["tip"][2])
        rows.append(
            {
                "model": c["model"],
                "k": c["k"],
                "divisions": "×".join(map(str, divisions(c["k"]))),
                "tets": r["tets"],
                "dofs": r["dofs"],
                "h (m)": r["h"],
                "tip uz (m)": w,
                "w / w_ref": w / w_ref,
                "tip err": abs(w - w_ref) / abs(w_ref),
                "L2 err (coarse vertices)": metrics.relative_l2_error(r["u_coarse"], u_ref),
                "wall time (s)": r["wall"],
            }
        )
    df = pd.DataFrame(rows)
    t_levels = Table(
        write_table(df, ctx.path("convergence_levels")),
        f"Cantilever h-refinement ([10, 1, 1]·k hexahedra, 6 tets each): tip deflection and "
        f"errors against P2 at k = {cfg.ref} ({ref['tets']} tets, tip uz = {w_ref:.6g} m).",
    )

    # -- rates, limits, spring-P1 gap -----------------------------------------------------
    timo = -metrics.timoshenko_tip_deflection(0.1 * SIZE[1] * SIZE[2], *SIZE, 1.0e4, 0.3)
    rates, rrows = {}, []
    for m in MODELS:
        d = df[df["model"] == m].sort_values("h (m)", ascending=False)
        rl2 = metrics.fitted_rate(d["h (m)"], d["L2 err (coarse vertices)"])
        rtip = metrics.fitted_rate(d["h (m)"], d["tip err"])
        L, p = richardson_limit(d["h (m)"].values[-3:], d["w / w_ref"].values[-3:])
        rates[m] = {"l2": rl2, "tip": rtip, "limit": L, "order": p}
        last = d.iloc[-1]
        rrows.append(
            {
                "model": m,
                "levels": len(d),
                "rate (L2)": rl2,
                "rate (tip)": rtip,
                "finest k": int(last["k"]),
                "L2 err at finest": last["L2 err (coarse vertices)"],
                "tip err at finest": last["tip err"],
                "extrapolated w / w_ref": L,
                "extrapolation order": p,
            }
        )
    rdf = pd.DataFrame(rrows)
    t_rates = Table(
        write_table(rdf, ctx.path("convergence_rates")),
        "Fitted rates (slope of log error over log h, all levels) and the tip deflection "
        "extrapolated from each model's three finest levels (w = L + C h^p); P1's true limit "
        "is 1, so its extrapolated value shows the extrapolation's own bias.",
    )
    sp = df[df["model"] == "spring"].set_index("k")
    p1 = df[df["model"] == "P1"].set_index("k")
    gap = (sp["tip uz (m)"] / p1["tip uz (m)"] - 1.0).sort_index()
    gap_rate = metrics.fitted_rate(sp.loc[gap.index, "h (m)"], gap.abs())
    w_cos = float(cosine["tip"][2])
    w_en = float(sp.at[cfg.cosine_check_level, "tip uz (m)"])
    h_gap = sp.loc[gap.index, "h (m)"].values
    gap_limit, gap_order = richardson_limit(h_gap[-3:], gap.values[-3:])
    extra = {
        "gap": gap,
        "gap_rate": gap_rate,
        "gap_limit": gap_limit,
        "gap_order": gap_order,
        "cosine_vs_energy": w_cos / w_en - 1.0,
    }

    figures = [
        rate_figure(ctx, df, rates, cfg),
        tip_figure(ctx, df, rates, w_ref, timo, cfg, extra),
    ]
    findings = report_findings(df, rates, w_ref, timo, cfg, ref, ctx.quick, extra)
    ex, p1r = rates["spring-exact"], rates["P1"]
    fin0 = rdf.set_index("model")
    findings.append(
        f"The exact spring element (axis-volume + energy torsion + exact calibration) "
        f"converges like P1: L2 rate {ex['l2']:.2f} (P1 {p1r['l2']:.2f}), tip error at the "
        f"finest level {fin0.at['spring-exact', 'tip err at finest']:.1%} (P1 "
        f"{fin0.at['P1', 'tip err at finest']:.1%}, seed spring model "
        f"{fin0.at['spring', 'tip err at finest']:.1%}): the spring–P1 gap of the seed model "
        "is its calibration, and with the exact element it is gone on every level."
    )
    fin = rdf.set_index("model")
    headline = {
        "rate_l2_spring": rates["spring"]["l2"],
        "rate_l2_p1": rates["P1"]["l2"],
        "rate_l2_p2": rates["P2"]["l2"],
        "rate_tip_p1": rates["P1"]["tip"],
        "rate_tip_p2": rates["P2"]["tip"],
        "tip_err_finest_spring": float(fin.at["spring", "tip err at finest"]),
        "tip_err_finest_p1": float(fin.at["P1", "tip err at finest"]),
        "spring_over_p1_finest": float(gap.iloc[-1] + 1.0),
        "rate_spring_p1_gap": gap_rate,
        "ref_over_timoshenko": w_ref / timo,
        "rate_l2_spring_exact": rates["spring-exact"]["l2"],
        "tip_err_finest_spring_exact": float(fin.at["spring-exact", "tip err at finest"]),
    }
    return StudyOutput(
        name=ctx.name,
        title="Convergence under h-refinement (cantilever): spring model, P1, P2",
        findings=findings,
        tables=[t_levels, t_rates],
        figures=figures,
        headline=headline,
    )
