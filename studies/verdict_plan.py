"""The verdict's plan: which models it solves, in which order, and which it leaves out.

Before its first solve the verdict prints one line per model with its predicted time and
peak memory (:mod:`studies.cost_model`) and what it will do with it:

- the reference comes first: nothing is weighed without it;
- then the models that can pass, cheapest first, so that a budget weighs as many as it can;
- last, the models the scene rules out (the models that say they lock: displacement P1 and P2 on a
  nearly incompressible scene); they never stand in for the reference, and one predicted
  to cost more than the reference is skipped (``skipped (ruled out)``): it only shows the
  locking, at a price the answer does not need;
- under a budget, a model whose predicted time does not fit in what is left is skipped
  (``skipped (budget)``), and one whose predicted memory exceeds what the machine has is
  skipped (``skipped (memory)``); both are named in the table with the reason.

Examples
--------
>>> from studies.cost_model import Law, SolveCosts
>>> laws = {"fem-P2-mixed": Law((10.0, 1.3), (2e9, 1.2)), "P1-NH": Law((1.0, 1.0), (3e8, 1.0)),
...         "P2-NH": Law((20.0, 1.2), (1e9, 1.2))}
>>> costs = SolveCosts(laws, tets=10_000)
>>> plan = make_plan(["P2-NH", "P1-NH", "fem-P2-mixed"], "fem-P2-mixed", costs,
...                  {"P2-NH": "displacement P2 locks at nu = 0.49"}, budget=15.0,
...                  memory=16e9)
>>> for p in plan:
...     print(p.name, p.role, p.action)
fem-P2-mixed reference solve
P1-NH model solve
P2-NH ruled out skip
>>> plan[2].reason
'displacement P2 locks at nu = 0.49; the budget has no room for it (20 s)'
>>> make_plan(["P2-NH", "fem-P2-mixed"], "fem-P2-mixed", costs, {"P2-NH": "it locks"},
...           budget=None, memory=None)[1].reason
'it locks; it would cost more than the reference (20 s)'
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from .cost_model import Prediction, SolveCosts, gigabytes

#: The share of the budget the solves may take: the rest is for the explicit-step timing,
#: the timed rounds of short solves and writing the table.
SOLVE_SHARE = 0.85
#: A reference predicted to take more than this many times the time left is not started.
REFERENCE_SLACK = 1.5
#: A model is not started when its predicted memory exceeds this share of what is available.
MEMORY_SHARE = 0.9


@dataclass
class Planned:
    """One model of the plan.

    Attributes
    ----------
    name
        The model.
    predicted
        Its predicted static solve.
    role
        ``reference``, ``model`` or ``ruled out``.
    action
        ``solve`` or ``skip``.
    why
        Why it is ruled out (empty otherwise).
    skip
        Why it is skipped (empty otherwise).
    """

    name: str
    predicted: Prediction
    role: str
    action: str = "solve"
    why: str = ""
    skip: str = ""

    @property
    def reason(self) -> str:
        """Why it is ruled out and skipped, in one phrase."""
        return "; ".join(w for w in (self.why, self.skip) if w)


def make_plan(
    names: Sequence[str],
    reference: str,
    costs: SolveCosts,
    ruled: dict[str, str],
    budget: float | None,
    memory: float | None,
) -> list[Planned]:
    """The models in the order to solve them, each with its prediction and action.

    Parameters
    ----------
    names
        The models weighed (the reference among them).
    reference
        The reference model.
    costs
        Their predicted costs.
    ruled
        Model -> why the scene rules it out (its ``locks``).
    budget
        Seconds for the whole verdict (``None``: no cap).
    memory
        Bytes available (``None``: not known).

    Returns
    -------
    list of Planned
    """

    def key(p: Planned) -> tuple[int, float]:
        rank = {"reference": 0, "model": 1, "ruled out": 2}[p.role]
        s = p.predicted.seconds
        return rank, s if math.isfinite(s) else math.inf

    plan = []
    for n in dict.fromkeys(names):
        role = "reference" if n == reference else ("ruled out" if n in ruled else "model")
        plan.append(Planned(n, costs.predict(n), role, why=ruled.get(n, "")))
    plan.sort(key=key)
    ref_seconds = next((p.predicted.seconds for p in plan if p.role == "reference"), math.nan)
    spent = 0.0
    room = None if budget is None else SOLVE_SHARE * budget
    for p in plan:
        skip = skip_reason(p, room, spent, memory) or dearer_than_reference(p, ref_seconds)
        if skip:
            p.action, p.skip = "skip", skip
        elif math.isfinite(p.predicted.seconds):
            spent += p.predicted.seconds
    return plan


def skip_reason(p: Planned, room: float | None, spent: float, memory: float | None) -> str:
    """Why ``p`` should not start after ``spent`` of ``room`` seconds (empty: it starts).

    Parameters
    ----------
    p
        The planned model.
    room
        Seconds the solves may take (``None``: no cap).
    spent
        Seconds already spent or planned.
    memory
        Bytes available (``None``: not known).

    Returns
    -------
    str
    """
    pred = p.predicted
    if memory is not None and math.isfinite(pred.bytes) and pred.bytes > MEMORY_SHARE * memory:
        return f"it would need {gigabytes(pred.bytes)}, {gigabytes(memory)} is available"
    if room is None or not math.isfinite(pred.seconds):
        return ""
    left = room - spent
    slack = REFERENCE_SLACK if p.role == "reference" else 1.0
    if pred.seconds > slack * left:
        return f"the budget has no room for it ({pred.seconds:.3g} s)"
    return ""


def dearer_than_reference(p: Planned, reference_seconds: float) -> str:
    """Why a ruled-out model is not worth its solve: it is predicted to cost more than the
    reference, or no measured law of its own prices it (empty: it is worth it, or it is not
    ruled out).

    Parameters
    ----------
    p
        The planned model.
    reference_seconds
        The reference's time (measured, or predicted).

    Returns
    -------
    str
    """
    s = p.predicted.seconds
    if p.role != "ruled out":
        return ""
    if p.predicted.source != "measured law":  # priced as another model: its cost is a guess
        return "no measured cost law prices it"
    if not math.isfinite(s) or not math.isfinite(reference_seconds):
        return ""
    if s <= max(reference_seconds, 1.0):
        return ""
    return f"it would cost more than the reference ({s:.3g} s)"


def plan_lines(plan: Sequence[Planned], tets: int, budget: float | None) -> list[str]:
    """The plan as lines to print before the first solve.

    Parameters
    ----------
    plan
        :func:`make_plan`'s.
    tets
        The scene's size.
    budget
        The verdict's budget (``None``: none).

    Returns
    -------
    list of str
    """
    todo = [p for p in plan if p.action == "solve"]
    total = sum(p.predicted.seconds for p in todo if math.isfinite(p.predicted.seconds))
    head = f"plan: {len(todo)} of {len(plan)} models on {tets:,} tets, estimated {total:.0f} s"
    if budget is not None:
        head += f" (budget {budget:g} s)"
    lines = [head]
    for p in plan:
        s = p.predicted.seconds
        when = "time ?" if not math.isfinite(s) else f"~{s:.2g} s" if s < 100 else f"~{s:.0f} s"
        what = p.role if p.action == "solve" else f"skip: {p.reason}"
        if p.action == "solve" and p.why:
            what += f" ({p.why})"
        src = "" if p.predicted.source == "measured law" else f", priced {p.predicted.source}"
        lines.append(f"  {p.name:<26} {when:>9} {gigabytes(p.predicted.bytes):>8}  {what}{src}")
    return lines
