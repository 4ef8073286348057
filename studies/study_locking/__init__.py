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
(:attr:`~.cases.Settings.max_time`); one that needs longer is recorded as stopped.

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

from ..registry import StudyContext, StudyOutput, study_run
from ..scenes import StudyScene, require
from .cases import (
    COST_PER_DOF,
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
from .findings import report_findings
from .tables import (
    answer_frame,
    answer_table,
    cases_table,
    reference_table,
    result_frame,
    with_errors,
)

__all__ = ["Settings", "bundled_scenes", "run"]


@study_run(
    "locking",
    Settings,
    bundled_scenes,
    settings_doc="Poisson ratios, levels, methods, the solve cap.",
    returns=(
        "Findings, the table of every case, the references, the cheapest method "
        "per ν, the two figures, headline errors."
    ),
)
def run(ctx: StudyContext, scenes: list[StudyScene], settings: Settings) -> StudyOutput:
    require(scenes, ctx.name)
    if ctx.cache.budget.seconds is not None and settings.timed:
        # within a budget each solve runs once: a warm-up solve and repeats would take a
        # first solve's time again of every method (the findings say so)
        from dataclasses import replace

        settings = replace(settings, timed=False)
    all_cases, all_results, laws, notes = [], [], {}, []
    for sc in scenes:
        laws[sc.label] = str(sc.table.get("material", {}).get("law", "linear"))
        factors, note = affordable_levels(ctx, sc, settings)
        notes += note
        cs, rs = _staged(ctx, sc, settings, factors)
        all_cases += cs
        all_results += rs
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
    ctx: StudyContext, sc: StudyScene, s: Settings, factors: tuple[int, ...]
) -> tuple[list[dict], list[dict]]:
    """The cases and results of one scene: the references first (the finest level), then
    each level from the coarsest; with ``s.prune`` a method's level whose predicted time is
    over 1.5 × the cap is left out (a ``skipped`` row), and so are the finer levels of a
    method that is within :data:`~.cases.TOLERANCE` at that ν already."""
    from ..budget import skipped_result

    methods = scene_methods(sc, s)
    finest = factors[-1]
    run = dict(progress=ctx.progress, estimate=estimate, skippable=True, priors=COST_PER_DOF)
    with_ref = REFERENCE in methods
    ref_cases = [case_of(sc, s, REFERENCE, nu, finest) for nu in s.nus] if with_ref else []
    ref_res = ctx.cache.run(ref_cases, locking_case, desc=f"{sc.label} reference", **run)
    ref_res = [{**r, "tets": estimate(c)[2]} if r.get("status") == "skipped" else r
               for c, r in zip(ref_cases, ref_res, strict=True)]  # fmt: skip
    refs = {c["nu"]: r for c, r in zip(ref_cases, ref_res, strict=True)}
    axis = _axis(sc, ref_res)
    done: set[tuple[str, float]] = set()  # (method, nu) within the tolerance
    out_c, out_r = [], []
    for f in factors:
        todo, skipped = [], []
        for nu in s.nus:
            for m in methods:
                if m == REFERENCE and f == finest or (m, nu) in done:
                    continue
                c = case_of(sc, s, m, nu, f)
                kind, size, _ = estimate(c)
                first = f == factors[0] or not s.prune
                guess = None if first else ctx.cache.costs.predict(kind, size)
                if m != REFERENCE and guess is not None and guess > 1.5 * s.max_time:
                    skipped.append((c, skipped_result(
                        f"not run: predicted {guess:.3g} s, over the {s.max_time:g} s cap "
                        "of a solve")))  # fmt: skip
                else:
                    todo.append(c)
        res = ctx.cache.run(todo, locking_case, desc=f"{sc.label} level x{f}", **run)
        for c, r in [*zip(todo, res, strict=True), *skipped]:
            if r.get("status") == "skipped":
                r = {**r, "tets": estimate(c)[2]}  # the size it would have had
            out_c.append(c)
            out_r.append(r)
            ref = refs.get(c["nu"], {})
            if s.prune and _within(r, ref, axis):
                done.add((c["method"], c["nu"]))
    for c, r in zip(ref_cases, ref_res, strict=True):
        out_c.append(c)
        out_r.append(r)
    return out_c, out_r


def _axis(sc: StudyScene, ref_results: list[dict]) -> int | None:
    """The compared component: the bundled scene's, else the reference's largest mean
    ``|u|`` (``None``: no reference solved)."""
    if sc.params.get("component") is not None:
        return int(sc.params["component"])
    us = [np.abs(r["u"]) for r in ref_results if r.get("status") == "ok" and "u" in r]
    return int(np.argmax(np.mean(us, axis=0))) if us else None


def _within(r: dict, ref: dict, axis: int | None) -> bool:
    """Whether a result is within the tolerance of its reference."""
    if axis is None or r.get("status") != "ok" or ref.get("status") != "ok":
        return False
    value = ref["u"][axis]
    return bool(value and abs(r["u"][axis] / value - 1.0) <= TOLERANCE)
