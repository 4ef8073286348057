"""Tables, figure and findings of the ``tissue`` study."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from ..registry import Figure, StudyContext, Table
from ..tables import pyplot

#: Land et al. 2015 problem 1: the published range of the beam's deformed tip z (mm). Rows
#: name their model as :mod:`studies.models` does (``fem``: the P2 reference; ``P1``: the
#: same-mesh P1).
BEAM_RANGE = (4.14, 4.20)


def _rel(value: float, ref: float) -> float:
    return (value - ref) / abs(ref) if ref and math.isfinite(ref) else math.nan


def stretch_frame(cases: list[dict], results: list[dict]) -> pd.DataFrame:
    """One row per (law, direction, stretch, model): stress and its error against the FEM."""
    rows = [{"law": c.get("law", "guccione"), "direction": c["direction"],
             "stretch": c["stretch"], "model": c["model"], "stress": r["stress"],
             "error": r["error"]}
            for c, r in zip(cases, results, strict=True)]  # fmt: skip
    df = pd.DataFrame(rows)
    df["stress"] = pd.to_numeric(df["stress"])
    ref = df[df.model == "fem"].set_index(["law", "direction", "stretch"])["stress"]
    df["rel_error"] = [
        _rel(s, ref[tuple(key)])
        for *key, s in zip(df.law, df.direction, df.stretch, df.stress, strict=True)
    ]
    return df


def beam_frame(cases: list[dict], results: list[dict]) -> pd.DataFrame:
    """One row per model: the beam's deformed tip z, its error against the FEM, time."""
    rows = [{"model": c["model"], "tip_z": r["tip_z"], "wall_time": r["wall_time"],
             "error": r["error"]} for c, r in zip(cases, results, strict=True)]  # fmt: skip
    df = pd.DataFrame(rows)
    df["tip_z"] = pd.to_numeric(df["tip_z"])
    fem = float(df.loc[df.model == "fem", "tip_z"].iloc[0])
    # the deflection is tip_z - 1 (the point starts at z = 1 mm)
    df["rel_error"] = [_rel(z - 1.0, fem - 1.0) for z in df.tip_z]
    p1 = _reference(df, "tip_z")
    df["rel_error_p1"] = [_rel(z - 1.0, p1 - 1.0) for z in df.tip_z]
    return df


def _reference(df: pd.DataFrame, column: str) -> float:
    """The same-mesh P1 FEM's ``column`` (NaN when the P1 row is missing or failed)."""
    rows = df.loc[(df.model == "P1") & (df.error.fillna("") == ""), column]
    return float(rows.iloc[0]) if len(rows) else math.nan


def ventricle_frame(cases: list[dict], results: list[dict]) -> pd.DataFrame:
    """One row per model: apex z, cavity volumes, errors of the apex motion vs the FEM."""
    rows = []
    for c, r in zip(cases, results, strict=True):
        cav = r.get("cavity") or {}
        rows.append({"model": c["model"], "endo_apex_z": r["endo_apex_z"],
                     "epi_apex_z": r["epi_apex_z"], "cavity_initial": cav.get("initial"),
                     "cavity_final": cav.get("final"), "wall_time": r["wall_time"],
                     "load_factor": r.get("load_factor", 1.0), "error": r["error"]})  # fmt: skip
    df = pd.DataFrame(rows)
    for col in ("endo_apex_z", "epi_apex_z", "cavity_initial", "cavity_final", "wall_time",
                "load_factor"):  # fmt: skip
        df[col] = pd.to_numeric(df[col])  # a failed case's NaN comes back from JSON as None
    fem = float(df.loc[df.model == "fem", "endo_apex_z"].iloc[0])
    # the apex motion is its downward displacement -17 - z (negative error: it moves less)
    df["rel_error"] = [_rel(-17.0 - z, -17.0 - fem) for z in df.endo_apex_z]
    p1 = _reference(df, "endo_apex_z")
    df["rel_error_p1"] = [_rel(-17.0 - z, -17.0 - p1) for z in df.endo_apex_z]
    cav = _reference(df, "cavity_final")
    df["cavity_rel_p1"] = [_rel(v, cav) for v in df.cavity_final]
    partial = ~(df.load_factor >= 1.0)  # its values are at another load
    df.loc[partial, ["rel_error", "rel_error_p1", "cavity_rel_p1"]] = float("nan")
    return df


def tables(ctx: StudyContext, sdf, bdf, vdf, settings) -> list[Table]:
    """Write the three tables (CSV + Markdown)."""
    out = []
    for df, stem, caption in (
        (sdf, "stress_stretch", f"Nominal stress (kPa) of the unit cube ({settings.n}^3 boxes "
         "of 6 tets), Guccione (Land's problem 1) and Holzapfel-Ogden (their 2009 fit), "
         "fibre along or across the pull; rel_error against the P1 FEM (exact for this "
         "homogeneous stretch)."),
        (bdf, "beam", f"Land beam {tuple(settings.beam_divisions)}: deformed z of "
         f"(10, 0.5, 1) mm (published {BEAM_RANGE[0]}-{BEAM_RANGE[1]}); rel_error of the "
         "deflection against the FEM (P2 mixed), rel_error_p1 against the same-mesh P1 FEM "
         "(displacement formulation, the spring's penalty)."),
        (vdf, "ventricle", f"{settings.lv_scene} (size {settings.lv_size} mm): apex z "
         "(mm) and cavity volume (mm^3, each model's own field: the P2 FEM's quadratic "
         "facets, the P1 FEM's and the spring model's flat ones); rel_error of the "
         "endocardial apex's downward motion vs the FEM (negative: it moves less), "
         "rel_error_p1 vs the same-mesh P1 FEM, cavity_rel_p1 of the final cavity vs P1's "
         "(none for a partial row: its values are at the load_factor it reached)."),
    ):  # fmt: skip
        out.append(ctx.table(df, stem, caption))
    return out


def pv_figure(ctx: StudyContext, sdf, lv_cases, lv_results, settings) -> Figure:
    """Stress-stretch curves (left) and the ventricle's pressure-volume curve (right)."""
    plt = pyplot()

    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    for ax, law in zip(axes[:2], ("guccione", "holzapfel-ogden"), strict=True):
        for (direction, model), g in sdf[sdf.law == law].groupby(["direction", "model"]):
            style = "-" if model == "fem" else "--"
            ax.plot(g.stretch, g.stress, style, marker="o", ms=3, label=f"{model}, {direction}")
        ax.set_yscale("log")  # Holzapfel-Ogden's fibre stress grows by e^7.6 to 30 %
        ax.set_title(law, fontsize=9)
        ax.set_xlabel("stretch")
        ax.set_ylabel("nominal stress (kPa)")
        ax.legend(fontsize=6)
        ax.grid(True, alpha=0.3)
    b = axes[2]
    p_end = math.nan  # the FEM's full pressure: the spring model's one point is drawn there
    for c, r in zip(lv_cases, lv_results, strict=True):
        rows = (r.get("cavity") or {}).get("pressure_volume")
        if rows:
            pv = np.asarray(rows, dtype=float)
            p_end = pv[-1, 1]
            b.plot(pv[:, 2] / 1000.0, pv[:, 1], "o-", ms=3, label=c["model"])
    for c, r in zip(lv_cases, lv_results, strict=True):
        cav = r.get("cavity") or {}
        if c["model"].startswith("spring") and cav.get("final") and math.isfinite(p_end):
            lf = r.get("load_factor", 1.0)
            b.plot(cav["final"] / 1000.0, p_end * lf, "s", ms=6,
                   label=c["model"] + ("" if lf >= 1 else f" (stopped at {lf:.2f})"))  # fmt: skip
    b.set_xlabel("cavity volume (ml)")
    b.set_ylabel("endocardial pressure (kPa)")
    b.legend(fontsize=7)
    b.grid(True, alpha=0.3)
    return ctx.figure(fig, "tissue.png", "Left and middle: nominal stress against stretch "
                      "along and across the fibre (log scale), Guccione and Holzapfel-Ogden, "
                      "FEM solid, spring variants dashed. Right: the Land ventricle's "
                      "pressure-volume curve over the FEM's load steps (P2 reference and "
                      "same-mesh P1); squares: the spring variants' final cavity, at the load "
                      "factor each reached.")  # fmt: skip


def findings(sdf, bdf, vdf) -> tuple[list[str], dict[str, float]]:
    """Findings (one line each) and the headline numbers."""
    text, head = [], {}
    last = sdf[sdf.stretch == sdf.stretch.max()]
    for _, row in last[last.model != "fem"].iterrows():
        text.append(f"{row.law}, at stretch {row.stretch:g} {row.direction} the fibre, "
                    f"{row.model} is {100 * row.rel_error:+.1f}% off the FEM's nominal stress"
                    + (f" (failed: {row.error})" if row.error else "") + ".")  # fmt: skip
        law = "" if row.law == "guccione" else f"{row.law}_"  # the Guccione keys as before
        head[f"stress_error_{law}{row.direction}_{row.model}"] = float(row.rel_error)
    fem = bdf[bdf.model == "fem"].iloc[0]
    inside = BEAM_RANGE[0] <= fem.tip_z <= BEAM_RANGE[1]
    text.append(f"Land beam: FEM tip z = {fem.tip_z:.4g} mm "
                f"({'inside' if inside else 'outside'} the published {BEAM_RANGE[0]}-"
                f"{BEAM_RANGE[1]} mm on this mesh).")  # fmt: skip
    for _, row in bdf[bdf.model != "fem"].iterrows():
        what = f"failed: {row.error}" if row.error else f"{100 * row.rel_error:+.1f}% deflection"
        if not row.error and row.model != "P1" and math.isfinite(row.rel_error_p1):
            what += f", {100 * row.rel_error_p1:+.1f}% against the same-mesh P1 FEM"
        text.append(f"Land beam, {row.model}: tip z = {row.tip_z:.4g} mm ({what}).")
        head[f"beam_error_{row.model}"] = float(row.rel_error)
    for _, row in vdf.iterrows():
        what = (f"failed: {row.error}" if row.error else
                f"endo apex z = {row.endo_apex_z:.4g} mm, epi {row.epi_apex_z:.4g} mm")  # fmt: skip
        if row.error and row.load_factor == row.load_factor:  # partial (not NaN)
            what = (f"partial, stopped at load factor {row.load_factor:.3g}: endo apex z = "
                    f"{row.endo_apex_z:.4g} mm, epi {row.epi_apex_z:.4g} mm")  # fmt: skip
        spring = row.model not in ("fem", "P1")
        if not row.error and spring and math.isfinite(row.cavity_rel_p1):
            what += (f"; against the same-mesh P1 FEM: apex motion {100 * row.rel_error_p1:+.1f}%,"
                     f" final cavity {100 * row.cavity_rel_p1:+.1f}%")  # fmt: skip
        text.append(f"Land ventricle, {row.model}: {what}.")
        if row.model != "fem":
            head[f"ventricle_error_{row.model}"] = float(row.rel_error)
    return text, head
