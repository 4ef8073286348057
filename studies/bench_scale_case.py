"""One case of ``springfem bench scale``: one model on one organ mesh, in its own process.

:func:`studies.bench_scale.run_case` starts this module as a child process under a memory
cap (``RLIMIT_AS``) and a time cap, so that the peak RSS the parent reads of it
(``os.wait4``) is this case's alone. The child

1. loads the small warm-up scene and solves it with the model, and takes one explicit force
   pass of it when the model has an explicit form, so that imports, compiled kernels and
   solver set-up are not timed (they are the same at every size);
2. loads the case's scene and prints a ``ready`` line;
3. for a model with an explicit form (:func:`explicit_system`): times its force pass, the
   explicit step of :func:`studies.verdict._step_costs` (the median of
   :data:`ROUNDS` samples, each of as many passes as last :data:`SAMPLE_SECONDS`), and
   prints a ``step`` line;
4. solves the scene statically (:func:`studies.models.run`, capped by
   :func:`springfem.mechanics.limits.solve_limits`) and prints a ``static`` line.

Every line on stdout is one JSON object with a ``stage`` key; the parent keeps the last of
each stage, so a case stopped in its static solve still gives its step time.

Run by hand::

    python -m studies.bench_scale_case SCENE MODEL --warmup WARMUP_SCENE --cap 120

``--step-only`` leaves out the static solve (and its warm-up): a size the model's static
solve does not fit still gives its explicit step.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import sys
import time

#: Seconds one sample of the explicit step timing lasts at least.
SAMPLE_SECONDS = 0.2
#: Samples of the explicit step timing (the median is kept).
ROUNDS = 3
#: Force passes per sample: at least, at most.
MIN_PASSES, MAX_PASSES = 3, 2000


def explicit_system(scene, name: str):
    """The model's explicit form on ``scene`` as the verdict times it
    (:func:`studies.verdict._step_costs`), or ``None``: P2 and the FEM formulations other
    than displacement have none.

    Parameters
    ----------
    scene
        The scene.
    name
        A model of :mod:`studies.models`.

    Returns
    -------
    MechanicalSystem or None
    """

    from . import models

    try:  # the explicit FEM is P1 in the displacement formulation
        return models.system(models.get(name), scene)
    except Exception:  # noqa: BLE001 - no explicit form on this scene
        return None


def step_seconds(system) -> tuple[float, int]:
    """Seconds of one explicit force pass of ``system`` at rest (median of :data:`ROUNDS`
    samples) and the passes per sample.

    Parameters
    ----------
    system
        A :class:`~springfem.mechanics.MechanicalSystem`.

    Returns
    -------
    tuple of (float, int)
    """
    import numpy as np

    x, v = system.x0.copy(), np.zeros_like(system.x0)
    system.forces(x, v)  # compiles, allocates
    t = time.perf_counter()
    system.forces(x, v)
    one = max(time.perf_counter() - t, 1e-9)
    count = int(np.clip(SAMPLE_SECONDS / one, MIN_PASSES, MAX_PASSES))
    samples = []
    for _ in range(ROUNDS):
        t = time.perf_counter()
        for _ in range(count):
            system.forces(x, v)
        samples.append((time.perf_counter() - t) / count)
    return float(np.median(samples)), count


def _say(**record) -> None:
    print(json.dumps(record), flush=True)


def _rss() -> int:
    """This process's peak RSS so far, in bytes."""
    import resource

    return int(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss) * 1024


def run(scene_path: str, name: str, warmup: str | None, cap: float, static: bool = True) -> int:
    """The case (see the module docstring); the exit code (0 also when the model failed:
    the lines say how).

    Parameters
    ----------
    scene_path
        The case's scene file.
    name
        The model.
    warmup
        The warm-up scene file (``None``: no warm-up).
    cap
        Seconds the static solve may take (:func:`~springfem.mechanics.limits.solve_limits`).
    static
        Solve statically (``False``: the explicit step only, and no warm-up solve).

    Returns
    -------
    int
    """
    from springfem.mechanics.limits import solve_limits
    from springfem.scene import load_scene

    from . import models

    quiet = contextlib.redirect_stderr(io.StringIO())  # warnings repeat the warm-up's
    if warmup:
        t = time.perf_counter()
        small = load_scene(warmup)
        with quiet, solve_limits(max_time=cap):
            if static:
                models.run(small, name)
            system = explicit_system(small, name)
            if system is not None:
                step_seconds(system)
        del system, small
        _say(stage="warmup", seconds=time.perf_counter() - t, rss=_rss())
    t = time.perf_counter()
    scene = load_scene(scene_path)
    _say(stage="ready", tets=int(scene.mesh.n_tets), load_seconds=time.perf_counter() - t,
         rss=_rss(), load_average=list(os.getloadavg()))  # fmt: skip
    system = explicit_system(scene, name)
    if system is not None:
        step, count = step_seconds(system)
        _say(stage="step", seconds=step, passes=count, rss=_rss())
    del system
    if not static:
        return 0
    with contextlib.redirect_stderr(io.StringIO()), solve_limits(max_time=cap):
        got = models.run(scene, name)
    _say(stage="static", status=got.status, seconds=float(got.seconds),
         message=got.message[:300], rss=_rss(), load_average=list(os.getloadavg()))  # fmt: skip
    return 0


def main(argv: list[str] | None = None) -> int:
    """``python -m studies.bench_scale_case SCENE MODEL [--warmup FILE] [--cap S]
    [--step-only]``."""
    p = argparse.ArgumentParser(prog="python -m studies.bench_scale_case")
    p.add_argument("scene")
    p.add_argument("model")
    p.add_argument("--warmup", default=None)
    p.add_argument("--cap", type=float, default=None)
    p.add_argument("--step-only", action="store_true")
    a = p.parse_args(argv)
    try:
        return run(a.scene, a.model, a.warmup, a.cap, static=not a.step_only)
    except MemoryError:
        _say(stage="error", kind="memory", message="MemoryError", rss=_rss())
        return 4


if __name__ == "__main__":
    sys.exit(main())
