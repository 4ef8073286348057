"""The verdict's times: static solves and explicit steps, within what the budget leaves.

- A static solve longer than :data:`RESOLVE` seconds is timed once, by the solve that gave
  its solution: its noise on a shared machine is small next to the ratios that matter, and
  a second solve of a big problem would cost the budget another model. A solve between
  :data:`LONG` and :data:`RESOLVE` seconds is timed by one more, warm solve (a first solve
  also pays for imports and compiling kernels, seconds that are no part of the model's
  cost), and a shorter one by the median of warm solves in interleaved rounds
  (:func:`studies.timing.interleaved`); each as far as the budget allows. The table's
  ``timed`` column says which.
- One explicit step of each model with an explicit form: the median of interleaved rounds
  of at least :data:`SAMPLE_SECONDS` each, and its stable step ``2 / omega_max``.
"""

from __future__ import annotations

import contextlib
import io
import time
from collections.abc import Callable

import numpy as np

from springfem.mechanics.limits import solve_limits
from springfem.scene import Scene

from . import models as registry
from .timing import interleaved, median

#: A static solve longer than this (seconds) is not timed in rounds.
LONG = 2.0
#: A static solve longer than this (seconds) is timed once, by its first solve.
RESOLVE = 5.0
#: ... unless it is predicted to be short (its first solve was start-up), up to this long.
COLD_MAX = 60.0
#: Explicit steps per timing of the step cost: at least this many, and as many as make the
#: cheapest model's sample last SAMPLE_SECONDS (at most MAX_STEPS).
STEPS = 20
SAMPLE_SECONDS = 0.05
MAX_STEPS = 2000


def static_times(
    scene: Scene,
    timed: list[str],
    first: dict[str, float],
    solves: int,
    left: Callable[[], float | None],
    notes: list[str],
    predicted: dict[str, float] | None = None,
) -> tuple[dict[str, float], dict[str, str]]:
    """Static time per model, and how it was timed.

    Parameters
    ----------
    scene
        The scene.
    timed
        The models solved (one per distinct solve).
    first
        Their first solve's wall time.
    solves
        Warm solves per short model (0: the first solve's time for all).
    left
        Seconds left of the budget (``None``: no cap).
    notes
        The verdict's notes (a line is added when the budget cuts the rounds).
    predicted
        Predicted seconds per model (:mod:`studies.cost_model`): a first solve over
        :data:`LONG` of a model predicted under it was mostly start-up (imports, compiling)
        and gets a warm solve too, up to :data:`COLD_MAX` seconds.

    Returns
    -------
    tuple
        ``({model: seconds}, {model: "median of N warm" | "one warm solve" | "one solve"})``.
    """
    out = dict(first)
    how = {n: "one solve" for n in timed}
    predicted = predicted or {}

    def cold(n: str) -> bool:
        return first[n] <= COLD_MAX and predicted.get(n, float("inf")) < LONG

    for n in [n for n in timed if LONG < first[n] and (first[n] <= RESOLVE or cold(n))]:
        budget_left = left()
        if budget_left is not None and budget_left < 1.5 * first[n]:
            continue
        with solve_limits(max_time=left()), contextlib.redirect_stderr(io.StringIO()):
            t = time.perf_counter()
            got = registry.run(scene, n)
            seconds = time.perf_counter() - t
        if got.ok:
            out[n], how[n] = seconds, "one warm solve"
    short = [n for n in timed if first[n] <= LONG]
    rounds = solves
    budget_left = left()
    if budget_left is not None and short:
        per_round = sum(first[n] for n in short)
        rounds = min(solves, int(budget_left // max(per_round, 1e-9)))
        if rounds < solves:
            notes.append(
                f"the budget left room for {rounds} timed round(s) of the {solves} asked for "
                "the short solves" + ("; their times are of one solve" if rounds == 0 else "")
            )
    if rounds > 0 and short:

        def solve(name: str):
            return lambda: registry.run(scene, name)

        # the first solves said what there is to say: no warning again for every round
        with solve_limits(max_time=left()), contextlib.redirect_stderr(io.StringIO()):
            samples = interleaved({n: solve(n) for n in short}, rounds=rounds, warmup=0)
        for n in short:
            out[n] = median(samples, n)
            how[n] = f"median of {rounds} warm"
    return out, how


def step_costs(
    scene: Scene, names: list[str], rounds: int, left: Callable[[], float | None]
) -> dict[str, tuple[float, float]]:
    """Per model with an explicit form: (seconds per explicit step, stable step).

    Models whose system would not be built in the time left are left out.

    Parameters
    ----------
    scene
        The scene.
    names
        The models (one per distinct solve).
    rounds
        Interleaved rounds.
    left
        Seconds left of the budget (``None``: no cap).

    Returns
    -------
    dict
    """
    from springfem.mechanics import stable_time_step

    systems, dts = {}, {}
    build = 0.0  # the longest system build so far: the next one may take as long
    for n in names:
        budget_left = left()
        if budget_left is not None and budget_left < max(1.0, 2.0 * build):
            break
        t0 = time.perf_counter()
        try:  # the explicit FEM is P1 in the displacement formulation
            s = registry.system(registry.get(n), scene)
            dts[n] = stable_time_step(s)[0]
        except Exception:  # noqa: BLE001 - a model with no explicit form on this scene
            continue
        systems[n] = s
        build = max(build, time.perf_counter() - t0)
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
    budget_left = left()
    if budget_left is not None:  # each round steps every model `count` times, after a warm-up
        per_round = count * sum(one.values())
        rounds = min(rounds, int(budget_left // max(1.5 * per_round, 1e-9)) - 1)
        if rounds < 1:  # no time for rounds: the one warm step each
            return {n: (one[n], dts[n]) for n in systems}
    samples = interleaved({n: step(s, count) for n, s in systems.items()}, rounds=rounds)
    return {n: (median(samples, n) / count, dts[n]) for n in systems}
