"""Study ``locking``: which method is cheapest within 5 % near incompressibility.

The probe deflection against the Poisson ratio ν = 0.3, 0.45, 0.49, 0.499, 0.4999 on three
mesh levels, for every method of :data:`~.cases.METHODS`:

- FEM on the scene's own law: P1 (displacement), P1 with nodal-averaged volume
  (``[fem] formulation = "nodal-volume"``, Bonet & Burton 1998, with its default
  stabilisation), P1 with nodal-averaged strain where the FEM offers it, MINI (P1-bubble /
  P1), P2 (displacement) and P2/P1 Taylor–Hood (``mixed``);
- the spring model: the specification's element (``spring-spec``), the exact element
  (``spring-exact``), the exact element on nodal volumes (``spring-nodal-volume``) and with
  nodal strain and nodal volume at their default stabilisations (``spring-stabilised``).

The shear modulus is held and ν sets the bulk modulus (:func:`~.cases.with_nu`; a tissue
law: its volumetric penalty). The reference at each ν is the P2/P1 Taylor–Hood deflection on
the finest level; a method's error is its relative difference from it and its cost the wall
time of its static solve. The answer per ν is the cheapest method and level within 5 % of
the reference (the reference itself excluded): "none" when none is. A solve is capped
(:attr:`~.cases.Settings.max_time`); one that needs longer is recorded as stopped. A finer
level that cannot change the answer is not run (a ``skipped`` row with the reason,
:attr:`~.cases.Settings.skip_costlier`): above all displacement P2 near incompressibility,
which locks there and needs hundreds of Newton iterations, while P2/P1 on a coarser mesh is
more accurate and faster.

The bundled run: Cook's membrane (neo-Hookean, shear load, Cook's μ = 80.19 kPa; deflection
``u_y`` of the corner) and Land's beam (Guccione, follower pressure; ``u_z`` of the tip).
``springfem study locking --scene FILE`` runs the same on a user's scene (an isotropic or
tissue law and a ``[[probe]]``; the deflection is its first probe's dominant component).

The study is split into :mod:`.cases` (methods, settings, ν, one timed solve), :mod:`.tables`
(rows, references, the cheapest method), :mod:`.figures` and :mod:`.findings`.

Examples
--------
>>> [s.label for s in bundled_scenes(Settings.quick())]
['cook-membrane', 'land-beam']
"""

from __future__ import annotations

import numpy as np

from ..registry import StudyContext, StudyOutput, study
from ..scenes import StudyScene, require
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
from .findings import HEADLINE_METHODS, report_findings
from .tables import (
    answer_frame,
    answer_table,
    cases_table,
    reference_table,
    result_frame,
    with_errors,
)

__all__ = ["Settings", "bundled_scenes", "run"]


@study("locking", Settings, bundled_scenes)
def run(ctx: StudyContext, scenes: list[StudyScene], settings: Settings) -> StudyOutput:
    """Error and cost of each locking-free method per Poisson ratio."""
    require(scenes, ctx.name)
    if ctx.cache.budget.seconds is not None and settings.timed:
        # within a budget each solve runs once: a warm-up solve and repeats would take a
        # first solve's time again of every method (the findings say so)
        from dataclasses import replace

        settings = replace(settings, timed=False)
    laws, notes, levels = {}, [], []
    for sc in scenes:
        laws[sc.label] = str(sc.table.get("material", {}).get("law", "linear"))
        factors, note = affordable_levels(ctx, sc, settings)
        notes += note
        levels.append((sc, factors))
    all_cases, all_results = _staged(ctx, levels, settings)
    df, refs = with_errors(result_frame(all_cases, all_results))
    answers = answer_frame(df)
    findings, headline = report_findings(df, refs, answers, laws, settings.max_time)
    if not settings.timed:
        notes.append("Within the study's budget every solve ran once: its time includes a "
                     "method's first-solve costs (imports, loading compiled kernels).")  # fmt: skip
    names = ", ".join(sc.label for sc in scenes)
    return StudyOutput(
        name=ctx.name,
        title=f"Locking: the cheapest method within 5 % near incompressibility ({names})",
        findings=notes + findings,
        tables=[answer_table(ctx, answers), cases_table(ctx, df), reference_table(ctx, refs)],
        figures=[deflection_figure(ctx, df), error_cost_figure(ctx, df)],
        headline=headline,
    )


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
    ``s.skip_costlier`` (on the same kind of tets, linear: :data:`~.cases.LINEAR_TETS`, or
    quadratic; ``best``: the cheapest there within :data:`~.cases.TOLERANCE` at this ν so
    far, ``(seconds, method, tets)``; ``last``: ``(method, error, seconds, tets)`` of the
    coarser level at this ν):

    - a method was within the tolerance in less than the case's predicted time: the case
      cannot be the cheapest;
    - on the coarser level a method was at least twice as accurate as the case's and no
      slower: the case's method is not expected to become the cheapest on a finer level
      (both converge; it is locking).

    (Not a rule: extrapolating a method's own error from two coarser levels. On the full
    report's beam at ν = 0.4999 the stabilised spring element went 66.7 %, 37.6 % and then
    3.1 %, where the same rate predicted 21 %: it would have removed an answer.)

    Neither applies to a headline method (:data:`~.findings.HEADLINE_METHODS`) at the
    highest ν: its finest level there is a headline number.

    (With ``s.prune`` a method within the tolerance does not run its own finer levels
    either: :func:`_staged`.)
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
