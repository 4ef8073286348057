"""Study ``locking``: which method is cheapest within 5 % near incompressibility.

The probe deflection against the Poisson ratio (ν = 0.3, 0.49, 0.4999 by default) on three
mesh levels, for every method of :data:`~.cases.METHODS`: FEM on the scene's own law (P1,
P1 with nodal-averaged volume, Bonet & Burton 1998, P1 with nodal-averaged strain, MINI,
P2, P2/P1 Taylor–Hood) and the spring elements (the specification's, the exact element, on
nodal volumes, stabilised nodal strain + volume). The shear modulus is held and ν sets the
bulk modulus (:func:`~.cases.with_nu`; a tissue law: its volumetric penalty). The reference
at each ν is P2/P1 on the finest level; a method's error is its relative difference from
it, its cost the wall time of its static solve. The answer per ν is the cheapest method
and level within 5 % (the reference excluded), or "none". A solve is capped
(:attr:`~.cases.Settings.max_time`; one that needs longer is stopped), and a finer level
that cannot change the answer is not run (a ``skipped`` row with the reason): above all
displacement P2 near incompressibility, which locks there and needs hundreds of Newton
iterations while P2/P1 on a coarser mesh is more accurate and faster.

Bundled: Cook's membrane (neo-Hookean, shear load, μ = 80.19 kPa; ``u_y`` of the corner)
and Land's beam (Guccione, follower pressure; ``u_z`` of the tip). ``--scene FILE`` runs
the same on a user's scene (an isotropic or tissue law and a ``[[probe]]``: its first
probe's dominant component). :mod:`.cases` holds the methods and one timed solve,
:mod:`.figures` the two figures.

Examples
--------
>>> [s.label for s in bundled_scenes(Settings.quick())]
['cook-membrane', 'land-beam']
>>> df = pd.DataFrame({"scene": "s", "nu": 0.3, "method": ["a", "b", "c"],
...     "status": "ok", "error": [0.01, 0.2, 0.04], "seconds": [3.0, 0.1, 1.0],
...     "reference": [True, False, False]})
>>> cheapest(df, 0.05).method
'c'
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np
import pandas as pd

from springfem.materials.tissue import TISSUE_LAWS

from ..registry import StudyContext, StudyOutput, study
from ..scenes import StudyScene, require
from ..study_convergence import richardson_limit
from .cases import (
    COST_PER_DOF,
    COSTLIER,
    LINEAR_TETS,
    REFERENCE,
    TOLERANCE,
    Settings,
    bundled_scenes,
    case_of,
    cases,
    estimate,
    locking_case,
    scene_methods,
)
from .figures import deflection_figure, error_cost_figure

__all__ = ["Settings", "bundled_scenes", "run"]

AXES = "xyz"
#: The methods whose error at the highest ν on the finest level is a headline number: those
#: that solve well inside the quick preset's cap, so that the headline does not depend on
#: the machine's speed (the stabilised spring elements and displacement P2 can take the cap
#: on a busy machine; the cheapest method depends on timings too).
HEADLINE_METHODS = ("P1", "P1-nodal-volume", "P1-nodal-strain", "MINI", "spring-spec",
                    "spring-exact", "spring-nodal-volume")  # fmt: skip


@study("locking", Settings, bundled_scenes)
def run(ctx: StudyContext, scenes: list[StudyScene], settings: Settings) -> StudyOutput:
    """Error and cost of each locking-free method per Poisson ratio.

    Headline: per scene and ν, ``cheapest_error_<scene>_nu<ν>`` (the cheapest adequate
    method's error), and at the highest ν ``error_<scene>_<method>_nu<ν>`` (the finest
    level's error of each of :data:`HEADLINE_METHODS`).
    """
    require(scenes, ctx.name)
    if ctx.cache.budget.seconds is not None and settings.timed:
        # within a budget each solve runs once: a warm-up solve and repeats would take a
        # first solve's time again of every method (a note says so)
        settings = replace(settings, timed=False)
    notes, levels = [], []
    for sc in scenes:
        factors, note = affordable_levels(ctx, sc, settings)
        notes += note
        levels.append((sc, factors))
    df, refs = with_errors(result_frame(*_staged(ctx, levels, settings)))
    answers = answer_frame(df)
    if not settings.timed:
        notes.append("Within the study's budget every solve ran once: its time includes a "
                     "method's first-solve costs (imports, loading compiled kernels).")  # fmt: skip
    headline = {f"cheapest_error_{r.scene}_nu{r.nu:g}": float(r["its error"])
                for _, r in answers.iterrows()}  # fmt: skip
    nu = df.nu.max()
    for (scene, m), g in df[df.nu == nu].groupby(["scene", "method"], sort=False):
        fine = g[g.factor == g.factor.max()]
        if m in HEADLINE_METHODS and len(fine) and not fine.reference.iloc[0]:
            ok = fine.status.iloc[0] == "ok"
            value = round(float(fine.error.iloc[0]), 4) if ok else math.nan
            headline[f"error_{scene}_{m}_nu{nu:g}"] = value

    findings = answer_sentences(answers)
    for scene, g in df.groupby("scene", sort=False):  # the highest ν: who locks
        top = g[(g.nu == g.nu.max()) & (g.factor == g.factor.max())]
        if (top.status == "ok").any():  # else nothing solved there (skipped by the budget)
            shares = [f"{r.method} {r.deflection / r.ref_value:.0%}" if r.status == "ok"
                      else f"{r.method} {r.status}"
                      + (f" at load {r.load:.2g}" if np.isfinite(r.load) else "")
                      for _, r in top.iterrows()]  # fmt: skip
            findings.append(
                f"{scene} at ν = {g.nu.max():g}, finest level ({int(top.tets.max())} tets): "
                "deflection as a share of the reference: " + ", ".join(shares) + "."
            )
    for scene, g in refs.groupby("scene", sort=False):
        vals = ", ".join(
            (f"ν = {r.nu:g}: {r.reference:.4g}" if np.isfinite(r.reference)
             else f"ν = {r.nu:g}: none ({REFERENCE} did not solve)")
            + (f" (Richardson {r.richardson:.4g}, order {r['observed order']:.2g})"
               if np.isfinite(r.richardson) else "")
            for _, r in g.iterrows()
        )  # fmt: skip
        shift = g["extrapolation shift"].max()
        findings.append(
            f"{scene}: the reference u_{g.axis.iloc[0]} is {REFERENCE} on the finest level "
            f"({int(g.tets.max()) if g.tets.notna().any() else 0} tets): {vals}. The "
            "extrapolations move it by at most "
            + (f"{shift:.1%}" if np.isfinite(shift) else "— (none possible: fewer than three "
               "levels, or values not monotone)")
            + "; they are shown, not used, because three levels cannot show the order to be "
            "asymptotic."
        )  # fmt: skip
    laws = {sc.label: str(sc.table.get("material", {}).get("law", "linear")) for sc in scenes}
    if tissue := [s for s, law in laws.items() if law in TISSUE_LAWS]:
        findings.append(
            f"{', '.join(tissue)}: a tissue law has its own shear response, so ν only sets "
            "its volumetric penalty, κ = 2μ(1 + ν) / (3(1 − 2ν)) with μ the mean shear "
            "modulus of the law's small-strain tangent; an incompressible scene is solved "
            "nearly incompressible at each ν (Land's beam: κ/μ = 500 at ν = 0.499, "
            "5000 at 0.4999)."
        )
    skipped = df[df.status == "skipped"]
    costlier = skipped.message.astype(str).str.contains(COSTLIER, regex=False)
    if len(over := skipped[~costlier]):
        which = ", ".join(f"{m} ({len(x)})" for m, x in over.groupby("method", sort=False))
        findings.append(
            f"Not run (count): {which}: their predicted time (DOFs × the method's measured "
            f"cost per DOF) was over the {settings.max_time:g} s cap of a solve or the "
            "study's budget; a method within 5 % on a coarser level does not run its finer "
            "levels either (they cannot be cheaper)."
        )
    findings += costlier_sentences(df, skipped[costlier])
    if len(stopped := df[~df.status.isin(["ok", "skipped"])]):
        which = ", ".join(f"{m} ({len(x)})" for m, x in stopped.groupby("method", sort=False))
        # a stopped solve could only have been the answer where no adequate method is
        # faster than the cap
        open_ = [f"{r.scene} ν = {r.nu:g}" for _, r in answers.iterrows()
                 if not (r["its seconds"] < settings.max_time)
                 and len(stopped[(stopped.scene == r.scene) & (stopped.nu == r.nu)])]  # fmt: skip
        findings.append(
            f"Solves that stopped at the {settings.max_time:g} s cap or failed (count): "
            f"{which}. "
            + ("Where they stopped, a method within the tolerance solved in less than the "
               "cap, so none of them could have been the cheapest." if not open_
               else "The answer may miss a slower method at " + ", ".join(open_) + ".")
        )  # fmt: skip

    tables = [
        ctx.table(answers, "cheapest",
                  "Per scene and Poisson ratio: the cheapest method and level (smallest solve "
                  f"wall time) whose deflection is within {TOLERANCE:.0%} of the reference, "
                  "excluding the reference itself (``none``: no method qualifies), the same "
                  "among the methods on the mesh's own vertices (linear tets: P1-type FEM and "
                  "the spring elements), the reference's own time, the methods more than "
                  f"{TOLERANCE:.0%} off on every level, and those not run on every level "
                  "(predicted over the cap of a solve, or over the study's budget) and not "
                  "within the tolerance where they ran."),
        ctx.table(df[["scene", "method", "nu", "tets", "status", "load", "axis", "deflection",
                      "error", "seconds", "message"]].sort_values(
                      ["scene", "nu", "method", "tets"], kind="stable"), "locking",
                  "Every scene, method, Poisson ratio and mesh level: status (``partial``: the "
                  "solve stopped at the load factor ``load``, by the time cap or a failure), "
                  "the compared probe displacement component (``axis``), its relative error "
                  f"against the reference ({REFERENCE} on the finest level at the same Poisson "
                  "ratio) and the static solve's wall time (s; median of three under half a "
                  "second, after an untimed warm-up solve of each method)."),
        ctx.table(refs, "references",
                  f"The reference per scene and Poisson ratio: {REFERENCE} on the finest "
                  "level, its Richardson extrapolation through the three levels (h ∝ 1 / "
                  "refinement factor) with the observed order (empty: the three values are "
                  "not monotone), and how far the extrapolation lies from the finest value."),
    ]  # fmt: skip
    return StudyOutput(
        name=ctx.name,
        title="Locking: the cheapest method within 5 % near incompressibility "
        f"({', '.join(sc.label for sc in scenes)})",
        findings=notes + findings,
        tables=tables,
        figures=[deflection_figure(ctx, df), error_cost_figure(ctx, df)],
        headline=headline,
    )


def answer_sentences(answers: pd.DataFrame, tolerance: float = TOLERANCE) -> list[str]:
    """Per scene: the cheapest method within ``tolerance`` at each ν, overall and on linear
    tets.

    Examples
    --------
    >>> a = pd.DataFrame({"scene": "s", "nu": [0.3, 0.4999],
    ...     "cheapest within tolerance": ["P1", "none"], "its tets": [6, np.nan],
    ...     "its error": [0.01, np.nan], "its seconds": [0.1, np.nan],
    ...     "reference seconds": [2.0, 3.0]})
    >>> s = answer_sentences(a)[0]
    >>> "at ν = 0.3, P1 on 6 tets (error 1.0%, 0.1 s" in s, "at ν = 0.4999, none:" in s
    (True, True)
    """
    out = []
    for scene, g in answers.groupby("scene", sort=False):
        parts = [
            f"at ν = {r.nu:g}, none: no method other than the reference is within "
            f"{tolerance:.0%}" if r["cheapest within tolerance"] == "none"
            else f"at ν = {r.nu:g}, {r['cheapest within tolerance']} on {int(r['its tets'])} "
            f"tets (error {r['its error']:.1%}, {r['its seconds']:.2g} s; the reference "
            f"{r['reference seconds']:.2g} s)"
            for _, r in g.iterrows()
        ]  # fmt: skip
        out.append(f"{scene}: the cheapest method within {tolerance:.0%} of the converged "
                   f"{REFERENCE} deflection is, " + "; ".join(parts) + ".")  # fmt: skip
        if "cheapest on linear tets" in g:
            lin = [
                f"ν = {r.nu:g}: " + ("none" if r["cheapest on linear tets"] == "none" else
                f"{r['cheapest on linear tets']} on {int(r['its tets (linear)'])} tets "
                f"({r['its error (linear)']:.1%}, {r['its seconds (linear)']:.2g} s)")
                for _, r in g.iterrows()
            ]  # fmt: skip
            out.append(f"{scene}: on linear tets (P1-type FEM, spring elements) the cheapest "
                       f"within {tolerance:.0%} is: " + "; ".join(lin) + ".")  # fmt: skip
    return out


def costlier_sentences(df: pd.DataFrame, left: pd.DataFrame) -> list[str]:
    """Per scene: the cases not run because they could not be the cheapest, and each such
    method's error at the lowest and highest ν on the finest level where it ran at both (a
    rise with ν is locking).

    Examples
    --------
    >>> df = pd.DataFrame({"scene": "s", "method": "P2", "nu": [0.3, 0.4999, 0.4999],
    ...     "tets": [24, 24, 192], "status": ["ok", "ok", "skipped"],
    ...     "error": [0.03, 0.2, np.nan]})
    >>> text = costlier_sentences(df, df[df.status == "skipped"])[0]
    >>> "P2 at ν = 0.4999 on 192 tets; where it ran, P2 is 3.0% off at ν = 0.3" in text
    True
    >>> "and 20.0% at ν = 0.4999 on 24 tets" in text
    True
    """
    out = []
    lo, hi = df.nu.min(), df.nu.max()
    for scene, g in left.groupby("scene", sort=False):
        parts = []
        for m, x in g.groupby("method", sort=False):
            where = "; ".join(f"ν = {nu:g} on {', '.join(str(int(t)) for t in sorted(y.tets))} "
                              "tets" for nu, y in x.groupby("nu"))  # fmt: skip
            ran = df[(df.scene == scene) & (df.method == m) & (df.status == "ok")]
            if "reference" in ran:
                ran = ran[~ran.reference.astype(bool)]
            both = sorted(set(ran[ran.nu == lo].tets) & set(ran[ran.nu == hi].tets))
            text = f"{m} at {where}"
            if both and lo < hi:
                t = both[-1]
                e = {nu: float(ran[(ran.nu == nu) & (ran.tets == t)].error.iloc[0])
                     for nu in (lo, hi)}  # fmt: skip
                text += (f"; where it ran, {m} is {e[lo]:.1%} off at ν = {lo:g} and "
                         f"{e[hi]:.1%} at ν = {hi:g} on {int(t)} tets")  # fmt: skip
            parts.append(text)
        out.append(
            f"{scene}: not run where they cannot be the cheapest of their kind of tets (on a "
            f"coarser level a method on the same tets was within {TOLERANCE:.0%} in less than "
            "their predicted time, or at least twice as accurate and no slower; the cases "
            "table gives each reason): " + "; ".join(parts) + ". An error "
            "that rises with ν on one mesh is locking."
            + (
                " Displacement P2 locks as ν → 1/2, and its Newton solve on the stiffening "
                "penalty takes hundreds of iterations there (274 on the quick beam's 486 tets "
                "at ν = 0.4999), while P2/P1 on the coarsest mesh is within the tolerance in "
                "a fraction of a second."
                if "P2" in set(g.method)
                else ""
            )
        )
    return out


# -- staging: which cases run, coarse levels first ----------------------------------------


def affordable_levels(
    ctx: StudyContext, sc: StudyScene, s: Settings
) -> tuple[tuple[int, ...], list[str]]:
    """The levels of a scene within the study's budget, and a note when some are left out.

    Without a budget every level of the settings runs. With one, the levels are kept from
    the coarsest up while the predicted time of all their cases (DOFs × each method's cost
    per DOF, :func:`~.cases.estimate`; on the workers in parallel) fits in it; the coarsest
    always runs, and the reference is solved on the finest level kept.
    """
    factors = tuple(sc.params.get("factors", s.factors))
    budget = ctx.cache.budget
    if budget.seconds is None or len(factors) == 1:
        return factors, []
    from ..executor import worker_count

    workers = max(worker_count(ctx.cache.workers, ctx.cache.scheduler), 1)
    ctx.cache.costs.priors.update(COST_PER_DOF)
    kept, spent = [], 0.0
    for f in factors:
        cost = 0.0
        for c in cases(sc, s, (f,)):
            kind, size, _ = estimate(c)
            got = ctx.cache.costs.predict(kind, size)
            cost += got if got is not None else 0.0
        cost = min(cost, len(cases(sc, s, (f,))) * s.max_time)  # each case is capped
        if kept and spent + cost / workers > budget.seconds:
            left = [x for x in factors if x not in kept]
            return tuple(kept), [
                f"{sc.label}: levels {', '.join(f'x{x}' for x in left)} left out: their "
                f"predicted time ({cost / workers:.0f} s for x{f} alone) does not fit in the "
                f"study's budget of {budget.seconds:g} s; the reference ({REFERENCE}) is "
                f"solved on level x{kept[-1]}, the finest that fits."
            ]
        kept.append(f)
        spent += cost / workers
    return tuple(kept), []


def _staged(
    ctx: StudyContext, levels: list[tuple[StudyScene, tuple[int, ...]]], s: Settings
) -> tuple[list[dict], list[dict]]:
    """The cases and results of the scenes, each with its levels: the references first (each
    scene's finest level), then the i-th level of every scene in one run, from the coarsest
    (the workers stay busy across scenes; without a budget the longest predicted cases start
    first). A case is not run (a ``skipped`` row, :func:`_not_run`) when it cannot change
    the answer."""
    from ..budget import skipped_result

    run = dict(progress=ctx.progress, estimate=estimate, skippable=True, priors=COST_PER_DOF)
    ref_cases = [case_of(sc, s, REFERENCE, nu, factors[-1]) for sc, factors in levels
                 if REFERENCE in scene_methods(sc, s) for nu in s.nus]  # fmt: skip
    ref_res = _run(ctx, ref_cases, "references", run)
    ref_res = [{**r, "tets": estimate(c)[2]} if r.get("status") == "skipped" else r
               for c, r in zip(ref_cases, ref_res, strict=True)]  # fmt: skip
    refs = {(c["scene"], c["nu"]): r for c, r in zip(ref_cases, ref_res, strict=True)}
    axes = {
        sc.label: _axis(
            sc, [r for c, r in zip(ref_cases, ref_res, strict=True) if c["scene"] == sc.label]
        )  # fmt: skip
        for sc, _ in levels
    }
    done: set[tuple[str, str, float]] = set()  # (scene, method, nu) within the tolerance
    dropped: dict[tuple[str, str, float], str] = {}  # (scene, method, nu) -> why not run
    best: dict[tuple[str, float, bool], tuple[float, str, int]] = {}
    last: dict[tuple[str, float, bool], list[tuple[str, float, float, int]]] = {}
    out: dict[str, list[tuple[dict, dict]]] = {sc.label: [] for sc, _ in levels}
    for i in range(max((len(f) for _, f in levels), default=0)):
        rows: list[tuple[dict, dict | None]] = []
        for sc, factors in levels:
            if i >= len(factors):
                continue
            f = factors[i]
            for nu in s.nus:
                for m in scene_methods(sc, s):
                    if m == REFERENCE and f == factors[-1] or (sc.label, m, nu) in done:
                        continue
                    if f == factors[-1] and s.finest_nus is not None and nu not in s.finest_nus:
                        continue  # the quick preset: the finest level at the highest ν only
                    c = case_of(sc, s, m, nu, f)
                    why = dropped.get((sc.label, m, nu))
                    if why is None and i > 0:
                        key = (sc.label, nu, m in LINEAR_TETS)
                        why = _not_run(ctx, s, c, best.get(key), last.get(key, []))
                        if why is not None and COSTLIER in why:
                            dropped[(sc.label, m, nu)] = why  # nor its finer levels
                    rows.append((c, None if why is None else skipped_result(why)))
        todo = [c for c, r in rows if r is None]
        names = ", ".join(f"{sc.label} x{f[i]}" for sc, f in levels if i < len(f))
        got = dict(zip(map(id, todo), _run(ctx, todo, f"level {i + 1} ({names})", run),
                       strict=True))  # fmt: skip
        last = {}
        for c, r in rows:
            r = got[id(c)] if r is None else r
            if r.get("status") == "skipped":
                r = {**r, "tets": estimate(c)[2]}  # the size it would have had
            out[c["scene"]].append((c, r))
            key = (c["scene"], c["nu"], c["method"] in LINEAR_TETS)
            error = _error(r, refs.get((c["scene"], c["nu"]), {}), axes[c["scene"]])
            if error is None:
                continue
            last.setdefault(key, []).append((c["method"], error, float(r["seconds"]),
                                             int(r["tets"])))  # fmt: skip
            if error <= TOLERANCE:
                if s.prune:
                    done.add((c["scene"], c["method"], c["nu"]))
                if key not in best or r["seconds"] < best[key][0]:
                    best[key] = (float(r["seconds"]), c["method"], int(r["tets"]))
    for c, r in zip(ref_cases, ref_res, strict=True):
        out[c["scene"]].append((c, r))
    pairs = [p for sc, _ in levels for p in out[sc.label]]
    return [c for c, _ in pairs], [r for _, r in pairs]


def _run(ctx: StudyContext, cases: list[dict], desc: str, run: dict) -> list[dict]:
    """Run ``cases`` (without a budget the longest predicted first: the last case to finish
    is a short one); the results in the order of ``cases``."""
    order = list(range(len(cases)))
    if ctx.cache.budget.seconds is None:  # a budget leaves out the last: keep the order
        ctx.cache.costs.priors.update(COST_PER_DOF)

        def cost(i: int) -> float:
            kind, size, _ = estimate(cases[i])
            return ctx.cache.costs.predict(kind, size) or 0.0

        order.sort(key=cost, reverse=True)
    res = ctx.cache.run([cases[i] for i in order], locking_case, desc=desc, **run)
    back: list[dict] = [{}] * len(cases)
    for i, r in zip(order, res, strict=True):
        back[i] = r
    return back


def _not_run(
    ctx: StudyContext,
    s: Settings,
    c: dict,
    best: tuple[float, str, int] | None,
    last: list[tuple[str, float, float, int]],
) -> str | None:
    """Why a case of a finer level is not run, or ``None`` to run it.

    With ``s.prune``: its predicted time is over 1.5 × the cap of a solve. With
    ``s.skip_costlier``, on the same kind of tets (``best``: ``(seconds, method, tets)`` of
    the cheapest there within the tolerance at this ν so far; ``last``: ``(method, error,
    seconds, tets)`` of the coarser level): a method was within the tolerance in less than
    the case's predicted time, or on the coarser level a method was at least twice as
    accurate and no slower (both converge; the case's method is locking). Not a rule:
    extrapolating a method's own error from two coarser levels (on the full report's beam
    at ν = 0.4999 the stabilised spring element went 66.7 %, 37.6 % and then 3.1 %, where
    the same rate predicted 21 %). Neither applies to a headline method at the highest ν.
    """
    kind, size, _ = estimate(c)
    guess = ctx.cache.costs.predict(kind, size)
    if s.prune and guess is not None and c["method"] != REFERENCE and guess > 1.5 * s.max_time:
        return f"not run: predicted {guess:.3g} s, over the {s.max_time:g} s cap of a solve"
    if not s.skip_costlier or c["method"] in HEADLINE_METHODS and c["nu"] == max(s.nus):
        return None  # the finest level of these at the highest ν is a headline number
    if best is not None and guess is not None and guess > best[0]:
        seconds, method, tets = best
        return (f"not run: {COSTLIER} (predicted {guess:.3g} s; {method} on {tets} tets "
                f"within {TOLERANCE:.0%} in {seconds:.2g} s)")  # fmt: skip
    mine = [x for x in last if x[0] == c["method"]]
    for method, error, seconds, tets in last if mine else []:
        if method != c["method"] and 2.0 * error <= mine[0][1] and seconds <= mine[0][2]:
            return (
                f"not run: {COSTLIER} (on {tets} tets {method} was {error:.1%} off in "
                f"{seconds:.2g} s, {c['method']} {mine[0][1]:.1%} in {mine[0][2]:.2g} s)"
            )
    return None


def _axis(sc: StudyScene, ref_results: list[dict]) -> int | None:
    """The compared component: the bundled scene's, else the reference's largest mean
    ``|u|`` (``None``: no reference solved)."""
    if sc.params.get("component") is not None:
        return int(sc.params["component"])
    us = [np.abs(r["u"]) for r in ref_results if r.get("status") == "ok" and "u" in r]
    return int(np.argmax(np.mean(us, axis=0))) if us else None


def _error(r: dict, ref: dict, axis: int | None) -> float | None:
    """A result's relative error against its reference (``None``: either did not solve)."""
    if axis is None or r.get("status") != "ok" or ref.get("status") != "ok":
        return None
    value = ref["u"][axis]
    return float(abs(r["u"][axis] / value - 1.0)) if value else None


# -- the rows, the references and the answers -------------------------------------------


def result_frame(cases: list[dict[str, Any]], results: list[dict[str, Any]]) -> pd.DataFrame:
    """One row per case: scene, method, nu, level factor, status, probe displacement,
    seconds, tets."""
    rows = []
    for c, r in zip(cases, results, strict=True):
        u = r.get("u", [np.nan] * 3)
        rows.append({"scene": c["scene"], "method": c["method"], "nu": c["nu"],
                     "factor": c["factor"], "tets": r.get("tets"), "status": r["status"],
                     "load": r.get("load", np.nan), "ux": u[0], "uy": u[1], "uz": u[2],
                     "seconds": r.get("seconds", np.nan), "message": r.get("message", ""),
                     "component": c.get("component")})  # fmt: skip
    return pd.DataFrame(rows)


def deflection_component(g: pd.DataFrame) -> int:
    """The compared component of one scene: its ``component`` (a bundled scene's), else
    the axis of the largest mean ``|u|`` of the reference on the finest level."""
    given = g.component.dropna()
    if len(given):
        return int(given.iloc[0])
    ref = g[(g.method == REFERENCE) & (g.factor == g.factor.max()) & (g.status == "ok")]
    src = ref if len(ref) else g[g.status == "ok"]
    if src.empty:
        return 0
    return int(np.argmax(np.abs(src[["ux", "uy", "uz"]].to_numpy()).mean(axis=0)))


def with_errors(df: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The rows with ``deflection``, ``error`` (relative, against the reference of their
    scene and nu) and ``reference`` (the row is the reference); and the references: one row
    per (scene, nu) with the finest-level value, the Richardson limit and observed order.
    """
    out, refs = [], []
    for scene, g in df.groupby("scene", sort=False):
        g = g.copy()
        k = deflection_component(g)
        g["deflection"] = g[f"u{AXES[k]}"]
        g["axis"] = AXES[k]
        finest = g.factor.max()
        g["reference"] = (g.method == REFERENCE) & (g.factor == finest)
        for nu, gn in g.groupby("nu", sort=True):
            p2 = gn[(gn.method == REFERENCE) & (gn.status == "ok")].sort_values("factor")
            top = p2[p2.factor == finest]
            value = float(top.deflection.iloc[0]) if len(top) else np.nan
            limit, order = (np.nan, np.nan)
            if len(p2) >= 3:
                h = 1.0 / p2.factor.to_numpy(float)[-3:]
                limit, order = richardson_limit(h, p2.deflection.to_numpy(float)[-3:])
            refs.append(
                {
                    "scene": scene,
                    "nu": nu,
                    "axis": AXES[k],
                    "reference": value,
                    "tets": int(top.tets.iloc[0]) if len(top) else np.nan,
                    "richardson": limit,
                    "observed order": order,
                    "extrapolation shift": abs(limit / value - 1.0) if value else np.nan,
                }
            )
            g.loc[gn.index, "ref_value"] = value
        g["error"] = np.abs(g.deflection / g.ref_value - 1.0)
        g.loc[g.status != "ok", "error"] = np.nan
        out.append(g)
    return pd.concat(out, ignore_index=True), pd.DataFrame(refs)


def cheapest(g: pd.DataFrame, tolerance: float = TOLERANCE) -> pd.Series | None:
    """The cheapest row of ``g`` (one scene and nu) within ``tolerance`` of the reference.

    Candidates: solved (``ok``) rows other than the reference itself, with a relative
    error at most ``tolerance``; the cheapest has the smallest ``seconds`` (a tie: the
    smaller error). ``None`` when no row qualifies.
    """
    ok = g[(g.status == "ok") & ~g.reference.astype(bool) & (g.error <= tolerance)]
    if ok.empty:
        return None
    return ok.sort_values(["seconds", "error"]).iloc[0]


def answer_frame(df: pd.DataFrame, tolerance: float = TOLERANCE) -> pd.DataFrame:
    """Per (scene, nu): the cheapest method within ``tolerance``, its level, error and time,
    the reference's time, and the locked methods (every level more than ``tolerance`` off)."""
    rows = []
    for (scene, nu), g in df.groupby(["scene", "nu"], sort=False):
        win = cheapest(g, tolerance)
        ref = g[g.reference.astype(bool)]
        close = g[(g.status == "ok") & (g.error <= tolerance)].method.unique()
        unrun = g[g.status == "skipped"].method.unique()
        lin = cheapest(g[g.method.isin(LINEAR_TETS)], tolerance)
        row = {"scene": scene, "nu": nu}
        for x, tag in ((win, ""), (lin, " (linear)")):
            row["cheapest within tolerance" if not tag else "cheapest on linear tets"] = (
                "none" if x is None else x.method
            )
            for key in ("tets", "error", "seconds"):
                row[f"its {key}{tag}"] = np.nan if x is None else x[key]
        row["reference seconds"] = ref.seconds.iloc[0] if len(ref) else np.nan
        row["never within tolerance"] = (
            ", ".join(m for m in g.method.unique() if m not in close and m not in unrun) or "none"
        )
        row["not run on every level"] = ", ".join(m for m in unrun if m not in close) or "none"
        rows.append(row)
    return pd.DataFrame(rows)
