"""``springfem bench forces|fem|step|threads|tissue|scale|lockfree|frames``: benchmarks.

Each benchmark returns a JSON-able result (``--json`` prints it) that its printer of
:mod:`studies.bench_print` shows as a table; ``scale`` writes its own folder.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

from springfem.errors import InputError

from .. import bench_print
from ..bench import DEFAULT_TETS, bench_forces, bench_step, machine


def _repeats(args: argparse.Namespace, default: int) -> int:
    repeats = int(args.repeats if args.repeats is not None else default)
    if repeats < 1:
        raise InputError(f"--repeats must be at least 1, got {repeats}")
    return repeats


def _tets(args: argparse.Namespace, default: int, least: int = 6) -> int:
    n = int(args.tets if args.tets is not None else default)
    if n < least:
        raise InputError(f"--tets must be at least {least}, got {n}")
    return n


def _sizes(args: argparse.Namespace, default: tuple[int, ...]) -> tuple[int, ...]:
    """``--sizes N,N,...``: tet counts of at least 100 (``default`` when not given)."""
    if args.sizes is None:
        return default
    try:
        sizes = tuple(int(float(s)) for s in str(args.sizes).split(",") if s.strip())
    except ValueError:
        sizes = ()
    if not sizes or min(sizes) < 100:
        raise InputError(f"--sizes must be tet counts of at least 100, got {args.sizes!r}")
    return sizes


def _print_json(res: dict) -> None:
    from springfem.files import jsonable

    print(json.dumps(jsonable(res), indent=2, sort_keys=True))


def _no_tets(args: argparse.Namespace, what: str, instead: str) -> None:
    if args.tets is not None:
        raise InputError(f"bench {what}: --tets does not apply; use {instead}")


def _forces(args: argparse.Namespace) -> dict:
    n, repeats = _tets(args, DEFAULT_TETS["forces"]), _repeats(args, 7)
    return bench_forces(n, repeats, variants=bool(getattr(args, "variants", False)))


def _step(args: argparse.Namespace) -> dict:
    return bench_step(_tets(args, DEFAULT_TETS["step"]), _repeats(args, 7))


def _threads(args: argparse.Namespace) -> dict:
    from ..bench_threads import bench_threads

    return bench_threads(_tets(args, DEFAULT_TETS["threads"]), _repeats(args, 7))


def _fem(args: argparse.Namespace) -> dict:
    from reference_fem import bench

    n = _tets(args, DEFAULT_TETS["fem"])
    _repeats(args, 7)
    t0 = time.perf_counter()
    res = bench(n, verbose=False)
    res["machine"] = machine()
    res["seconds"] = time.perf_counter() - t0
    return res


def _print_fem(res: dict) -> None:
    from reference_fem.bench import _print

    _print(res, file=sys.stdout)  # its default stream is bound at import time
    print(f"  machine load average {res['machine']['load_average']}")


def _lockfree(args: argparse.Namespace) -> dict:
    """``springfem bench lockfree`` (:mod:`studies.bench_lockfree`)."""
    from ..bench_lockfree import DEFAULT_TETS as LOCKFREE_TETS
    from ..bench_lockfree import bench_lockfree

    solves = int(getattr(args, "solves", None) or 0)
    if solves < 0:
        raise InputError(f"--solves must be at least 0, got {solves}")
    return bench_lockfree(_tets(args, LOCKFREE_TETS, least=100), _repeats(args, 7), solves)


def _tissue(args: argparse.Namespace) -> dict:
    """``springfem bench tissue`` (:mod:`studies.bench_tissue`)."""
    from ..bench_tissue import DEFAULT_DIVISIONS, DEFAULT_REPEATS, DEFAULT_SIZE, bench_tissue

    _no_tets(args, "tissue", "--size and --divisions")
    repeats = _repeats(args, DEFAULT_REPEATS)
    size = DEFAULT_SIZE if args.size is None else float(args.size)
    if not size > 0:
        raise InputError(f"--size must be positive, got {size:g}")
    divisions = DEFAULT_DIVISIONS
    if args.divisions is not None:
        try:
            divisions = tuple(int(d) for d in str(args.divisions).split(","))
        except ValueError:
            divisions = ()
        if len(divisions) != 3 or min(divisions) < 1:
            raise InputError(f"--divisions must be three positive integers NX,NY,NZ, "
                             f"got {args.divisions!r}")  # fmt: skip
    return bench_tissue(repeats, args.cases, size, divisions)


def _frames(args: argparse.Namespace) -> dict:
    """``springfem bench frames`` (:mod:`studies.bench_frames`)."""
    from ..bench_frames import MODELS, SIZES, bench_frames

    _no_tets(args, "frames", "--sizes")
    names = [m.strip() for m in args.models.split(",")] if args.models else MODELS
    rows = bench_frames(_sizes(args, SIZES), names, rounds=_repeats(args, 3))
    return {"rows": rows, "machine": machine()}


def _print_frames(res: dict) -> None:
    from ..bench_frames import frames_markdown

    print(frames_markdown(res["rows"]))


#: ``what`` -> (run the benchmark from the options, print its result).
BENCHES = {
    "forces": (_forces, bench_print.print_forces),
    "step": (_step, bench_print.print_step),
    "threads": (_threads, bench_print.print_threads),
    "fem": (_fem, _print_fem),
    "lockfree": (_lockfree, bench_print.print_lockfree),
    "tissue": (_tissue, bench_print.print_tissue),
    "frames": (_frames, _print_frames),
}


def cmd_bench(args: argparse.Namespace) -> int:
    """Entry point of ``springfem bench``: run one benchmark, print its table or JSON."""
    if args.what == "scale":
        return _bench_scale(args)
    if args.what == "forces" and (args.models or args.sizes):
        return _bench_models(args)
    if args.what not in BENCHES:  # argparse restricts the choices
        raise InputError(f"unknown benchmark {args.what!r}; valid: {', '.join(BENCHES)}, scale")
    run, show = BENCHES[args.what]
    res = run(args)
    if getattr(args, "json", False):
        _print_json(res)
    else:
        show(res)
    return 0


def _bench_scale(args: argparse.Namespace) -> int:
    """``springfem bench scale`` (:mod:`studies.bench_scale`)."""
    from pathlib import Path

    from ..bench_scale import (
        DEFAULT_MAX_MEMORY,
        DEFAULT_MAX_TIME,
        DEFAULT_MESHES,
        DEFAULT_OUT,
        DEFAULT_SIZES,
        QUICK_SIZES,
        ScaleSettings,
        bench_scale,
    )

    _no_tets(args, "scale", "--sizes N,N,...")
    sizes = _sizes(args, QUICK_SIZES if args.quick else DEFAULT_SIZES)
    models = None
    if args.models:
        from .. import models as registry

        models = [registry.get(m.strip()).name for m in str(args.models).split(",") if m.strip()]
    settings = ScaleSettings(
        sizes=sorted(set(sizes)),
        models=models,
        max_time=DEFAULT_MAX_TIME if args.max_time is None else float(args.max_time),
        reference_time=args.reference_time,
        max_memory=DEFAULT_MAX_MEMORY if args.max_memory is None else args.max_memory * 1e9,
        budget=args.budget,
        meshes=Path(args.meshes) if args.meshes else DEFAULT_MESHES,
        out=Path(args.out) if args.out else DEFAULT_OUT,
        cost_laws=Path(args.cost_laws) if args.cost_laws else None,
        resume=bool(args.resume),
    )
    bench_scale(settings, log=lambda line: print(line, flush=True))
    print(f"wrote {settings.out}/laws.md, cases.md, scale.png, cost_laws.json"
          + (f" and {settings.cost_laws}" if settings.cost_laws else ""))  # fmt: skip
    return 0


def _bench_models(args: argparse.Namespace) -> int:
    """``springfem bench forces --models M,...|all --sizes N,...`` (:mod:`studies.bench_forces`):
    every fast model's pass at organ sizes against the bandwidth floor."""
    from pathlib import Path

    from .. import bench_forces as bf

    _no_tets(args, "forces --models", "--sizes N,N,...")
    sizes = _sizes(args, bf.DEFAULT_SIZES)
    names = None if args.models in (None, "all") else [m.strip() for m in args.models.split(",")]
    memory = 4.0e9 if args.max_memory is None else float(args.max_memory) * 1e9
    res = bf.bench_forces(sizes, names, _repeats(args, 7), memory, args.meshes,
                          log=lambda s: print(s, file=sys.stderr, flush=True))  # fmt: skip
    if args.json:
        _print_json(res)
    else:
        print(bf.markdown(res))
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "bench_forces.csv").write_text(bf.csv(res) + "\n", encoding="utf-8")
        (out / "bench_forces.md").write_text(bf.markdown(res) + "\n", encoding="utf-8")
    return 0
