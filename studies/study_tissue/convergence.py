"""Mesh convergence of the Land ventricles' apex (P2/P1 mixed FEM) and beam, extrapolated.

Land et al. 2015 measure the deformed z of the endocardial and epicardial apex, the points
``(0, 0, -17)`` and ``(0, 0, -20)`` mm at rest (the lowest points of the undeformed surfaces
on the axis; the gmsh ellipsoid has a mesh vertex at each). Each scene is solved on a
sequence of meshes; the effective element size ``h`` is the edge of the regular tet of the
mesh's mean volume, ``h = (6 sqrt(2) V_wall / n_tets)^(1/3)`` (gmsh's size parameter is only
the upper bound it meshes to). From the three finest meshes the observed order ``p`` and the
extrapolated value ``f0`` solve ``f_i = f0 + C h_i^p`` (Richardson). The order is called
asymptotic when the three coarser meshes (a fourth size is needed) give the same order
within 25 % and ``0.5 <= p <= 6``; otherwise the extrapolation is reported but flagged.
``fit_order_2`` is a second estimate: the least-squares ``f0`` of ``f = f0 + C h^2`` over all
the meshes (the order of the flat-faceted boundary's geometry error); the distance between
the two shows how far the meshes are from the asymptotic range.

Published values: problem 2's consensus in Land et al. 2015 is given in figures only; the
FEniCS-pulse reimplementation prints -26.5328 / -28.1790 mm (endo / epi apex z; github.com/
finsberg/pulse pull request 98, 2024), and Land et al. report typical differences of about
0.5 % between the groups' fine solutions: the band drawn. Problem 3 adds an active tension
springfem does not model; the passive inflation here has no published value.

Land's problem-1 beam is refined the same way (:func:`beam_level_scenes`): three
structured meshes of the 10 x 1 x 1 mm beam (``n x n/10 x n/10`` divisions, so the element
length ``h = 10 / n`` mm is exact), the finest the study's own beam mesh (its FEM case is
shared with the beam measurement), extrapolated beside the 11 codes' published
4.14-4.20 mm.

Examples
--------
>>> cases = [{"divisions": [n, n // 10, n // 10]} for n in (10, 20, 40)]
>>> results = [{"tip_z": 4.17 - 0.1 / n**2, "wall_time": 1.0, "error": ""} for n in (10, 20, 40)]
>>> df = beam_levels_frame(cases, results)
>>> round(float(df.tip_z.iloc[-1]), 6), df.mesh.iloc[-1]
(4.17, 'Richardson (p = 2)')
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from springfem.ellipsoid import wall_volume

from ..metrics import observed_order
from ..scenes import StudyScene
from ..tables import pyplot

#: Published apex z (mm) per bundled scene: FEniCS-pulse's problem 2 (pulse PR 98).
PUBLISHED = {"land-ventricle": {"endo": -26.5328, "epi": -28.1790}}
#: Land et al. 2015: typical relative difference between the groups' fine solutions.
BAND = 0.005
#: The published range of the deformed z of (10, 0.5, 1) mm over Land et al.'s 11 codes.
PUBLISHED_RANGE = (4.14, 4.20)
#: Problem numbers of the bundled scenes.
PROBLEM = {"land-ventricle": "2", "land-ventricle-fibres": "3 (passive)"}


def convergence_frame(cases: list[dict], results: list[dict]) -> pd.DataFrame:
    """One row per (scene, size): apex z of endo and epi, h, tets, DOFs and wall time."""
    v = 6.0 * math.sqrt(2.0) * wall_volume()
    rows = []
    for c, r in zip(cases, results, strict=True):
        tets = r.get("tets") or math.nan
        rows.append({"problem": PROBLEM.get(c["scene"], c["scene"]), "scene": c["scene"],
                     "size": c["size"], "h": (v / tets) ** (1 / 3), "tets": tets,
                     "dofs": r.get("dofs") or math.nan, "endo_apex_z": r["endo_apex_z"],
                     "epi_apex_z": r["epi_apex_z"], "wall_time": r["wall_time"],
                     "error": r["error"]})  # fmt: skip
    df = pd.DataFrame(rows)
    for col in ("h", "tets", "dofs", "endo_apex_z", "epi_apex_z", "wall_time"):
        df[col] = pd.to_numeric(df[col])
    for col in ("tets", "dofs"):  # counts print as integers (a failed case's as <NA>)
        df[col] = df[col].round().astype("Int64")
    return df


def richardson_frame(df: pd.DataFrame) -> pd.DataFrame:
    """Per (scene, surface): finest value, observed order, extrapolations, published value."""
    rows = []
    for scene, g in df.groupby("scene", sort=False):
        g = g[np.isfinite(g.endo_apex_z)].sort_values("h", ascending=False)
        for surface in ("endo", "epi"):
            f, h = g[f"{surface}_apex_z"].to_numpy(), g.h.to_numpy()
            p, f0, note = observed_order(h[-3:], f[-3:]) if len(g) >= 3 else (
                math.nan, math.nan, "fewer than 3 meshes")  # fmt: skip
            p_prev = observed_order(h[-4:-1], f[-4:-1])[0] if len(g) >= 4 else math.nan
            fit2 = np.polyfit(h**2, f, 1)[1] if len(g) >= 2 else math.nan
            pub = PUBLISHED.get(scene, {}).get(surface, math.nan)
            rows.append({"problem": PROBLEM.get(scene, scene), "surface": surface,
                         "finest_h": h[-1] if len(h) else math.nan,
                         "finest": f[-1] if len(f) else math.nan, "order": p,
                         "order_coarser": p_prev, "extrapolated": f0, "fit_order_2": fit2,
                         "asymptotic": _asymptotic(p, p_prev, note), "published": pub,
                         "extrapolated_minus_published": f0 - pub})  # fmt: skip
    return pd.DataFrame(rows)


def _asymptotic(p: float, p_prev: float, note: str) -> str:
    if not math.isfinite(p):
        return f"no ({note})"
    if not 0.5 <= p <= 6:
        return f"no (p = {p:.2g} outside 0.5-6)"
    if not math.isfinite(p_prev):
        return "unchecked (needs a 4th size)"
    if abs(p - p_prev) <= 0.25 * p:
        return "yes"
    return f"no (coarser triple: p = {p_prev:.2g})"


def convergence_figure(ctx, df: pd.DataFrame, rich: pd.DataFrame):
    """Apex z against h per problem, the Richardson value at h = 0 and the published band."""
    plt = pyplot()
    scenes = list(dict.fromkeys(df.scene))
    fig, axes = plt.subplots(1, len(scenes), figsize=(5.2 * len(scenes), 4.0), squeeze=False,
                             layout="constrained")  # fmt: skip
    for ax, scene in zip(axes[0], scenes, strict=True):
        g = df[df.scene == scene].sort_values("h")
        for surface, colour in (("endo", "C0"), ("epi", "C3")):
            ok = g[np.isfinite(g[f"{surface}_apex_z"])]
            ax.plot(ok.h, ok[f"{surface}_apex_z"], "o-", color=colour, ms=4, label=surface)
            if len(ok) >= 2:
                c, f0 = np.polyfit(ok.h**2, ok[f"{surface}_apex_z"], 1)
                hh = np.linspace(0.0, ok.h.max(), 50)
                ax.plot(hh, f0 + c * hh**2, "--", color=colour, lw=0.8, alpha=0.7,
                        label=f"{surface}: f0 + C h^2 fit")  # fmt: skip
            r = rich[(rich.problem == PROBLEM.get(scene, scene)) & (rich.surface == surface)]
            if len(r) and math.isfinite(r.extrapolated.iloc[0]):
                sure = r.asymptotic.iloc[0] == "yes"
                ax.plot([0.0], [r.extrapolated.iloc[0]], "*", color=colour, ms=11,
                        mfc=colour if sure else "none", label=f"{surface} Richardson"
                        + ("" if sure else " (order not shown asymptotic)"))  # fmt: skip
            pub = PUBLISHED.get(scene, {}).get(surface)
            if pub is not None:
                ax.axhspan(pub * (1 + BAND), pub * (1 - BAND), color=colour, alpha=0.12)
                ax.axhline(pub, color=colour, ls=":", lw=1,
                           label=f"{surface} published {pub:.2f}")  # fmt: skip
        ax.set_xlim(left=-0.1)
        ax.set_xlabel("h: regular-tet edge of the mean tet volume (mm)")
        ax.set_ylabel("deformed apex z (mm)")
        ax.set_title(f"Land problem {PROBLEM.get(scene, scene)} (P2/P1 mixed)", fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=6, loc="center", framealpha=0.9)
    return ctx.figure(fig, "apex_convergence.png", "Deformed apex z of the endocardium (blue) "
                      "and epicardium (red) against the element size; stars at h = 0: "
                      "Richardson extrapolation from the three finest meshes (hollow: the order "
                      "is not shown to be in the asymptotic range); dashed: the least-squares "
                      "f0 + C h^2 fit; dotted lines and shaded bands: the published problem-2 "
                      "values (FEniCS-pulse) +/- 0.5 % (Land et al. 2015's typical spread "
                      "between codes). Problem 3 is the passive inflation (no published "
                      "value).")  # fmt: skip


def convergence_findings(rich: pd.DataFrame) -> list[str]:
    """One sentence per problem: the extrapolated apex z against the published one."""
    text = []
    for problem, g in rich.groupby("problem", sort=False):
        e, p = g.set_index("surface").loc["endo"], g.set_index("surface").loc["epi"]
        if not math.isfinite(e.extrapolated):
            text.append(f"Land problem {problem}: finest mesh (h = {e.finest_h:.2f} mm) apex "
                        f"z = {e.finest:.2f} / {p.finest:.2f} mm (endo / epi); not "
                        f"extrapolated: endo {e.asymptotic}.")  # fmt: skip
            continue
        s = (f"Land problem {problem}: Richardson-extrapolated apex z = {e.extrapolated:.2f} "
             f"/ {p.extrapolated:.2f} mm (endo / epi; observed order {e.order:.2g} / "
             f"{p.order:.2g}, asymptotic: {e.asymptotic} / {p.asymptotic}; an h^2 fit over "
             f"all meshes gives {e.fit_order_2:.2f} / {p.fit_order_2:.2f} mm)")  # fmt: skip
        if math.isfinite(e.published):
            s += (f" vs the published {e.published:.2f} / {p.published:.2f} mm (differences "
                  f"{e.extrapolated_minus_published:+.2f} / {p.extrapolated_minus_published:+.2f}"
                  " mm)")  # fmt: skip
        text.append(s + ".")
    return text


def beam_level_scenes(finest: tuple[int, int, int]) -> list[StudyScene]:
    """The beam at a third, two thirds and all of ``finest``'s divisions (role ``beam-level``).

    Parameters
    ----------
    finest
        The study's beam divisions; three levels need the cross-section's divisions to be a
        multiple of 3 (otherwise the one level).

    Returns
    -------
    list of StudyScene
    """
    nx, ny, nz = finest
    if ny % 3 or nz % 3 or nx % 3:
        levels = [finest]
    else:
        levels = [(nx * k // 3, ny * k // 3, nz * k // 3) for k in (1, 2, 3)]
    out = []
    for d in levels:
        s = StudyScene.bundled("land-beam", {"mesh.divisions": list(d)}, roles=("beam-level",))
        out.append(s)
    return out


def beam_levels_frame(cases: list[dict], results: list[dict]) -> pd.DataFrame:
    """One row per level (``h``, tip z, wall time) and a Richardson row when three converged.

    Parameters
    ----------
    cases
        The level cases (their ``divisions``, or the table's ``mesh.divisions``).
    results
        :func:`~.cases.beam_case` results.

    Returns
    -------
    pandas.DataFrame
        ``mesh``, ``h``, ``tip_z``, ``wall_time``, ``error``, ``published_range``.
    """
    rows = []
    for c, r in zip(cases, results, strict=True):
        d = c.get("divisions") or c["table"]["mesh"]["divisions"]
        rows.append({"mesh": "x".join(map(str, d)), "h": 10.0 / d[0], "tip_z": r["tip_z"],
                     "wall_time": r["wall_time"], "error": r["error"]})  # fmt: skip
    ok = [r for r in rows if not r["error"] and math.isfinite(r["tip_z"])]
    if len(ok) >= 3:
        p, f0, note = observed_order([r["h"] for r in ok[-3:]], [r["tip_z"] for r in ok[-3:]])
        label = f"Richardson (p = {p:.2g})" if math.isfinite(p) else f"Richardson: {note}"
        rows.append({"mesh": label, "h": 0.0, "tip_z": f0, "wall_time": math.nan, "error": ""})
    df = pd.DataFrame(rows)
    df["published_range"] = "{:.2f}-{:.2f}".format(*PUBLISHED_RANGE)
    return df


def beam_levels_finding(df: pd.DataFrame) -> list[str]:
    """One sentence: the finest level and the extrapolated tip z against the published range."""
    rich = df[df.mesh.str.startswith("Richardson")]
    if not len(rich):
        return []
    f0, finest = float(rich.tip_z.iloc[0]), df.iloc[-2]
    lo, hi = PUBLISHED_RANGE
    inside = "inside" if lo <= f0 <= hi else "outside"
    return [f"Land problem 1 (beam), P2/P1 mixed on {len(df) - 1} meshes: tip z "
            f"{finest.tip_z:.4f} mm on {finest.mesh}, {rich.mesh.iloc[0]} {f0:.4f} mm, "
            f"{inside} the 11 codes' {lo:.2f}-{hi:.2f} mm."]  # fmt: skip
