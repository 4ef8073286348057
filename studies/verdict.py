"""The verdict on a scene: which model is good enough, and how fast is it against FEM?

:func:`verdict` runs every model of :mod:`studies.models` that applies to the scene against
its best reference and measures for each

- the error of its static solution against the reference (relative L2 over the vertices);
- the wall time of its static solve and its peak memory: a solve longer than two seconds
  is timed once, by the solve that gave its solution; a shorter one gets the median of
  :data:`SOLVES` warm solves, interleaved (every model once per round, in a shuffled order,
  :func:`studies.timing.interleaved`); the table's ``timed`` column says which
  (:mod:`studies.verdict_timing`);
- for the models with an explicit form (the spring variants, the explicit P1 FEM), the cost
  of one explicit step (median of interleaved rounds) and the stable step
  ``2 / omega_max``, hence the cost of one simulated second, ``cost per step / stable step``;
- what it solves against the reference's law (``law vs reference``:
  :func:`studies.models.law_versus`): the same law, or a small-strain law or calibration
  of it, whose speed is not like for like.

The reference is the finest FEM of the scene's law: P2, neo-Hookean P2 at large strain, the
scene's own formulation for tissue; on a nearly incompressible scene of a hyperelastic law
P2/P1 mixed (``fem-P2-mixed``), and the locking-free methods are weighed too
(:mod:`studies.models`). It then names the cheapest model within the tolerance, for
static solves and for explicit dynamics separately, in at most two short sentences
(:func:`verdict_sentence`).

Before its first solve the verdict plans (:mod:`studies.verdict_plan`): each model's time
and peak memory are predicted from the mesh (:mod:`studies.cost_model`); the reference is
solved first, then the models that can pass, cheapest first, and last the models the scene
rules out (displacement P1 and P2 on a nearly incompressible scene). Under a time budget a
model that no longer fits is ``skipped (budget)``, one that would not fit in memory
``skipped (memory)``, and each solve is capped by the time left. A reference that does not
fit or finish falls back to the next finest FEM the scene does not rule out, with a note;
when none is left, the note says what the reference would need. A reference with inverted
elements or implausible strains (:func:`springfem.plausibility.check_solution`) is not
valid: the verdict says so and names no model. A mesh too coarse across a thin wall for
linear tets gets a note (:func:`springfem.mesh.thickness.thin_wall_note`). The verdict so
far is handed to ``on_update`` after every model, so that a verdict stopped part way leaves
its table.
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

import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from reference_fem.fitting import is_tissue
from springfem.mechanics.limits import solve_limits
from springfem.mechanics.memory import MemoryLimitExceeded, memory_limit
from springfem.mesh.thickness import thin_wall_note
from springfem.model_api import declared
from springfem.scene import Scene

from . import models
from .cost_model import SolveCosts, gigabytes, read_laws
from .metrics import max_principal_strain
from .models import reference_model
from .peak_memory import PeakMemory
from .verdict_plan import (
    SOLVE_SHARE,
    Planned,
    dearer_than_reference,
    make_plan,
    plan_lines,
    skip_reason,
)
from .verdict_table import Verdict, VerdictState, verdict_sentence
from .verdict_timing import static_times, step_costs

__all__ = ["Verdict", "candidate_models", "reference_model", "verdict", "verdict_sentence"]

#: Default tolerance: the largest relative L2 error a model may have to count.
TOLERANCE = 0.05
#: Warm static solves per model whose median is its static time (interleaved rounds).
SOLVES = 3


def candidate_models(scene: Scene) -> list[str]:
    """The primary models (:func:`studies.models.candidates`: :data:`~studies.models.PRIMARY`
    and the default plug-ins) that apply to ``scene``, and on a nearly incompressible scene
    the locking-free ones (:func:`studies.models.locking_free_models`).

    Parameters
    ----------
    scene
        The scene.

    Returns
    -------
    list of str
    """
    out = [m.name for m in map(models.get, models.candidates())
           if m.name != "fem" and m.applies(scene) is None]  # fmt: skip
    return out + [n for n in models.locking_free_models(scene) if n not in out]


def verdict(
    scene: Scene,
    tolerance: float = TOLERANCE,
    budget: float | None = None,
    models: tuple[str, ...] | None = None,
    rounds: int = 5,
    log=None,
    solves: int = SOLVES,
    on_update: Callable[[Verdict], None] | None = None,
    laws: dict | None = None,
    spent: float = 0.0,
) -> Verdict:
    """The verdict on ``scene`` (see the module docstring).

    Parameters
    ----------
    scene
        The scene.
    tolerance
        Largest relative L2 error against the reference that counts as good enough.
    budget
        Seconds for the whole verdict (``None``: no cap): the plan leaves out what does not
        fit, each solve gets the time left, and the timed rounds are cut to what fits.
    models
        The models to weigh (default :func:`candidate_models`); the reference is added.
    rounds
        Interleaved rounds of the step-cost timing.
    log
        Called with each line of the plan and one line per finished model.
    solves
        Warm solves per short model whose median is its static time (:data:`SOLVES`; 0:
        the first solve's time).
    on_update
        Called with the verdict so far after every model (the CLI writes its table then, so
        that a verdict stopped part way leaves the models done).
    laws
        Cost laws of :mod:`studies.cost_model` (default :func:`~studies.cost_model.read_laws`).
    spent
        Seconds of the budget already spent (the command's start-up and the scene's
        loading).

    Returns
    -------
    Verdict
    """
    from . import models as registry

    say = log or (lambda _line: None)
    t0 = time.perf_counter() - spent
    notes: list[str] = list(scene.mesh.notes)
    thin = thin_wall_note(scene.mesh)  # linear tets cannot bend through one tet across
    if thin is not None:
        notes.append(thin)
    names = list(models) if models is not None else candidate_models(scene)
    names = list(dict.fromkeys(registry.get(n).name for n in names))
    state = VerdictState(scene, tolerance, names, notes)
    costs = SolveCosts(read_laws() if laws is None else laws, scene.mesh.n_tets,
                       scene.material.law)  # fmt: skip

    def elapsed() -> float:
        return time.perf_counter() - t0

    def left() -> float | None:
        return None if budget is None else max(budget - elapsed(), 1e-3)

    def solve_room() -> float | None:
        return None if budget is None else SOLVE_SHARE * budget - elapsed()

    def run(name: str) -> registry.Outcome:
        if name in state.outcomes:
            return state.outcomes[name]
        if name in state.alias:
            state.outcomes[name] = run(state.alias[name])
            return state.outcomes[name]
        cap = solve_room()
        try:
            with PeakMemory() as pm, solve_limits(max_time=None if cap is None else max(cap, 1e-3)):
                got = registry.run(scene, name)
        except (MemoryLimitExceeded, MemoryError) as exc:  # refused before it started
            why = str(exc) or "out of memory"
            state.skipped[name] = ("skipped (memory)", why)
            say(f"  {name:<26} skipped (memory): {why}")
            publish()
            return registry.Outcome(registry.get(name), "failed", None, why)
        if got.stopped and got.status == "failed":  # the budget's cap, not a solver failure
            why = got.message  # "stopped after ... (the --max-time cap ...)"
            state.skipped[name] = ("skipped (budget)", why[:200])
            say(f"  {name:<26} skipped (budget): {why[:120]}")
            publish()
            return got
        state.outcomes[name], state.peaks[name] = got, pm.peak
        if got.ok:
            costs.observe(name, got.seconds)
        say(f"  {name:<26} {got.status} in {got.seconds:.2f} s, peak {gigabytes(pm.peak)}")
        publish()
        return got

    def skip(p: Planned, why: str) -> None:
        kind = "memory" if "available" in why else "budget"
        ruled = "more than the reference" in why or "no measured cost law" in why
        kind = "ruled out" if ruled else kind
        state.skipped[p.name] = (f"skipped ({kind})", why)
        say(f"  {p.name:<26} skipped ({kind}): {why}")
        publish()

    def publish() -> None:
        if on_update is not None:
            on_update(state.verdict())

    mixed = registry.mixed_reference(scene)
    if mixed is None:  # the reference depends on the strain of the small-strain P1 solution
        p1 = run("P1")
        strain = max_principal_strain(scene, p1.u) if p1.ok else float("nan")
    ref = reference_model(scene, strain if mixed is None else 0.0)
    if ref not in names:
        names.append(ref)
    state.alias = registry.same_solves(scene, names)
    for n, first in state.alias.items():
        notes.append(f"{n} is the same solve as {first} on this scene: solved once")
    locking_free = [n for n in registry.locking_free_models(scene) if n in names]
    if locking_free:
        notes.append(registry.locking_note(scene, locking_free, ref))
    notes += registry.formulation_notes(scene, names)
    ruled = {n: why for n in names if (why := declared(registry.get(n), "locks", scene))}
    distinct = [n for n in names if n not in state.alias]
    memory = _memory()
    plan = make_plan(distinct, ref, costs, ruled, budget, memory)
    for line in plan_lines(plan, scene.mesh.n_tets, budget):
        say(line)
    state.reference = ref
    ref = _solve_reference(scene, plan, ref, ruled, names, state, run, skip, solve_room, memory)
    state.reference = ref
    if ref:
        state.check_reference()
    publish()
    for p in plan:
        if p.name in state.outcomes or p.name in state.skipped:
            continue
        p.predicted = costs.predict(p.name)
        ref_seconds = float(state.outcomes[ref].seconds) if ref else np.nan
        p.skip = skip_reason(p, solve_room(), 0.0, _memory()) or dearer_than_reference(
            p, ref_seconds
        )
        if p.skip:
            skip(p, p.reason)
        else:
            run(p.name)
    timed = [n for n in distinct if n in state.outcomes and state.outcomes[n].ok]
    first = {n: float(state.outcomes[n].seconds) for n in timed}
    predicted = {n: costs.predict(n).seconds for n in timed}
    state.times, state.timed = static_times(scene, timed, first, solves, left, notes, predicted)
    budget_left = left()
    if budget_left is not None and budget_left < 2.0:
        notes.append("the budget left no time to time the explicit steps")
    else:
        state.costs = step_costs(scene, timed, rounds, left)
    v = state.verdict(final=True)
    publish_final = on_update
    if publish_final is not None:
        publish_final(v)
    return v


def _memory() -> float | None:
    """Bytes a solve may hold (:func:`springfem.mechanics.memory.memory_limit`)."""
    limit = memory_limit()
    return float(limit) if limit and limit < float("inf") else None


def _solve_reference(scene, plan, ref, ruled, names, state, run, skip, solve_room, memory) -> str:
    """Solve the reference; when it does not fit or finish, the next finest FEM the scene
    does not rule out stands in, with a note; ``""`` when none does."""
    from . import models as registry

    planned = {p.name: p for p in plan}
    first_ref = ref
    finite = ref != "P2" and not is_tissue(scene)  # P2, P1: a tissue law
    fallback = ("P2-NH", "P1-NH", "P2", "P1") if finite else ("P2", "P2-NH", "P1-NH", "P1")
    preference = [ref] + [n for n in fallback if n in names and n not in ruled]
    for cand in dict.fromkeys(preference):
        if registry.get(cand).applies(scene) is not None:
            continue
        p = planned.get(state.alias.get(cand, cand))
        if p is not None and p.action == "skip" and cand not in state.outcomes:
            skip(p, p.reason)
            continue
        if run(cand).ok:
            if cand != first_ref:
                got = state.outcomes.get(first_ref)
                why = got.message if got is not None else state.skipped[first_ref][1]
                state.notes.append(
                    f"the reference {first_ref} did not finish ({why}); {cand} stands in"
                )
            return cand
    p = planned.get(first_ref)
    need = (
        f": {first_ref} would need about {p.predicted.seconds:.0f} s and "
        f"{gigabytes(p.predicted.bytes)}"
        if p is not None and np.isfinite(p.predicted.seconds)
        else ""
    )
    if ruled:
        state.notes.append(
            "no valid reference fit the budget or finished" + need + "; the models the scene "
            f"rules out ({', '.join(ruled)}) do not stand in: errors are not computed"
        )
    else:
        state.notes.append("no FEM reference finished" + need + ": errors are not computed")
    return ""


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
