"""The verdict on a scene: which model is good enough, and how fast is it against FEM?

:func:`verdict` runs every model of :mod:`studies.models` that applies to the scene against
its best reference and measures for each

- the error of its static solution against the reference (relative L2 over the vertices);
- the wall time of its static solve: the median of :data:`SOLVES` warm solves, interleaved
  (every model once per round, in a shuffled order, :func:`studies.timing.interleaved`),
  after a first solve that gives the solution and warms up imports, compiled kernels and
  solver set-up;
- for the models with an explicit form (the spring variants, the explicit P1 FEM), the cost
  of one explicit step (median of interleaved rounds, each of at least
  :data:`SAMPLE_SECONDS`) and the stable step ``2 / omega_max``,
  hence the cost of one simulated second, ``cost per step / stable step``;
- what it solves against the reference's law (``law vs reference``:
  :func:`studies.model_set.law_versus`): the same law, or a small-strain law or calibration
  of it, whose speed is not like for like.

The reference is the finest FEM of the scene's law: P2, neo-Hookean P2 at large strain, the
scene's own formulation for tissue; on a nearly incompressible scene of a hyperelastic law
P2/P1 mixed (``fem-P2-mixed``), and the locking-free methods are weighed too
(:mod:`studies.model_set`). It then names the cheapest model within the tolerance, for
static solves and for explicit dynamics separately, in at most two short sentences
(:func:`verdict_sentence`). A time budget caps each solve with the time left; a reference
that does not finish falls back to the next finest FEM among the models weighed, with a note.
Models whose options resolve to the same solve on this scene are solved once (a note says
which are the same).

Examples
--------
A block of transversely isotropic material in uniaxial stress (a uniform strain: P1 is
exact, and the exact spring element is P1's element at small strain):

>>> from studies.overrides import load_scene_with
>>> scene = load_scene_with("studies/scenes/stretch-cross.toml", ["mesh.divisions=[2, 2, 2]"])
>>> v = verdict(scene, tolerance=0.05, models=("spring-spec", "spring-exact", "P1", "P2"),
...             rounds=1, solves=1)
>>> v.reference, v.static_pick in ("spring-exact", "P1")
('P2', True)
>>> bool(v.table.set_index("model").at["spring-spec", "within tolerance"])  # calibration
False
"""

from __future__ import annotations

import contextlib
import io
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from reference_fem.options import FemOptions
from springfem.mechanics.limits import solve_limits
from springfem.scene import Scene

from . import fem_laws, metrics, model_set, models
from .compare import LARGE_STRAIN, max_principal_strain
from .timing import interleaved, median
from .verdict_rank import pct as _pct
from .verdict_rank import rank_by_error, ranking_line, same_mesh_line

#: Default tolerance: the largest relative L2 error a model may have to count.
TOLERANCE = 0.05
#: Explicit steps per timing of the step cost: at least this many, and as many as make the
#: cheapest model's sample last SAMPLE_SECONDS (at most MAX_STEPS).
STEPS = 20
SAMPLE_SECONDS = 0.05
MAX_STEPS = 2000
#: The same mesh's P1 of a reference's law: the model error of a P1-based fast model.
SAME_MESH_P1 = {"P2-NH": "P1-NH", "P2": "P1"}
#: Warm static solves per model whose median is its static time (interleaved rounds).
SOLVES = 3


@dataclass
class Verdict:
    """The outcome of :func:`verdict`.

    Attributes
    ----------
    scene
        The scene's name.
    tolerance
        The error tolerance.
    reference
        The reference model.
    table
        One row per model: status, error, its rank by error, static time, step cost, stable
        step, cost per simulated second, what it solves against the reference's law, and
        whether it is within the tolerance.
    static_pick, dynamic_pick
        The cheapest model within the tolerance for static solves (the reference when no
        other model within it is cheaper) and for explicit dynamics (``None``: none
        qualifies).
    sentence
        The answer in words (:func:`verdict_sentence`).
    ranking
        Every model by its error against the reference (:func:`ranking_line`; the table's
        ``rank`` column).
    notes
        What was skipped, merged or substituted, and why.
    """

    scene: str
    tolerance: float
    reference: str
    table: pd.DataFrame
    static_pick: str | None
    dynamic_pick: str | None
    sentence: str
    notes: list[str] = field(default_factory=list)
    ranking: str = ""


def candidate_models(scene: Scene) -> list[str]:
    """The primary models (:func:`studies.model_set.candidates`: :data:`~studies.models.PRIMARY`
    and the default plug-ins) that apply to ``scene``, and on a nearly incompressible scene
    the locking-free ones (:func:`studies.model_set.locking_free_models`).

    Parameters
    ----------
    scene
        The scene.

    Returns
    -------
    list of str
    """
    out = []
    for m in map(models.get, model_set.candidates()):
        if m.name == "fem" or m.applies(scene) is not None:
            continue
        if m.kind == "spring" and not _spring_builds(m, scene):
            continue
        out.append(m.name)
    return out + [n for n in model_set.locking_free_models(scene) if n not in out]


def _spring_builds(m: models.Model, scene: Scene) -> bool:
    """Whether the spring variant's options are valid for the scene's law (a stiffening
    needs a modulus the law gives, e.g.)."""
    try:
        opts = m.spring_options(scene)
    except (ValueError, TypeError):
        return False
    if opts.stiffening != "off" and opts.stiffening_modulus is None:
        return scene.material.law in ("guccione", "holzapfel-ogden")
    return True


def reference_model(scene: Scene, p1_strain: float) -> str:
    """The scene's best reference: P2/P1 mixed on a nearly incompressible hyperelastic
    scene (:func:`studies.model_set.mixed_reference`), else P2 of its law (neo-Hookean when
    it is or at large strain).

    Parameters
    ----------
    scene
        The scene.
    p1_strain
        The largest principal Green–Lagrange strain of its small-strain P1 solution.

    Returns
    -------
    str
    """
    mixed = model_set.mixed_reference(scene)
    if mixed is not None:
        return mixed
    if fem_laws.is_tissue(scene) or scene.material.law == "transverse-linear":
        return "P2"
    if scene.material.law == "neo-hookean" or p1_strain > LARGE_STRAIN:
        return "P2-NH"
    return "P2"


def _step_costs(scene: Scene, names: list[str], rounds: int) -> dict[str, tuple[float, float]]:
    """Per model with an explicit form: (seconds per explicit step, stable step)."""
    from springfem.mechanics import stable_time_step

    systems, dts = {}, {}
    for n in names:
        m = models.get(n)
        if m.kind == "fem" and (m.order == 2 or _formulation(scene, m) != "displacement"):
            continue  # the explicit FEM is P1 in the displacement formulation: not this model

        try:
            s = m.system(scene)
            dts[n] = stable_time_step(s)[0]
        except Exception:  # noqa: BLE001 - a model with no explicit form on this scene
            continue
        systems[n] = s
    if not systems:
        return {}

    def step(s, count):
        x, v = s.x0.copy(), np.zeros_like(s.x0)

        def run():
            for _ in range(count):
                s.forces(x, v)

        return run

    # enough steps per sample that one sample lasts SAMPLE_SECONDS: a shorter one measures
    # the machine's scheduling more than the model
    one = {}
    for n, s in systems.items():
        step(s, 1)()  # compiles
        t = time.perf_counter()
        step(s, 1)()
        one[n] = time.perf_counter() - t
    count = int(np.clip(SAMPLE_SECONDS / max(min(one.values()), 1e-9), STEPS, MAX_STEPS))
    samples = interleaved({n: step(s, count) for n, s in systems.items()}, rounds=rounds)
    return {n: (median(samples, n) / count, dts[n]) for n in systems}


def _formulation(scene: Scene, m: models.Model) -> str:
    """The ``[fem] formulation`` FEM model ``m`` solves ``scene`` with."""
    from reference_fem.options import FemOptions

    return FemOptions.of(m.fem_settings(scene)[0]).formulation


def verdict(
    scene: Scene,
    tolerance: float = TOLERANCE,
    budget: float | None = None,
    models: tuple[str, ...] | None = None,
    rounds: int = 5,
    log=None,
    solves: int = SOLVES,
) -> Verdict:
    """The verdict on ``scene`` (see the module docstring).

    Parameters
    ----------
    scene
        The scene.
    tolerance
        Largest relative L2 error against the reference that counts as good enough.
    budget
        Seconds for the whole verdict (``None``: no cap); each solve gets the time left,
        and the timed solves are cut to the rounds that fit in it (a note says so).
    models
        The models to weigh (default :func:`candidate_models`); the reference is added.
    rounds
        Interleaved rounds of the step-cost timing.
    log
        Called with one line per finished model.
    solves
        Warm solves per model whose median is its static time (:data:`SOLVES`; 0: the
        first, cold solve's time).

    Returns
    -------
    Verdict
    """
    from . import models as registry

    say = log or (lambda _line: None)
    t0 = time.perf_counter()
    notes: list[str] = list(scene.mesh.notes)
    names = list(models) if models is not None else candidate_models(scene)
    names = list(dict.fromkeys(registry.get(n).name for n in names))
    outcomes: dict[str, registry.Outcome] = {}

    def left() -> float | None:
        return None if budget is None else max(budget - (time.perf_counter() - t0), 1e-3)

    def run(name: str) -> registry.Outcome:
        if name in outcomes:
            return outcomes[name]
        if name in alias:
            outcomes[name] = run(alias[name])
            return outcomes[name]
        with solve_limits(max_time=left()):
            got = registry.run(scene, name)
        outcomes[name] = got
        say(f"  {name:<24} {got.status} in {got.seconds:.2f} s")
        return got

    alias: dict[str, str] = {}
    p1 = run("P1")
    strain = max_principal_strain(scene, p1.u) if p1.ok else float("nan")
    ref = reference_model(scene, strain)
    if ref not in names:
        names.append(ref)
    alias = model_set.same_solves(scene, names)
    for n, first in alias.items():
        notes.append(f"{n} is the same solve as {first} on this scene: solved once")
    locking_free = [n for n in model_set.locking_free_models(scene) if n in names]
    if locking_free:
        notes.append(model_set.locking_note(scene, locking_free, ref))
    notes += model_set.formulation_notes(scene, names)
    finite = ref != "P2" and not fem_laws.is_tissue(scene)  # P2, P1: a tissue law
    fallback = ("P2-NH", "P1-NH", "P2", "P1") if finite else ("P2", "P2-NH", "P1-NH", "P1")
    preference = [ref] + [n for n in fallback if n in names]
    for cand in dict.fromkeys(preference):
        if registry.get(cand).applies(scene) is not None:
            continue
        if run(cand).ok:
            if cand != ref:
                why = outcomes[ref].message if ref in outcomes else "not run"
                notes.append(f"the reference {ref} did not finish ({why}); {cand} stands in")
            ref = cand
            break
    else:
        ref = ""
        notes.append("no FEM reference finished: errors are not computed")
    for n in names:
        run(n)
    times = _static_times(scene, names, outcomes, alias, solves, left, notes)
    u_ref = outcomes[ref].u if ref else None
    ref_law = outcomes[ref].solution.result.law if ref else ""
    costs = _step_costs(scene, [n for n in names if outcomes[n].ok and n not in alias], rounds)
    costs.update({n: costs[first] for n, first in alias.items() if first in costs})
    rows = []
    for n in names:
        got = outcomes[n]
        err = (
            metrics.relative_l2_error(got.u, u_ref)
            if got.ok and u_ref is not None and n != ref
            else (0.0 if n == ref and got.ok else float("nan"))
        )
        step, dt = costs.get(n, (float("nan"), float("nan")))
        rows.append(
            {
                "model": n,
                "status": got.status,
                "rel L2 error": err,
                "static time (s)": times.get(n, float("nan")),
                "step cost (s)": step,
                "stable step (s)": dt,
                "cost per simulated s": step / dt if np.isfinite(step) and dt > 0 else np.nan,
                "law vs reference": model_set.law_versus(scene, n, ref_law) if ref else "",
                "within tolerance": bool(got.ok and np.isfinite(err) and err <= tolerance),
                "message": got.message[:160],
            }
        )
    table = pd.DataFrame(rows)
    p1 = SAME_MESH_P1.get(ref)
    # the model error of the linear-tet models: against the same mesh's P1 of the law
    if p1 in names and outcomes[p1].ok:
        u_p1 = outcomes[p1].u
        scene_order = FemOptions.of(scene).order
        quadratic = {
            n for n in names
            if (m := registry.get(n)).kind == "fem" and (m.order or scene_order) == 2
        }  # fmt: skip
        same = {n for n in names if alias.get(n, n) == alias.get(p1, p1)}  # p1's own solve
        table.insert(3, f"vs {p1} (same mesh)", [
            metrics.relative_l2_error(outcomes[n].u, u_p1)
            if outcomes[n].ok and n not in same and n not in quadratic
            else (0.0 if n in same else float("nan")) for n in names
        ])  # fmt: skip
    # the reference competes too (a model within the tolerance but dearer is no answer);
    # the rows that are the same solve as the reference are the reference
    same_as_ref = table["model"].map(lambda n: alias.get(n, n) == alias.get(ref, ref))
    ok = table[table["within tolerance"] & (~same_as_ref | (table["model"] == ref))]
    static_pick = _cheapest(ok, "static time (s)")
    dynamic_pick = _cheapest(ok, "cost per simulated s")
    sentence = verdict_sentence(table, ref, tolerance, static_pick, dynamic_pick)
    ranked = rank_by_error(table, ref, same_as_ref)
    table.insert(3, "rank", ranked)
    v = Verdict(scene.name, tolerance, ref, table, static_pick, dynamic_pick, sentence, notes)
    v.ranking = ranking_line(table, ref)
    if p1 in names and outcomes[p1].ok:
        v.ranking += " " + same_mesh_line(table, ref, p1, same_as_ref)
    return v


def _static_times(
    scene: Scene,
    names: list[str],
    outcomes: dict,
    alias: dict[str, str],
    solves: int,
    left,
    notes: list[str],
) -> dict[str, float]:
    """Static time per model: the median of ``solves`` interleaved warm solves (the first,
    cold solve's time when ``solves`` is 0 or the budget leaves no room for a round)."""
    timed = [n for n in names if n not in alias and outcomes[n].ok]
    first = {n: float(outcomes[n].seconds) for n in timed}
    rounds = solves
    budget_left = left()
    if budget_left is not None and timed:
        per_round = sum(first.values())
        rounds = min(solves, int(budget_left // max(per_round, 1e-9)))
        if rounds < solves:
            notes.append(
                f"the budget left room for {rounds} timed round(s) of the {solves} asked for"
                + ("; static times are of the first (cold) solves" if rounds == 0 else "")
            )
    out = dict(first)
    if rounds > 0 and timed:
        from . import models as registry

        def solve(name: str):
            return lambda: registry.run(scene, name)

        # the first solves said what there is to say: no warning again for every round
        with solve_limits(max_time=left()), contextlib.redirect_stderr(io.StringIO()):
            samples = interleaved({n: solve(n) for n in timed}, rounds=rounds, warmup=0)
        out = {n: median(samples, n) for n in timed}
    for n, first_name in alias.items():
        if first_name in out:
            out[n] = out[first_name]
    return out


def write_verdict_markdown(v: Verdict, path: str | Path) -> Path:
    """Write the verdict as Markdown: its sentences, its notes and its table.

    Parameters
    ----------
    v
        The verdict.
    path
        The ``.md`` file.

    Returns
    -------
    Path
    """
    from springfem.files import atomic_write_text

    path = Path(path)
    lines = [f"# Verdict: {v.scene}", "", v.sentence, ""] + ([v.ranking, ""] if v.ranking else [])
    lines += [f"- note: {n}" for n in v.notes] + ([""] if v.notes else [])
    lines.append(v.table.drop(columns=["message"]).to_markdown(index=False, floatfmt=".4g"))
    atomic_write_text(path, "\n".join(lines) + "\n")
    return path


def _cheapest(rows: pd.DataFrame, column: str) -> str | None:
    rows = rows[np.isfinite(rows[column])]
    return None if rows.empty else str(rows.loc[rows[column].idxmin(), "model"])


def _unlike(row: pd.Series) -> str:
    what = row.get("law vs reference", "same law")
    return "" if what in ("same law", "") else f" ({what}, not the reference's law)"


def verdict_sentence(
    table: pd.DataFrame,
    ref: str,
    tol: float,
    static_pick: str | None,
    dynamic_pick: str | None,
) -> str:
    """The verdict in at most two short sentences: the cheapest model within the tolerance
    for a static solve, its error and its time as a ratio to the reference's; the same for
    explicit dynamics (per simulated second, against explicit P1) when a model qualifies.

    A model that solves another law than the reference (``law vs reference``) is marked so,
    and no speed is called faster or slower: the ratio is a ratio of times.

    Parameters
    ----------
    table
        The verdict's table.
    ref
        The reference model.
    tol
        The tolerance.
    static_pick, dynamic_pick
        The picks.

    Returns
    -------
    str

    Examples
    --------
    >>> t = pd.DataFrame({"model": ["P2", "P1", "spring-exact"], "rel L2 error": [0, .02, .03],
    ...     "static time (s)": [4.0, 1.0, 2.0], "cost per simulated s": [np.nan, 9.0, 12.0],
    ...     "law vs reference": ["same law", "same law", "small-strain calibration"]})
    >>> print(verdict_sentence(t, "P2", 0.05, "P1", "spring-exact"))
    P1 is the cheapest static solve within 5% of P2: 2% off, in 0.25× the reference's time. \
For explicit dynamics spring-exact (small-strain calibration, not the reference's law) is: \
3% off, 12 s per simulated second, 1.33× explicit P1's.
    """
    t = table.set_index("model")
    within = f"within {_pct(tol)} of {ref}"
    if not ref:
        return "No FEM reference finished: no error, no verdict."
    if static_pick and static_pick != ref:
        r = t.loc[static_pick]
        ratio = r["static time (s)"] / t.at[ref, "static time (s)"]
        in_time = f", in {ratio:.2g}× the reference's time" if np.isfinite(ratio) else ""
        first = (
            f"{static_pick}{_unlike(r)} is the cheapest static solve {within}: "
            f"{_pct(r['rel L2 error'])} off{in_time}."
        )
    else:
        others = t[(t["rel L2 error"] > 0) & np.isfinite(t["rel L2 error"])]
        good = others[others["rel L2 error"] <= tol]
        if not good.empty:  # within it, but dearer than the reference
            n = good["static time (s)"].idxmin()
            ratio = good.at[n, "static time (s)"] / t.at[ref, "static time (s)"]
            rest = f"{n} ({_pct(good.at[n, 'rel L2 error'])} off) takes {ratio:.2g}× its time"
        elif not others.empty:
            n = others["rel L2 error"].idxmin()
            rest = f"no other model is (closest: {n}, {_pct(others.at[n, 'rel L2 error'])} off)"
        else:
            rest = "no other model is"
        first = f"{ref}, the reference, is the cheapest static solve {within}: {rest}."
    if not dynamic_pick:
        return first
    r = t.loc[dynamic_pick]
    cost = r["cost per simulated s"]
    vs = ""
    if dynamic_pick != "P1" and "P1" in t.index and np.isfinite(t.at["P1", "cost per simulated s"]):
        vs = f", {cost / t.at['P1', 'cost per simulated s']:.3g}× explicit P1's"
    if dynamic_pick == static_pick:
        return f"{first} For explicit dynamics it is too: {cost:.3g} s per simulated second{vs}."
    return (
        f"{first} For explicit dynamics {dynamic_pick}{_unlike(r)} is: "
        f"{_pct(r['rel L2 error'])} off, {cost:.3g} s per simulated second{vs}."
    )
