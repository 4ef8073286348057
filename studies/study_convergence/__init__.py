"""Study ``convergence``: refinement of a scene for the spring model, P1 and P2.

Every scene is refined by the factors of the settings (:mod:`.levels`: a box grid's
divisions times the factor, any other mesh uniformly, each tet into 8 per doubling), so
every level contains the level-1 vertices. On each level the spring model
(``spring-energy``), the exact spring element (``spring-exact``) and P1 are solved, P2 on
its own levels (``P1-NH`` and ``P2-NH`` on a neo-Hookean scene: the FEM of the scene's law).
Errors are measured against P2 on the reference level (the settings' ``ref``, or the finest
level the scene runs): the relative L2 error at the level-1 vertices and the relative error
of one displacement component ``w`` (:func:`tracked`). Rates are slopes of ``log err`` over
``log h`` (:func:`studies.metrics.fitted_rate`), ``h = h₁ / factor`` with ``h₁`` the mean
edge length of the scene's own mesh.

The spring model need not converge to the FEM limit: its calibration cannot match the
material on six-tet meshes. The study tracks ``spring / P1 − 1`` of ``w`` on the same meshes
(does the gap close under refinement?) and extrapolates each model's limit from its three
finest levels (P1's extrapolation, whose true limit is the reference, shows how far the
extrapolation itself can be trusted). A scene with a closed-form reference
(:mod:`studies.analytic`, the bar's Timoshenko deflection) compares the P2 reference with it.
The spring model runs with energy torsion (analytic Hessian) instead of the specification's
cosine torsion (finite-difference Jacobian, ~4× slower); one ``spring-cosine`` case at
``Settings.cosine_check_level`` measures the difference.

The bundled report runs it on the cantilever bar (0.1 × 0.01 × 0.01 m) on ``[10, 1, 1]``
hexahedra refined by 1–8; ``springfem study convergence --scene FILE`` on the user's scene.

Examples
--------
>>> [s.label for s in bundled_scenes(Settings.quick())]
['cantilever']
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from springfem.errors import SolverError
from springfem.files import safe_filename

from .. import metrics, models
from ..analytic import reference
from ..plots import loglog_rates
from ..registry import StudyContext, StudyOutput, study
from ..scenes import StudyScene, require
from ..tables import pyplot
from .levels import case_level, coarse_index, grid_box, level_label, mean_edge, select_levels

VERSION = 2
#: The spring model of the study (energy torsion), its cosine check and the exact element.
SPRING, COSINE, EXACT = "spring-energy", "spring-cosine", "spring-exact"
#: An extrapolation with a lower fitted order is not trusted.
MIN_EXTRAPOLATION_ORDER = 0.8
L2 = "L2 err (level-1 vertices)"


@dataclass(frozen=True)
class Settings:
    """Refinement levels (factors of the scene's own mesh): ``levels`` of the spring models
    and P1, ``p2_levels`` of P2, ``ref`` of the P2 reference (a scene that cannot take it:
    its finest), ``cosine_check_level`` of the cosine-torsion check (or the finest level
    below it); levels over ``max_tets`` are left out (the two coarsest always run)."""

    levels: tuple[int, ...] = (1, 2, 3, 4, 6, 8)
    p2_levels: tuple[int, ...] = (1, 2, 3, 4)
    ref: int = 8
    cosine_check_level: int = 4
    max_tets: int = 40_000

    @classmethod
    def full(cls) -> Settings:
        """Levels 1-8, reference P2 at 8."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """Levels 1-4, reference P2 at 4."""
        return cls(levels=(1, 2, 3, 4), p2_levels=(1, 2, 3), ref=4, max_tets=5_000)


def fem_models(law: str) -> tuple[str, str]:
    """The FEM models ``(P1, P2)`` of a scene's law.

    Examples
    --------
    >>> fem_models("neo-hookean"), fem_models("transverse-linear")
    (('P1-NH', 'P2-NH'), ('P1', 'P2'))
    """
    return ("P1-NH", "P2-NH") if law == "neo-hookean" else ("P1", "P2")


def bundled_scenes(settings: Settings) -> list[StudyScene]:
    """The cantilever bar on ``[10, 1, 1]`` hexahedra, six tets each, with Timoshenko's tip
    deflection as its closed-form reference.

    Examples
    --------
    >>> [s.build().mesh.n_tets for s in bundled_scenes(Settings())]
    [60]
    """
    return [StudyScene.bundled("cantilever", {"mesh.divisions": [10, 1, 1]}, analytic="timoshenko")]


@dataclass(frozen=True)
class Plan:
    """What runs on one scene: its P1 and P2 models (``fem``), the levels of the spring
    models and P1 and of P2 (without the reference level), the reference and cosine-check
    levels, the settings' levels it does not run and why (``notes``), and the tets and mean
    edge length of level 1."""

    scene: StudyScene
    fem: tuple[str, str]
    levels: tuple[int, ...]
    p2_levels: tuple[int, ...]
    ref: int
    cosine: int
    notes: tuple[str, ...]
    n_tets: int
    h1: float

    @property
    def models(self) -> tuple[str, ...]:
        """The models of the tables: the spring models, P1 and P2."""
        return (SPRING, EXACT, *self.fem)

    def case(self, model: str, factor: int) -> dict[str, Any]:
        """The cache case of ``model`` on level ``factor``."""
        return self.scene.case("convergence", VERSION, model=model, factor=factor)

    def cases(self) -> list[dict[str, Any]]:
        """The reference first (a budget leaves out the last cases, never the reference),
        then the levels, the P2 levels and the cosine check."""
        p1, p2 = self.fem
        out = [self.case(m, k) for m in (SPRING, p1, EXACT) for k in self.levels]
        out += [self.case(p2, k) for k in self.p2_levels]
        return [self.case(p2, self.ref), *out, self.case(COSINE, self.cosine)]


def plan(s: StudyScene, q: Settings) -> Plan:
    """The levels a scene runs (see :func:`.levels.select_levels`).

    Examples
    --------
    >>> p = plan(bundled_scenes(Settings())[0], Settings())
    >>> p.levels, p.p2_levels, p.ref, p.cosine
    ((1, 2, 3, 4, 6, 8), (1, 2, 3, 4), 8, 4)
    """
    mesh = (scene := s.build()).mesh
    kept, notes = select_levels(s.table, mesh.n_tets, sorted({*q.levels, *q.p2_levels, q.ref}),
                                q.max_tets)  # fmt: skip
    levels = tuple(k for k in q.levels if k in kept)
    ref = q.ref if q.ref in kept else max(kept)
    below = [k for k in levels if k <= q.cosine_check_level]
    p2 = tuple(k for k in q.p2_levels if k in kept and k != ref)
    return Plan(s, fem_models(scene.material.law), levels, p2, ref,
                max(below) if below else levels[0], tuple(notes), mesh.n_tets,
                mean_edge(mesh))  # fmt: skip


def work(case: dict[str, Any]) -> dict[str, Any]:
    """Solve one level with one model: its probes and its field at the level-1 vertices."""
    scene = case_level(case)
    got = models.run(scene, case["model"])
    out = {"status": got.status, "tets": scene.mesh.n_tets, "message": got.message[:240]}
    if not got.ok:
        return out
    r = got.solution.result
    return {**out, "dofs": r.counts.get("dofs", 3 * scene.mesh.n_points), "probes": r.probes,
            "u_coarse": np.asarray(got.u)[coarse_index(case, scene.mesh)],
            "wall": r.wall_time}  # fmt: skip


def richardson_limit(h: np.ndarray, w: np.ndarray) -> tuple[float, float]:
    """Limit ``L`` and order ``p`` of ``w(h) = L + C h^p`` through three points (``nan``:
    fewer points, or no such fit; :func:`studies.metrics.observed_order`).

    Examples
    --------
    >>> h = np.array([0.4, 0.2, 0.1]); L, p = richardson_limit(h, 2.0 + 3.0 * h**1.5)
    >>> round(L, 10), round(p, 10)
    (2.0, 1.5)
    """
    p, L, _ = metrics.observed_order(h, w)
    return L, p


@dataclass(frozen=True)
class Tracked:
    """The displacement component ``w`` of the tip columns: a probe's or a level-1
    vertex's; ``name`` is its name in headline keys (the probe's, or ``vertex``)."""

    name: str
    probe: str | None
    vertex: int | None
    component: int

    @property
    def label(self) -> str:
        where = f"probe {self.probe}" if self.probe else f"level-1 vertex {self.vertex}"
        return f"u{'xyz'[self.component]} at {where}"

    def value(self, r: dict) -> float:
        """Its value in one case's result."""
        if self.probe is not None:
            return float(r["probes"][self.probe][self.component])
        return float(r["u_coarse"][self.vertex][self.component])


def tracked(p: Plan, ref: dict) -> tuple[Tracked, tuple[float, str] | None]:
    """``w``, and its closed-form value if the scene has one: the scene's closed-form
    quantity (the cantilever's tip ``u_z``), else its first probe's largest component in the
    reference, else the largest component of the level-1 vertex that moves most."""
    hook = reference(p.scene, None)
    if hook is not None:
        probe, component, value, source = hook
        return Tracked(probe, probe, None, component), (value, source)
    if ref["probes"]:
        probe, u = next(iter(ref["probes"].items()))
        return Tracked(probe, probe, None, int(np.argmax(np.abs(u)))), None
    u = np.asarray(ref["u_coarse"], float)
    vertex = int(np.argmax(np.linalg.norm(u, axis=1)))
    return Tracked("vertex", None, vertex, int(np.argmax(np.abs(u[vertex])))), None


def _scene(ctx: StudyContext, p: Plan, results: list[dict], suffix: str, out: StudyOutput):
    """Tables, figures, findings and headline of one scene from :meth:`Plan.cases`'s
    results (the reference first)."""
    ref, (p1, p2), name = results[0], p.fem, p.scene.label
    if ref["status"] != "ok":
        raise SolverError(f"the reference {p2} on level {p.ref} failed: {ref['message']}")
    track, analytic = tracked(p, ref)
    w_ref, u_ref = track.value(ref), np.asarray(ref["u_coarse"], float)
    rows = []
    for c, r in zip(p.cases()[1:], results[1:], strict=True):
        ok = r["status"] == "ok"
        w = track.value(r) if ok else np.nan
        rows.append({
            "model": c["model"], "factor": c["factor"],
            "mesh": level_label(p.scene.table, c["factor"]), "tets": r["tets"],
            "dofs": r.get("dofs", np.nan), "h": p.h1 / c["factor"], "w": w,
            "w / w_ref": w / w_ref, "w err": abs(w - w_ref) / abs(w_ref),
            L2: metrics.relative_l2_error(r["u_coarse"], u_ref) if ok else np.nan,
            "wall time (s)": r.get("wall", np.nan), "status": r["status"],
        })  # fmt: skip
    df = pd.DataFrame(rows)
    w_cosine = float(df[df["model"] == COSINE]["w"].iloc[0])
    levels = df[df["model"] != COSINE].reset_index(drop=True)
    good = levels[levels["status"] == "ok"]

    rate, rate_rows = {}, []  # per model: L2 and w rates, extrapolated w / w_ref
    for m in p.models:
        d = good[good["model"] == m].sort_values("h", ascending=False)
        if not len(d):
            continue
        rl2, rtip = metrics.fitted_rate(d["h"], d[L2]), metrics.fitted_rate(d["h"], d["w err"])
        limit, order = richardson_limit(d["h"].values[-3:], d["w / w_ref"].values[-3:])
        rate[m] = {"l2": rl2, "tip": rtip}
        last = d.iloc[-1]
        rate_rows.append({
            "model": m, "levels": len(d), "rate (L2)": rl2, "rate (w)": rtip,
            "finest factor": int(last["factor"]), "L2 err at finest": last[L2],
            "w err at finest": last["w err"], "extrapolated w / w_ref": limit,
            "extrapolation order": order,
        })  # fmt: skip
    rates = pd.DataFrame(rate_rows)
    fin = rates.set_index("model")["w err at finest"] if len(rates) else pd.Series(dtype=float)
    # the gap: spring / P1 - 1 of w on the same meshes, its rate and extrapolated limit
    sp = good[good["model"] == SPRING].set_index("factor")
    q1 = good[good["model"] == p1].set_index("factor")
    common = sp.index.intersection(q1.index)
    gap = (sp.loc[common, "w"] / q1.loc[common, "w"] - 1.0).sort_index()
    h_gap = sp.loc[gap.index, "h"]
    gap_rate = metrics.fitted_rate(h_gap, gap.abs())
    g_inf, g_order = richardson_limit(h_gap.values[-3:], gap.values[-3:])
    cosine_vs_energy = (w_cosine / float(sp.at[p.cosine, "w"]) - 1.0 if p.cosine in sp.index
                        else float("nan"))  # fmt: skip

    if len(gap) == 0:
        limit_text = f"No level has both {SPRING} and {p1}."
    else:
        k0, k1 = int(gap.index[0]), int(gap.index[-1])
        limit_text = (
            f"On the same mesh {SPRING}'s w is {gap.iloc[0]:+.1%} from {p1} at level {k0} and "
            f"{gap.iloc[-1]:+.1%} at level {k1} ({'softer' if gap.iloc[-1] > 0 else 'stiffer'});"
            " the gap " + (f"shrinks at rate {gap_rate:.2f} in h" if gap_rate > 0
                           else f"does not shrink (rate {gap_rate:.2f})")
        )  # fmt: skip
        if not np.isfinite(g_inf):
            limit_text += " (three finest gaps not monotone: no limit extrapolated)."
        elif g_order < MIN_EXTRAPOLATION_ORDER or (abs(g_inf) >= 0.02 and g_inf * gap.iloc[-1] < 0):
            limit_text += (
                f"; extrapolating the three finest levels gives {g_inf:+.1%} with order "
                f"{g_order:.2f}, which these levels are too coarse to trust (pre-asymptotic): no "
                "conclusion on the spring model's limit."
            )
        else:
            limit_text += (
                f" and extrapolates (three finest levels, order {g_order:.2f}) to {g_inf:+.1%}"
                + (": the spring model converges to within ~2% of FEM's limit." if abs(g_inf) < 0.02
                   else ": the spring model converges to another limit than FEM.")
            )  # fmt: skip

    last = {m: good[good["model"] == m].sort_values("factor").iloc[-1] for m in rate}
    l2_rates = ", ".join(f"{m} {r['l2']:.2f}" for m, r in rate.items())
    findings = [
        f"{name}: fitted L2 rates at the level-1 vertices against {p2} on level {p.ref} "
        f"({ref['tets']} tets): {l2_rates} (w = {track.label}: "
        + ", ".join(f"{m} {r['tip']:.2f}" for m, r in rate.items()) + "); "
        "the asymptotic L2 rates on a smooth solution are 2 for linear elements and 3 for P2, "
        "so lower fitted rates mean pre-asymptotic levels (the bending stiffness of linear "
        "tets) or a singular solution"
        + ("; quick run: reference only one level finer than the last P2 point." if ctx.quick
           else "."),
    ]  # fmt: skip
    if p.notes:
        findings.append(f"{name}: {'; '.join(p.notes)}.")
    if {SPRING, p1} <= set(last):
        text = (
            f"At the finest spring/{p1} level ({int(last[p1]['factor'])}, "
            f"{int(last[p1]['tets'])} tets) w is {last[SPRING]['w / w_ref'] - 1:+.1%} from the "
            f"reference for {SPRING} and {last[p1]['w / w_ref'] - 1:+.1%} for {p1}"
        )
        if p2 in last:
            text += f" ({p2} at level {int(last[p2]['factor'])}: {last[p2]['w / w_ref'] - 1:+.2%})"
        findings.append(text + ".")
    findings.append(
        limit_text + " The calibration mismatch of the specification's element shows most in "
        "the Poisson (lateral) response (accuracy study), which bending barely feels."
    )
    if analytic is not None:
        value, source = analytic
        findings.append(
            f"The {p2} reference's w is {w_ref / value - 1:+.2%} from {source} (its "
            "idealisations: for a beam, the 3D clamping and Poisson effects at the support), "
            f"so errors are measured against {p2}, not against {source}."
        )
    if np.isfinite(cosine_vs_energy):
        findings.append(
            f"{SPRING} (energy-consistent torsion, analytic Hessian) is the spring model here; "
            f"the specification's cosine torsion ({COSINE}) changes w by "
            f"{cosine_vs_energy:+.2%} at level {p.cosine}."
        )
    if {EXACT, p1, SPRING} <= set(rate):
        findings.append(
            f"{EXACT} (axis-volume + energy torsion + exact calibration) converges like P1: "
            f"L2 rate {rate[EXACT]['l2']:.2f} ({p1} {rate[p1]['l2']:.2f}), w error at the "
            f"finest level {fin[EXACT]:.1%} ({p1} {fin[p1]:.1%}, {SPRING} {fin[SPRING]:.1%}): "
            "the spring–P1 gap of the specification's element is its calibration, and the "
            "exact element has none."
        )
    out.findings += findings

    # headline: rates, w errors at the finest level, the gap; <w> is the tracked probe (tip)
    tip = track.name
    head = {f"rate_l2_{m}": r["l2"] for m, r in rate.items()}
    head.update({f"rate_{tip}_{m}": rate[m]["tip"] for m in (p1, p2) if m in rate})
    head.update({f"{tip}_err_finest_{m}": float(fin[m]) for m in (SPRING, EXACT, p1) if m in rate})
    if len(gap):
        head[f"{SPRING}_over_{p1}_finest"] = float(gap.iloc[-1] + 1.0)
        head[f"rate_{SPRING}_{p1}_gap"] = gap_rate
    if analytic is not None and p.scene.analytic is not None:
        head[f"ref_over_{p.scene.analytic}"] = w_ref / analytic[0]
    out.headline.update({f"{k}{suffix}": v for k, v in head.items()})

    how = ("its divisions times the factor" if grid_box(p.scene.table)
           else "uniform refinement (each tet into 8 per doubling)")  # fmt: skip
    out.tables += [
        ctx.table(levels, f"convergence_levels{suffix}",
                  f"{name} refined by {how}: w = {track.label} and errors against {p2} on level "
                  f"{p.ref} ({ref['tets']} tets, w = {w_ref:.6g}); h = h₁ / factor with h₁ = "
                  f"{p.h1:.4g} the mean edge length of the scene's mesh (its length unit)"
                  + (f"; {'; '.join(p.notes)}" if p.notes else "") + "."),
        ctx.table(rates, f"convergence_rates{suffix}",
                  "Fitted rates (slope of log error over log h, all levels) and w extrapolated "
                  "from each model's three finest levels (w = L + C h^p); "
                  f"{p1}'s true limit is the reference's, so its extrapolated value shows the "
                  "extrapolation's own bias."),
    ]  # fmt: skip

    # figures: errors against h (log-log, fitted rates); w per level and the gap against h
    plt = pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    curves = {m: good[good["model"] == m].sort_values("h") for m in rate}
    ticks = sorted(good["h"].unique())
    hx = "h (mean edge length)"
    loglog_rates(
        left,
        {m: (d["h"], d[L2]) for m, d in curves.items()},
        hx,
        f"relative L2 error at the {len(ref['u_coarse'])} level-1 vertices",
        {m: r["l2"] for m, r in rate.items()},
        xticks=ticks,
    )
    loglog_rates(right, {m: (d["h"], d["w err"]) for m, d in curves.items()}, hx,
                 f"relative error of {track.label}", {m: r["tip"] for m, r in rate.items()},
                 xticks=ticks)  # fmt: skip
    fig.tight_layout()
    left.set_title(f"{name}: displacement vs {p2} on level {p.ref}", fontsize=10)
    right.set_title(track.label, fontsize=10)
    e = good[good["model"].isin([SPRING, p1])].pivot(index="factor", columns="model", values=L2)
    n_below = int((e[SPRING] < e[p1]).sum()) if {SPRING, p1} <= set(e.columns) else 0
    out.figures.append(ctx.figure(
        fig, f"convergence{suffix}.png",
        f"Errors against the {p2} reference under refinement, log-log, fitted rates in the "
        f"legend (L2: {l2_rates}); {SPRING}'s "
        f"error is below {p1}'s on {n_below} of {len(e)} levels."))  # fmt: skip

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2))
    for m, mk in zip(rate, "o*sD", strict=False):
        d = good[good["model"] == m].sort_values("factor")
        ax.plot(d["factor"], d["w / w_ref"], marker=mk, label=m)
    ax.axhline(1.0, color="k", lw=0.8, label=f"{p2} reference (level {p.ref})")
    if analytic is not None:
        ax.axhline(analytic[0] / w_ref, color="gray", ls="--", lw=0.8, label=analytic[1])
    ax.set_xscale("log")
    ks = sorted(good["factor"].unique())
    ax.set_xticks(ks, [str(k) for k in ks])
    ax.minorticks_off()
    ax.set(xlabel=f"refinement factor of {name}'s mesh", ylabel="w / reference")
    ax.set_title(f"{track.label} under refinement", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    gap_name = f"|{SPRING} / {p1} − 1| (same mesh)"
    h = p.h1 / np.asarray(gap.index, float)
    loglog_rates(bx, {gap_name: (list(h), list(gap.abs()))}, hx, f"|{SPRING} / {p1} − 1| of w",
                 {gap_name: gap_rate}, xticks=sorted(h))  # fmt: skip
    bx.set_title("does the spring–P1 gap close under refinement?", fontsize=10)
    fig.tight_layout()
    out.figures.append(ctx.figure(
        fig, f"tip_deflection{suffix}.png",
        f"Left: {track.label} normalised by the P2 reference under refinement. Right: the "
        f"spring model's w relative to P1 on the same mesh. {limit_text}"))  # fmt: skip


@study("convergence", Settings, bundled_scenes)
def run(ctx: StudyContext, scenes: list[StudyScene], settings: Settings) -> StudyOutput:
    """Refine every scene (one table pair, two figures and the headline each; with several
    scenes, files and headline keys end in the scene's label)."""
    require(scenes, "convergence")
    out = StudyOutput(ctx.name, "")
    for s in scenes:
        p = plan(s, settings)
        results = ctx.cache.run(p.cases(), work, ctx.progress, "convergence")
        _scene(ctx, p, results, "" if len(scenes) == 1 else f"_{safe_filename(s.label)}", out)
    out.title = (f"Convergence under refinement ({', '.join(s.label for s in scenes)}): "
                 "spring models, P1, P2")  # fmt: skip
    return out
