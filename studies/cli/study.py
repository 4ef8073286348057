"""``springfem study NAME`` and ``springfem report``: run registered studies."""

from __future__ import annotations

import argparse
import dataclasses

from springfem.errors import InputError
from springfem.files import output_folder
from springfem.mechanics.limits import solve_limits

from ..budget import Budget
from ..html import write_index
from ..runner import default_out, run_report, run_study

#: Default cap of each solve of a study on a user's scene (s): a scene the solvers cannot
#: handle gives stopped (partial or failed) rows instead of a study that never ends.
USER_SCENE_MAX_TIME = 120.0
#: Default budget of a whole study on a user's scene (s), quick and full preset: the plan
#: line names it, ``--budget`` changes it.
USER_SCENE_BUDGET = {True: 100.0, False: 160.0}
#: The environment variable of the default number of worker processes of ``study`` and
#: ``report`` (unset: one per core; ``1``: in this process, as the tests run).
WORKERS_ENV = "SPRINGFEM_WORKERS"


def default_workers(given: int | None, budgeted: bool = False) -> int | None:
    """The worker processes of a study's cases: ``--workers`` if given, else
    :data:`WORKERS_ENV`, else one per core (``0``), but this process for a study with a
    budget (``budgeted``: starting a cluster takes seconds of a short budget); ``1`` means
    in this process (``None``) (docs/studies.rst: what two workers measured against one
    process).

    Examples
    --------
    >>> default_workers(1) is None, default_workers(3), default_workers(None, budgeted=True)
    (True, 3, None)
    """
    import os

    if given is None and budgeted and WORKERS_ENV not in os.environ:
        return None
    n = given if given is not None else int(os.environ.get(WORKERS_ENV, "0") or 0)
    if n == 0 and (os.cpu_count() or 1) < 2:
        return None
    return None if n == 1 else n


def cmd_study(args: argparse.Namespace) -> int:
    """``springfem study NAME [--quick] [--out DIR] [--scene FILE] [--set K=V] [--workers N]``.

    Runs one study (on the bundled scenes, or on ``--scene`` with ``--set`` overrides where
    the study supports it) and prints what it found. Each solve is capped at
    ``--max-time`` seconds (default: :data:`USER_SCENE_MAX_TIME` on ``--scene``, none on
    the bundled scenes, whose numbers must not depend on the machine's speed).

    Parameters
    ----------
    args
        Parsed options ``name``, ``quick``, ``out``, ``scene``, ``set``, ``max_time``,
        ``budget``, ``workers``, ``scheduler``.

    Returns
    -------
    int
        The exit code (0).

    Raises
    ------
    InputError
        If the study cannot run on the given scene (the message says why), or ``--set``
        is given without ``--scene``.
    """
    from ..registry import get_study
    from ..scenes import StudyScene

    spec = get_study(args.name)
    sets = list(getattr(args, "set", None) or [])
    scene = getattr(args, "scene", None)
    scenes = None
    out = default_out(args.out, args.quick)
    if scene is not None:
        if spec.user_scenes is not None:
            name = spec.name.replace("_", "-")
            raise InputError(f"study {name} cannot run on --scene: {spec.user_scenes}")
        from ..overrides import parse_assignment

        user = StudyScene.from_file(scene, [parse_assignment(a) for a in sets])
        scenes = [user]
        if args.out is None:
            out = output_folder("study", user.label)
    elif sets:
        raise InputError("--set needs --scene (the bundled studies run their own scenes)")
    command = None
    if scene is not None:
        sets_text = "".join(f" --set {a}" for a in sets)
        command = f"springfem study {args.name}{' --quick' * args.quick} --scene {scene}{sets_text}"
    settings = None
    tolerance = getattr(args, "tolerance", None)
    if tolerance is not None:
        base = spec.settings_for(args.quick)
        if not hasattr(base, "max_error"):
            name = spec.name.replace("_", "-")
            raise InputError(
                f"study {name} has no tolerance (--tolerance applies to: ablation, speed-accuracy)"
            )
        settings = dataclasses.replace(base, max_error=tolerance)
    cap = getattr(args, "max_time", None)
    if cap is None and scene is not None:
        cap = USER_SCENE_MAX_TIME
    seconds = getattr(args, "budget", None)
    if seconds is None and scene is not None:
        seconds = USER_SCENE_BUDGET[bool(args.quick)]
    budget = Budget(seconds=seconds, case_cap=cap)
    with solve_limits(max_time=cap):
        res = run_study(spec.name, out, args.quick, scenes=scenes, settings=settings,
                        workers=_workers(args, budget.seconds is not None),
                        scheduler=getattr(args, "scheduler", None), command=command,
                        budget=budget)  # fmt: skip
    if scene is not None:
        write_index(out, f"springfem studies of {scenes[0].label}",
                    f"Every study run on the scene {scene} into this folder.")  # fmt: skip
    print(f"{res.title} ({res.seconds:.1f} s)")
    for line in res.findings:
        print(f"  - {line}")
    for t in res.tables:
        print(f"  table:  {t.path}")
    for f in res.figures:
        print(f"  figure: {f.path}")
    if scene is not None:
        print(f"  page:   {out / 'index.html'}")
    return 0


def _workers(args: argparse.Namespace, budgeted: bool = False) -> int | None:
    if getattr(args, "scheduler", None) is not None:
        return None
    return default_workers(getattr(args, "workers", None), budgeted)


def cmd_report(args: argparse.Namespace) -> int:
    """``springfem report [--quick] [--out DIR]``: run every study and write the report.

    Parameters
    ----------
    args
        Parsed options ``quick``, ``out``.

    Returns
    -------
    int
        The exit code (0).
    """
    out = default_out(args.out, args.quick)
    outputs = run_report(out, args.quick, workers=_workers(args))
    total = sum(o.seconds for o in outputs)
    pages = f"{out / 'REPORT.md'} and {out / 'index.html'}"
    print(f"wrote {pages} ({len(outputs)} studies, {total:.0f} s)")
    return 0
