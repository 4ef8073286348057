"""Study ``speed_accuracy``: wall time against error, one point per method, level and setting.

Each scene is refined by the settings' factors (:mod:`studies.study_convergence.levels`).
Every point is one timed solve from the scene to the answer, its error measured against P2
with the scene's law on the reference level: the relative error of the scene's probe
displacement (the probe of its closed-form reference, e.g. the cantilever's tip, else its
first probe) or, without probes, the relative L2 error at the level-1 vertices; beside it
:data:`~.cases.SAME`, the error against the ``P1-NH`` static point of the same level (for
XPBD its substep error). A method is a model and a solution method (:mod:`.cases`): static
Newton, implicit pseudo-time stepping and explicit dynamic relaxation of ``spring-energy``;
static and explicit ``spring-exact``; the static FEM that apply; the explicit P1 FEM; the
plug-in models (a point per entry of a plug-in's sweep of its own settings, ``xpbd 20x2
static``). The Pareto points are those no other point beats in both time and error, among
all and per model (:mod:`.figures`). A separate case measures on each level the cost of one
explicit step of the spring model and of the explicit P1 FEM (both in one run). Timings are
noisy on a shared machine: they appear in tables and findings, never in the headline.

Bundled: the cantilever bar on ``[10, 1, 1]`` hexahedra refined by 1, 2, 4 (reference 6);
``--scene FILE`` runs it on the user's scene.

Examples
--------
>>> Settings.quick().levels, Settings.quick().reference
((1, 2), 4)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from springfem.errors import SolverError
from springfem.files import safe_filename

from .. import metrics, models
from ..analytic import reference
from ..registry import StudyContext, StudyOutput, Table, study
from ..scenes import StudyScene, require
from ..study_convergence.levels import level_label, select_levels
from ..tables import write_table
from .cases import (
    EXACT,
    EXPLICIT_FEM,
    L2,
    SAME,
    SPRING,
    STEP_COUNT,
    STEP_REPEATS,
    Settings,
    bundled_scenes,
    explicit_fem_refusal,
    method_name,
    model_of,
    pareto_front,
    point_case,
    point_work,
    points,
    reference_model,
    step_cost_case,
    step_cost_work,
)
from .figures import pareto_figure

__all__ = ["SAME", "Settings", "bundled_scenes", "measure", "pareto_front", "point_work",
           "points_frame", "report_findings", "run"]  # fmt: skip

#: The explicit setting the spring model and the explicit FEM are compared at, if both ran it.
COMPARED_SETTING = "tol 1e-06, dt = 0.5 dt_crit"


@study("speed_accuracy", Settings, bundled_scenes, serial=True)
def run(ctx: StudyContext, scenes: list[StudyScene], settings: Settings) -> StudyOutput:
    """Time and error of every model at each level; the Pareto front."""
    require(scenes, "speed-accuracy")
    out = StudyOutput(ctx.name, "")
    for s in scenes:
        suffix = "" if len(scenes) == 1 else f"_{safe_filename(s.label)}"
        scene = s.build()
        wanted = sorted({*settings.levels, settings.reference})
        kept, notes = select_levels(s.table, scene.mesh.n_tets, wanted, settings.max_tets)
        levels = [k for k in settings.levels if k in kept]
        ref_level = settings.reference if settings.reference in kept else max(kept)
        ref_model = reference_model(scene.material.law)
        ref_text = f"{method_name(ref_model, 'static')} on {level_label(s.table, ref_level)}"
        ref_case = point_case(s, ref_model, "static", ref_level, {})
        ref = ctx.cache.run([ref_case], point_work, ctx.progress, "reference")[0]
        if ref["status"] != "ok":
            raise SolverError(f"the reference {ref_text} failed: {ref['message']}")
        cases = points(s, scene, levels, settings)
        how = measure(s, ref)
        df = points_frame(s, cases, ctx.cache.run(cases, point_work, ctx.progress, "points"),
                          ref, how)  # fmt: skip
        sdf = steps = None
        if explicit_fem_refusal(scene) is None:
            n = scene.mesh.n_tets
            step_cases = [step_cost_case(s, k, n * k**3) for k in levels]
            steps = ctx.cache.run(step_cases, step_cost_work, ctx.progress, "step cost")
            sdf = step_frame(s, levels, steps)
        finest = level_label(s.table, levels[-1])
        findings, headline, front = report_findings(
            df, steps[-1] if steps else None, how, finest, s.label, settings.max_error, cases
        )
        if notes:
            findings.insert(0, f"{s.label}: {'; '.join(notes)}.")
        out.findings += findings
        out.tables += write_tables(ctx, s, df, sdf, ref, ref_text, how, suffix)
        ref_seconds = float(ref.get("cpu_seconds", ref["seconds"]))
        out.figures.append(
            pareto_figure(ctx, df, how.column, ref_text, front, s.label, suffix, ref_seconds)
        )
        out.headline.update({f"{k}{suffix}": v for k, v in headline.items()})
    out.title = f"Speed against accuracy ({', '.join(s.label for s in scenes)})"
    return out


def setting_label(solution: str, setting: dict) -> str:
    """A point's setting in the tables (empty for a static solve).

    Examples
    --------
    >>> setting_label("explicit", {"tol": 1e-6, "dt_safety": 0.5})
    'tol 1e-06, dt = 0.5 dt_crit'
    >>> setting_label("static", {"model": {"substeps": 20, "iterations": 2}})
    'substeps 20, iterations 2'
    """
    if setting.get("model"):
        return ", ".join(f"{k} {v}" for k, v in setting["model"].items())
    if solution == "implicit":
        return f"dt = {setting['dt_factor']:g} dt_crit"
    if "dt_safety" in setting:
        return f"tol {setting['tol']:g}, dt = {setting['dt_safety']:g} dt_crit"
    return ""


@dataclass(frozen=True)
class Measure:
    """What a scene's points are measured by: a probe, or the level-1 field.

    Attributes
    ----------
    probe
        The probe, or ``None`` (L2 at the level-1 vertices).
    analytic
        The probe's closed-form ``(component, value, source)``, if the scene has one.
    """

    probe: str | None
    analytic: tuple[int, float, str] | None = None

    @property
    def column(self) -> str:
        return f"{self.probe}_error" if self.probe else L2

    @property
    def key(self) -> str:
        """The headline keys' prefix (``tip_error``, ``l2_error``)."""
        return f"{self.probe}_error" if self.probe else "l2_error"


def measure(s: StudyScene, ref: dict) -> Measure:
    """The measure of a scene's points (see the module docstring)."""
    hook = reference(s, None)
    if hook is not None:
        probe, component, value, source = hook
        return Measure(probe, (component, value, source))
    return Measure(next(iter(ref["probes"]), None))


def _relative(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def points_frame(
    s: StudyScene, cases: list[dict], results: list[dict], ref: dict, how: Measure
) -> pd.DataFrame:
    """One row per point: method, level, setting, status, CPU and wall time, errors against
    the reference (and the probe over its closed form), steps, message, on the Pareto front.
    """
    u_ref = np.asarray(ref["u"], float)
    same = {
        c["factor"]: np.asarray(r["u"], float)
        for c, r in zip(cases, results, strict=True)
        if (c["model"], c["solution"]) == (EXPLICIT_FEM, "static") and r["status"] == "ok"
    }
    rows = []
    for c, r in zip(cases, results, strict=True):
        ok = r["status"] == "ok"
        row = {"method": method_name(c["model"], c["solution"], c["setting"]),
               "factor": c["factor"], "mesh": level_label(s.table, c["factor"]),
               "tets": r["tets"], "setting": setting_label(c["solution"], c["setting"]),
               "status": r["status"], "seconds": r["cpu_seconds"],
               "wall_seconds": r["seconds"]}  # fmt: skip
        probe = r["probes"][how.probe] if ok and how.probe else None
        if how.probe is not None:
            row[how.column] = _relative(probe, ref["probes"][how.probe]) if ok else np.nan
        if how.analytic is not None:
            component, value, source = how.analytic
            row[f"{how.probe} / {source}"] = probe[component] / value if ok else np.nan
        row[L2] = metrics.relative_l2_error(np.asarray(r["u"], float), u_ref) if ok else np.nan
        if same:
            own = same.get(c["factor"]) if ok else None
            u = np.asarray(r["u"], float) if own is not None else None
            row[SAME] = np.nan if u is None else metrics.relative_l2_error(u, own)
        row["steps"] = r.get("steps", np.nan)
        row["message"] = r.get("message", "")
        rows.append(row)
    df = pd.DataFrame(rows)
    ok = df["status"] == "ok"
    df["pareto"] = False
    df.loc[ok, "pareto"] = pareto_front(
        df.loc[ok, "seconds"].to_numpy(), df.loc[ok, how.column].to_numpy()
    )
    return df


def step_frame(s: StudyScene, factors: list[int], steps: list[dict]) -> pd.DataFrame:
    """One row per level: the cost of one explicit step, spring model and explicit P1 FEM
    (``steps``: the levels' :func:`~.cases.step_cost_work` results).
    """
    a, b = method_name(SPRING, "explicit"), method_name(EXPLICIT_FEM, "explicit")
    return pd.DataFrame([
        {"mesh": level_label(s.table, k), "tets": r["tets"],
         f"{a} ms/step": 1e3 * r[f"{SPRING}_wall"], f"{b} ms/step": 1e3 * r[f"{EXPLICIT_FEM}_wall"],
         "ratio (wall)": r["ratio_wall"], f"{a} CPU ms/step": 1e3 * r[f"{SPRING}_cpu"],
         f"{b} CPU ms/step": 1e3 * r[f"{EXPLICIT_FEM}_cpu"], "ratio (CPU)": r["ratio_cpu"]}
        for k, r in zip(factors, steps, strict=True)
    ])  # fmt: skip


def write_tables(
    ctx: StudyContext, s: StudyScene, df: pd.DataFrame, sdf: pd.DataFrame | None, ref: dict,
    ref_text: str, how: Measure, suffix: str = "",
) -> list[Table]:  # fmt: skip
    """Write the points and step-cost tables (``sdf`` ``None``: no step costs) and the
    failures, if any; ``ref_text`` names the reference (method and level).
    """
    show = df.drop(columns=["message"]).copy()
    if how.probe is not None:
        show[f"{how.column} %"] = 100 * show.pop(how.column)
    against = f"{how.probe} displacement" if how.probe else "field at the level-1 vertices"
    context = ""
    if how.analytic is not None:
        component, value, source = how.analytic
        ratio = ref["probes"][how.probe][component] / value
        context = f"; its {how.probe} is {ratio:.4f} × {source}"
    tables = [
        ctx.table(show, f"points{suffix}",
            f"{s.label}: every (method, level, setting) point: CPU time (`seconds`) and wall "
            "time from the scene to the answer (model build and time-step estimate included; "
            "the solves are serial, so CPU time is the wall time of an idle machine, while a "
            "shared machine's wall times vary), relative error of the "
            f"{against} against {ref_text} ({ref['tets']} tets{context}), status, "
            "explicit/implicit steps, and whether the point is on the Pareto front.")
    ]  # fmt: skip
    if sdf is not None:
        tables.append(ctx.table(sdf, f"step_cost{suffix}",
            "Cost of one explicit step (forces + update through the same solver loop), "
            "spring model vs explicit P1 neo-Hookean FEM on the same mesh: medians of "
            f"{STEP_REPEATS} alternating repeats of {STEP_COUNT}-500 steps; wall and CPU "
            "(process) time."))  # fmt: skip
    failed = df[df["status"] != "ok"]
    if len(failed):
        write_table(failed[["method", "mesh", "setting", "status", "message"]],
                    ctx.path(f"failures{suffix}"))  # fmt: skip
    return tables


def report_findings(
    df: pd.DataFrame, steps: dict | None, how: Measure, finest: str, label: str,
    tolerance: float = 0.05, cases: list[dict] | None = None,
) -> tuple[list[str], dict[str, float], str]:  # fmt: skip
    """The findings, the headline errors and the Pareto-front sentence of one scene.

    ``steps``: the step costs on the finest level (``None``: none); ``finest``: its label
    (``20x2x2``); ``cases``: the points' cases, row by row (for the plug-ins' sweeps,
    :func:`.sweeps.sweep_findings`). The headline holds the errors on the finest level (no
    timings, rounded to 4 decimals), ``<measure>_<model>_<solution>_<level>``, the sweeps'
    observed rates, and point and failure counts; the front's sentence is also the figure's
    caption.
    """
    err, key = how.column, how.key
    findings: list[str] = []
    headline: dict[str, float] = {}
    ok = df["status"] == "ok"
    good, failed = df[ok], df[~ok]
    if steps is not None:
        ratio, ratio_cpu = steps["ratio_wall"], steps["ratio_cpu"]
        findings.append(
            f"One explicit step of {SPRING} costs {ratio_cpu:.2f}x one step of the explicit "
            f"P1 neo-Hookean FEM on the same {finest} mesh ({steps['tets']} tets; CPU time, "
            f"median of {STEP_REPEATS} alternating repeats in one run; wall-clock ratio "
            f"{ratio:.2f}x on this shared machine): the spring model is "
            + ("slower per step." if ratio_cpu > 1 else "cheaper per step.")
        )

    def best(model: str, solution: str, mesh: str = finest):
        g = good[(good["method"] == method_name(model, solution)) & (good["mesh"] == mesh)]
        return g.sort_values(err).iloc[0] if len(g) else None

    def put(model: str, solution: str, row) -> None:
        headline[f"{key}_{model}_{solution}_{finest}"] = round(float(row[err]), 4)

    def pct(row, digits: int = 1) -> str:
        return f"{100 * row[err]:.{digits}f}%"

    sp, p1, p2 = best(SPRING, "static"), best("P1", "static"), best("P2", "static")
    if sp is not None and p1 is not None and p2 is not None:
        findings.append(
            f"On {finest} {SPRING} is {pct(sp)} off the reference (static Newton, "
            f"{sp['seconds']:.2f} s), P1 on the same mesh {pct(p1)} ({p1['seconds']:.2f} s) "
            f"and P2 {pct(p2, 2)} ({p2['seconds']:.2f} s)."
        )
        for m, row in ((SPRING, sp), ("P1", p1), ("P2", p2)):
            put(m, "static", row)
    se = good[(good["method"] == method_name(SPRING, "explicit")) & (good["mesh"] == finest)]
    fe = good[(good["method"] == method_name(EXPLICIT_FEM, "explicit")) & (good["mesh"] == finest)]
    common = sorted(set(se["setting"]) & set(fe["setting"]))
    if common:
        st = COMPARED_SETTING if COMPARED_SETTING in common else common[-1]
        a = se[se["setting"] == st].iloc[0]
        b = fe[fe["setting"] == st].iloc[0]
        findings.append(
            f"To rest by dynamic relaxation ({st}) on {finest}: {SPRING} {a['seconds']:.2f} s "
            f"in {int(a['steps'])} steps (error {pct(a)}), the explicit P1 FEM "
            f"{b['seconds']:.2f} s in {int(b['steps'])} steps (error {pct(b)}, the P1 static "
            "answer to the solver tolerance)."
        )
        put(EXPLICIT_FEM, "explicit", b)
        nh = best(EXPLICIT_FEM, "static")
        if sp is not None and nh is not None:
            findings.append(
                "For this static problem dynamic relaxation is the slow way to the answer: "
                f"{a['seconds'] / sp['seconds']:.0f}x {SPRING} static Newton and "
                f"{b['seconds'] / nh['seconds']:.0f}x {EXPLICIT_FEM} static Newton on "
                f"{finest}; explicit stepping pays off only when the dynamics themselves are "
                "wanted."
            )
    on_front = good[good["pareto"]]
    fam = ", ".join(
        f"{m} ({', '.join(on_front[on_front['method'] == m]['mesh'])})"
        for m in on_front["method"].unique()
    )
    n_spring_front = int(on_front["method"].str.startswith("spring").sum())
    front_text = f"{label}: Pareto front ({len(on_front)} of {len(good)} points): {fam}; " + (
        f"{n_spring_front} spring-model point(s) on it."
        if n_spring_front
        else "no spring-model point is on it: for every spring point some FEM point is both "
        "faster and more accurate."
    )
    findings.append(front_text)
    findings.append(cheapest_sentence(good, err, tolerance))
    findings.append(per_model_sentence(good, err, tolerance))
    for _, r in failed.iterrows():
        findings.append(
            f"{r['method']} on {r['mesh']} ({r['setting']}) {r['status']}: {r['message'][:140]}"
        )
    findings += peer_findings(good, err, put, pct, finest, sp, p1)
    if cases is not None:
        lines, rates = sweep_findings(df, cases, err, finest)
        findings += lines
        headline.update(rates)
    exact = df["method"].str.startswith(f"{EXACT} ")
    headline["n_points"] = float((~exact).sum())
    headline["n_failed"] = float((~ok & ~exact).sum())
    headline["n_points_exact"] = float(exact.sum())
    ex = best(EXACT, "static")
    if ex is not None:
        put(EXACT, "static", ex)
        if sp is not None and p1 is not None:
            findings.insert(
                2 if steps is not None else 1,
                f"{EXACT} (axis-volume + energy torsion + exact calibration) on {finest}: "
                f"{pct(ex)} off the reference (static Newton, {ex['seconds']:.2f} s), i.e. "
                f"P1's error on the same mesh ({pct(p1)}), where {SPRING} is {pct(sp)} off. "
                "A smaller error of the specification's element on a coarse mesh is its extra "
                "softness cancelling P1's bending stiffness (accuracy study), not accuracy; "
                "the exact element is P1 at the spring model's cost, so it converges where "
                "the specification's element does not.",
            )
    return findings, headline, front_text


def peer_findings(good, err: str, put, pct, finest: str, sp, p1) -> list[str]:
    """A sentence per plug-in model (``studies.models.plugins``) on the finest level: its
    most accurate static point (of its sweep, if it has one) and explicit point, error and
    time, beside the spring model's and P1's."""

    out = []
    fine = good[good["mesh"] == finest]
    for name in dict.fromkeys(model_of(m) for m in good["method"]):
        if name not in {m.name for m in models.sync_plugins()}:
            continue
        own = fine[fine["method"].map(model_of) == name]
        st, ex = (most_accurate(own, err, suffix) for suffix in (" static", " explicit"))
        if st is None:
            continue
        put(name, "static", st)
        text = f"{name} on {finest}: {pct(st)} off the reference ({st['method']}, "
        text += f"{st['seconds']:.2f} s"
        if ex is not None:
            put(name, "explicit", ex)
            text += f"; to rest explicitly {pct(ex)}, {ex['seconds']:.2f} s"
        text += ")"
        if p1 is not None:
            text += f"; P1 {pct(p1)} ({p1['seconds']:.2f} s)"
        if sp is not None:
            text += f", {SPRING} {pct(sp)} ({sp['seconds']:.2f} s)"
        out.append(text + ".")
    return out


def cheapest_sentence(good: pd.DataFrame, column: str, tolerance: float) -> str:
    """The cheapest point (CPU time) whose error ``column`` is at most ``tolerance``, and the
    cheapest spring-model point within it, in a sentence.

    Examples
    --------
    >>> df = pd.DataFrame({"method": ["P1 static", "spring-energy static", "P2 static"],
    ...     "mesh": ["10x1x1", "20x2x2", "10x1x1"], "seconds": [0.1, 0.5, 0.3],
    ...     "err": [0.2, 0.04, 0.01]})
    >>> overall, spring = cheapest_sentence(df, "err", 0.05).split("; ")
    >>> overall
    'Within 5% of the reference the cheapest point is P2 static on 10x1x1 (0.30 s, 1.0% off)'
    >>> spring[spring.index("spring-energy"):]
    'spring-energy static on 20x2x2 (0.50 s, 4.0% off), 1.7x its time.'
    """

    def point(r) -> str:
        return f"{r['method']} on {r['mesh']} ({r['seconds']:.2f} s, {100 * r[column]:.1f}% off)"

    within = good[good[column] <= tolerance].sort_values("seconds")
    head = f"Within {tolerance:.0%} of the reference"
    if within.empty:
        return f"{head} no point qualifies: every method's error is larger on these levels."
    first = within.iloc[0]
    text = f"{head} the cheapest point is {point(first)}"
    if str(first["method"]).startswith("spring"):
        return text + "; it is a spring-model point."
    spring = within[within["method"].str.startswith("spring")]
    if spring.empty:
        return text + "; no spring-model point is within it."
    sp = spring.iloc[0]
    ratio = sp["seconds"] / first["seconds"]
    return text + f"; the cheapest spring-model point is {point(sp)}, {ratio:.1f}x its time."


def most_accurate(df: pd.DataFrame, err: str, suffix: str = ""):
    """The row of least error ``err`` among methods ending in ``suffix`` (``None``: none)."""
    g = df[df["method"].str.endswith(suffix)] if suffix else df
    return g.sort_values(err).iloc[0] if len(g) else None


def per_model_sentence(good: pd.DataFrame, err: str, tolerance: float) -> str:
    """Per model, its cheapest point (CPU time) within ``tolerance``, or, when none is, its
    most accurate point (the cheapest within 1 % of its least error), in a sentence.

    Examples
    --------
    >>> df = pd.DataFrame({"method": ["P1 static", "xpbd 20x2 static", "xpbd 40x2 static"],
    ...     "mesh": ["10x1x1", "10x1x1", "10x1x1"], "seconds": [0.1, 0.5, 0.9],
    ...     "err": [0.2, 0.04, 0.03]})
    >>> within, outside = per_model_sentence(df, "err", 0.05).split(". ")
    >>> within[within.index("xpbd:"):]
    'xpbd: xpbd 20x2 static on 10x1x1 (0.50 s, 4.0% off)'
    >>> outside
    'None within it: P1 (best P1 static on 10x1x1 (0.10 s, 20.0% off)).'
    """

    def point(r) -> str:
        return f"{r['method']} on {r['mesh']} ({r['seconds']:.2f} s, {100 * r[err]:.1f}% off)"

    parts, outside = [], []
    for name, g in good.groupby(good["method"].map(model_of), sort=False):
        within = g[g[err] <= tolerance].sort_values("seconds")
        if len(within):
            parts.append(f"{name}: {point(within.iloc[0])}")
        else:  # its most accurate, the cheapest of those within 1 % of that error
            near = g[g[err] <= 1.01 * g[err].min()].sort_values("seconds")
            outside.append(f"{name} (best {point(near.iloc[0])})")
    text = f"Per model, its cheapest point within {tolerance:.0%} of the reference: "
    text += "; ".join(parts) if parts else "none"
    if outside:
        text += f". None within it: {'; '.join(outside)}"
    return text + "."


def observed_rate(values, errors) -> float:
    """``p`` of ``error ~ value**-p`` (least squares in log-log; NaN below two points).

    Examples
    --------
    >>> round(observed_rate([10, 20, 40], [4e-2, 1e-2, 2.5e-3]), 6)
    2.0
    """
    v, e = np.asarray(values, float), np.asarray(errors, float)
    keep = np.isfinite(e) & (e > 0)
    if np.unique(v[keep]).size < 2:
        return float("nan")
    return float(-np.polyfit(np.log(v[keep]), np.log(e[keep]), 1)[0])


def sweep_findings(
    df: pd.DataFrame, cases: list[dict], err: str, finest: str
) -> tuple[list[str], dict[str, float]]:
    """For each plug-in sweep and each of its settings that varies (the others at the
    plug-in's defaults), on the finest level where it varies (``finest`` first): the errors
    by setting and the observed rate, a sentence each, and headline keys
    ``rate_<model>_<setting>_<level>``."""

    own = [c["setting"].get("model") or {} for c in cases]
    ok = df["status"] == "ok"
    column = SAME if SAME in df and df.loc[ok, SAME].notna().any() else err
    against = "P1-NH on the same mesh" if column == SAME else "the reference"
    meshes = df.sort_values("tets", ascending=False, kind="stable")["mesh"].unique().tolist()
    meshes = sorted(meshes, key=lambda m: m != finest)  # stable: finest, then by size
    lines, rates = [], {}
    for name in dict.fromkeys(c["model"] for c, o in zip(cases, own, strict=True) if o):
        defaults = models.get(name).settings
        swept = [i for i, c in enumerate(cases) if c["model"] == name and own[i] and ok.iloc[i]]
        for key in dict.fromkeys(k for i in swept for k in own[i]):
            for mesh in meshes:
                series = sorted(
                    (own[i][key], float(df[column].iloc[i]))
                    for i in swept
                    if df["mesh"].iloc[i] == mesh
                    and all(v == defaults.get(k) for k, v in own[i].items() if k != key)
                )
                if len({v for v, _ in series}) >= 2:
                    break
            else:
                continue
            rate = observed_rate(*zip(*series, strict=True))
            fixed = ", ".join(f"{k} {v}" for k, v in defaults.items() if k in own[swept[0]]
                              and k != key)  # fmt: skip
            errors = ", ".join(f"{v}: {100 * e:.3g}%" for v, e in series)
            lines.append(
                f"{name} on {mesh}, error against {against} by {key} ({fixed}): {errors}; "
                f"observed rate {rate:.2f} (error ~ {key}^-p, least squares)."
            )
            rates[f"rate_{name}_{key}_{mesh}"] = round(rate, 4)
    return lines, rates
