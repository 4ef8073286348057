"""The ``springfem`` command line: inspect, solve, compare, verdict, study, report, sweep,
bench.

This package holds the parser and one module per command (:mod:`.inspect`, :mod:`.solve`,
:mod:`.compare`, :mod:`.verdict`, :mod:`.study`, :mod:`.sweep`, :mod:`.bench`); nothing
else imports it.
Exit codes: 0 ok, 2 bad input (one clear line on stderr, no traceback), 3 solver failure
(what, where, when), 1 internal error.
"""

from __future__ import annotations

import argparse
import os
import time

# One BLAS thread: multithreaded OpenBLAS on a busy 2-core machine is many times slower
# for the small dense factorisations of the solvers (set before numpy is imported).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
# Passive OpenMP waiting: spinning threads of the parallel kernels otherwise steal the
# other core on a busy machine (far slower than serial).
os.environ.setdefault("OMP_WAIT_POLICY", "passive")
import sys
import traceback
from collections.abc import Callable, Sequence
from typing import Any

from springfem.errors import SpringFemError
from springfem.warning_count import counted_warnings
from springfem.warning_count import summary as warnings_summary

from ..overrides import add_set_option
from .common import args_started


def _subcommand(module: str, func: str) -> Callable[[argparse.Namespace], int]:
    """Lazily import the module implementing a subcommand (keeps start-up fast)."""

    def run(args: argparse.Namespace) -> int:
        import importlib

        return getattr(importlib.import_module(module), func)(args)

    return run


def _positive(kind: type, noun: str) -> Callable[[str], Any]:
    """An argparse type: a positive ``kind`` (``float``: above 0, ``int``: at least 1).

    Examples
    --------
    >>> _positive(int, "an integer")("3"), _positive(float, "a number")("0.5")
    (3, 0.5)
    """

    def convert(text: str) -> Any:
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not {noun}: {text!r}") from None
        if not value > 0:
            raise argparse.ArgumentTypeError(f"must be positive, got {text}")
        return value

    return convert


_positive_float = _positive(float, "a number")
_positive_int = _positive(int, "an integer")


def _model_list(text: str) -> list[str]:
    """An argparse type: comma-separated model names (checked against the registry later)."""
    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        raise argparse.ArgumentTypeError("no model named")
    return names


class _Parser(argparse.ArgumentParser):
    """argparse with usage errors as one line (exit 2), like every other bad input."""

    def error(self, message: str):
        self.exit(2, f"springfem: error: {message} (see {self.prog} --help)\n")


class _StudyParser(_Parser):
    """The ``study`` subcommand's parser: its help lists the registered studies.

    The list is read from :data:`studies.registry.REGISTRY` only when the help is shown
    (importing every study module would slow down every other command's start-up).
    """

    def format_help(self) -> str:
        import inspect

        from ..runner import REGISTRY

        rows = []
        for name, spec in REGISTRY.items():
            doc = _first_line(inspect.getmodule(spec.run).__doc__)
            mark = "*" if spec.user_scenes is None else " "
            rows.append(f"  {name.replace('_', '-'):<16}{mark} {doc}")
        names = "\n".join(rows)
        return super().format_help() + f"\nstudies (* also runs on --scene FILE):\n{names}\n"


def _first_line(doc: str | None) -> str:
    """The first line of a docstring (empty for none)."""
    import re

    line = (doc or "").strip().splitlines()[0] if (doc or "").strip() else ""
    return re.sub(r"^Study ``[^`]*``:\s*", "", line)


# -- options several commands share -----------------------------------------------------------

SCENE_HELP = "scene TOML file or bundled scene name"


def _out(p: argparse.ArgumentParser, help: str) -> None:
    p.add_argument("--out", default=None, help=help)


def _max_time(p: argparse.ArgumentParser, help: str) -> None:
    p.add_argument("--max-time", type=_positive_float, default=None, metavar="SECONDS", help=help)


def _models(p: argparse.ArgumentParser, help: str) -> None:
    p.add_argument("--models", type=_model_list, default=None, metavar="M1,M2,...", help=help)


def _dask(p: argparse.ArgumentParser, workers: str, scheduler: str) -> None:
    """``--workers [N]`` or ``--scheduler ADDRESS``: where the cases run (one of them)."""
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, nargs="?", const=0, default=None, metavar="N",
                       help=workers)  # fmt: skip
    where.add_argument("--scheduler", default=None, metavar="ADDRESS", help=scheduler)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="springfem",
        description="Anisotropic spring model vs FEM on the same tetrahedral mesh.",
    )
    parser.add_argument("--debug", action="store_true", help="show tracebacks of errors")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser(
        "inspect", help="the mesh file's regions, mesh quality, axes and calibration of a scene"
    )
    p.add_argument("scene", help=SCENE_HELP)
    p.add_argument("--json", action="store_true", help="print JSON")
    p.add_argument("--modes", action="store_true",
                   help="count the near-zero eigenvalues of each model's tangent at rest "
                   "(spurious modes beyond the free rigid motions are named)")  # fmt: skip
    p.set_defaults(func=_subcommand("studies.cli.inspect", "cmd_inspect"))

    p = sub.add_parser("solve", help="solve a scene with one model")
    p.add_argument("scene", help=SCENE_HELP)
    p.add_argument("--model", choices=("spring", "fem"), default="spring")
    p.add_argument("--order", type=int, choices=(1, 2), default=None, help="FEM order")
    p.add_argument("--law", default=None, help="FEM material law override")
    _out(p, "output folder (default: out/<scene>-<model>)")
    p.add_argument("--json", action="store_true", help="print result.json to stdout")
    p.add_argument("--verbose", "-v", action="store_true",
                   help="print solver progress (Newton and relaxation residuals)")  # fmt: skip
    _max_time(p, "stop the solve after this wall time (exit 3)")
    p.add_argument("--max-steps", type=_positive_int, default=None, metavar="N",
                   help="stop a time-stepping solve after N steps (exit 3)")  # fmt: skip
    add_set_option(p)  # sweeps: --set key=value
    p.set_defaults(func=_subcommand("studies.cli.solve", "cmd_solve"))

    p = sub.add_parser("compare", help="spring model vs FEM (P1, P2) on the same scene")
    p.add_argument("scene", nargs="?", default=None, help="scene (default: cantilever)")
    _out(p, "output folder (default: out/compare-<scene>)")
    p.add_argument("--json", action="store_true", help="print the table as JSON")
    _models(p, "models to run, e.g. spring,p1 (default: spring, P1, P2 and, at large strain, "
            "P1-NH, P2-NH); the reference is the finest FEM among them")  # fmt: skip
    p.add_argument("--verbose", "-v", action="store_true",
                   help="print each model's solver progress")  # fmt: skip
    _max_time(p, "stop each model's solve after this wall time (a FAILED row)")
    add_set_option(p)  # sweeps: --set key=value
    p.set_defaults(func=_subcommand("studies.cli.compare", "cmd_compare"))

    p = sub.add_parser("verdict", help="which model is good enough for a scene, and how fast")
    p.add_argument("scene", help=SCENE_HELP)
    p.add_argument("--tolerance", type=_positive_float, default=0.05,
                   help="largest relative L2 error vs the reference (default 0.05)")  # fmt: skip
    p.add_argument("--budget", type=_positive_float, default=None, metavar="SECONDS",
                   help="time for the whole verdict; each solve gets the time left")  # fmt: skip
    _models(p, "the models to weigh (default: every one that applies)")
    _out(p, "output folder (default: out/verdict-<scene>)")
    p.add_argument("--json", action="store_true", help="print the verdict as JSON")
    p.add_argument("--frame-rate", type=_positive_float, default=None, metavar="HZ",
                   help="weigh the fast models at this frame rate against the dynamic "
                   "reference (60: a picture, 1000: haptics); budget default 600 s")  # fmt: skip
    add_set_option(p)
    p.set_defaults(func=_subcommand("studies.cli.verdict", "cmd_verdict"))

    p = sub.add_parser("study", help="run one study into reports/")
    p.__class__ = _StudyParser  # lists the studies in its --help
    p.add_argument("name", help="study name (listed below)")
    p.add_argument("--quick", action="store_true", help="coarser meshes, fewer points")
    _out(p, "report folder (default reports/, quick: reports/quick/; with --scene: "
         "out/study-<scene>/)")  # fmt: skip
    p.add_argument(
        "--scene",
        default=None,
        metavar="FILE",
        help="run the study on this scene instead of the bundled ones (where it makes sense)",
    )
    _max_time(p, "cap each case, the reference's too (default: 120 s with --scene, none "
              "otherwise); a capped solve is a partial or stopped row")  # fmt: skip
    p.add_argument("--budget", type=_positive_float, default=None, metavar="SECONDS",
                   help="time for the whole study (default: 100 s with --scene --quick, "
                   "160 s with --scene, none otherwise): cases that do not fit are skipped "
                   "and listed, and the tables are still written")  # fmt: skip
    p.add_argument("--tolerance", type=_positive_float, default=None, metavar="ERROR",
                   help="the model error a variant may have to count (studies with a "
                   "tolerance: ablation, speed-accuracy)")  # fmt: skip
    add_set_option(p)
    _dask(p, "run the cases on a local Dask cluster of N processes (default: one per core, or "
          "$SPRINGFEM_WORKERS; 1: in this process)",
          "run the cases on a Dask cluster, e.g. tcp://host:8786")  # fmt: skip
    p.set_defaults(func=_subcommand("studies.cli.study", "cmd_study"))

    p = sub.add_parser("sweep", help="a scene over a grid of values (SWEEP.toml), on Dask")
    p.add_argument("file", help="sweep TOML file (see studies/sweeps/cantilever.toml)")
    _out(p, "output folder (default: out/sweep-<name>)")
    _dask(p, "local Dask cluster of N processes (no N: one per core)",
          "join a Dask cluster, e.g. tcp://host:8786")  # fmt: skip
    add_set_option(p)
    p.set_defaults(func=_subcommand("studies.cli.sweep", "cmd_sweep"))

    p = sub.add_parser("report", help="run all studies and write reports/REPORT.md")
    p.add_argument("--quick", action="store_true", help="coarser meshes, fewer points")
    _out(p, "report folder (default reports/, quick: reports/quick/)")
    p.add_argument("--workers", type=int, nargs="?", const=0, default=None, metavar="N",
                   help="run the cases on a local Dask cluster of N processes shared by the "
                   "studies (default: one per core, or $SPRINGFEM_WORKERS; 1: in this "
                   "process)")  # fmt: skip
    p.set_defaults(func=_subcommand("studies.cli.study", "cmd_report"))

    p = sub.add_parser(
        "bench", help="benchmarks: spring force kernel, threads rule, FEM, steps, tissue solves"
    )
    p.add_argument(
        "what",
        choices=("forces", "fem", "step", "threads", "tissue", "scale", "lockfree", "frames"),
    )
    p.add_argument("--tets", type=int, default=None, help="approximate number of tets")
    p.add_argument("--repeats", type=int, default=None,
                   help="repeats (median reported; default 7, tissue 3)")  # fmt: skip
    p.add_argument("--json", action="store_true", help="print JSON")
    p.add_argument("--variants", action="store_true", help="forces: every spring variant too")
    p.add_argument("--cases", default=None,
                   help="tissue: cases, beam, ventricle, default or all")  # fmt: skip
    p.add_argument("--size", type=float, default=None,
                   help="tissue: ventricle element size in mm (default 4)")  # fmt: skip
    p.add_argument("--divisions", default=None, metavar="NX,NY,NZ",
                   help="tissue: beam divisions (default 30,3,3)")  # fmt: skip
    p.add_argument("--solves", type=int, default=None, metavar="K",
                   help="lockfree: interleaved rounds of static solves (default 0)")  # fmt: skip
    _scale_options(p)
    p.set_defaults(func=_subcommand("studies.cli.bench", "cmd_bench"))
    return parser


def _scale_options(p: argparse.ArgumentParser) -> None:
    """The options of ``springfem bench scale`` (:mod:`studies.bench_scale`)."""
    g = p.add_argument_group("scale (organ meshes, one process per model and size)")
    seconds = {"type": _positive_float, "default": None, "metavar": "S"}
    # fmt: off
    g.add_argument("--sizes", default=None, metavar="N,N,...",
                   help="organ sizes in tets (default 5000,30000,120000,500000; forces "
                   "--models: 1000,50000,500000)")
    g.add_argument("--quick", action="store_true", help="scale: sizes 2000,8000")
    g.add_argument("--models", default=None, metavar="M,M,...",
                   help="scale: models (default: the verdict's on the organ); forces: each "
                   "model's pass against the bandwidth floor (all: every fast one)")
    g.add_argument("--max-time", **seconds, help="scale: seconds per static solve (default 120)")
    g.add_argument("--reference-time", **seconds, help="scale: seconds per static solve of the "
                   "reference, P2/P1 mixed (default 3x --max-time)")
    g.add_argument("--max-memory", **{**seconds, "metavar": "GB"},
                   help="scale: GB of address space per case (default 14); forces "
                   "--models: resident GB a size may need (default 4)")
    g.add_argument("--budget", **seconds, help="scale: seconds for the whole run (cases that "
                   "would not fit are not started)")
    g.add_argument("--out", default=None, help="scale: output folder (default reports/scale); "
                   "forces --models: bench_forces.csv and .md go there")
    g.add_argument("--resume", action="store_true",
                   help="scale: keep the cases of an earlier run in the output folder")
    g.add_argument("--meshes", default=None,
                   help="scale: folder of the organ meshes (default out/organ-meshes)")
    g.add_argument("--cost-laws", default=None, metavar="PATH",
                   help="scale: also write the fitted laws (the cost model's JSON) here")
    # fmt: on


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``springfem`` console script."""
    args_started(time.perf_counter())
    os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
    os.environ.setdefault("MPLBACKEND", "Agg")
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.debug:  # every raw warning, where it was raised
        return _run(args)
    with counted_warnings() as seen:
        try:
            return _run(args)
        finally:
            if (line := warnings_summary(seen)) is not None:
                print(f"springfem: note: {line}", file=sys.stderr)


def _run(args: argparse.Namespace) -> int:
    """Run the subcommand; errors become one line on stderr and an exit code."""
    try:
        return int(args.func(args) or 0)
    except SpringFemError as exc:
        if args.debug:
            traceback.print_exc()
        kind = "solver failure" if exc.exit_code == 3 else "error"
        print(f"springfem: {kind}: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("springfem: interrupted", file=sys.stderr)
        return 130
    except MemoryError:
        print("springfem: error: out of memory", file=sys.stderr)
        return 1
    except Exception as exc:  # noqa: BLE001 - last line of defence: one line, exit 1
        if args.debug:
            traceback.print_exc()
        print(
            f"springfem: internal error: {type(exc).__name__}: {exc} (rerun with --debug)",
            file=sys.stderr,
        )
        return 1


if __name__ == "__main__":
    sys.exit(main())
