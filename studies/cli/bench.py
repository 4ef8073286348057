"""``springfem bench forces|fem|step|threads|tissue|scale|lockfree``: benchmarks (medians)."""

from __future__ import annotations

import argparse
import json
import sys
import time

from ..bench import DEFAULT_TETS, bench_forces, bench_step, machine
from ..bench_print import print_forces, print_step, print_threads
from ..bench_threads import bench_threads


def cmd_bench(args: argparse.Namespace) -> int:
    """Entry point of ``springfem bench``."""
    from springfem.errors import InputError

    what = args.what
    if what == "tissue":
        return _bench_tissue(args)
    if what == "scale":
        return _bench_scale(args)
    if what == "lockfree":
        return _bench_lockfree(args)
    n = args.tets if args.tets is not None else DEFAULT_TETS[what]
    repeats = int(getattr(args, "repeats", None) or 7)
    if n < 6:
        raise InputError(f"--tets must be at least 6, got {n}")
    if repeats < 1:
        raise InputError(f"--repeats must be at least 1, got {repeats}")
    as_json = bool(getattr(args, "json", False))
    if what == "forces":
        res = bench_forces(n, repeats, variants=bool(getattr(args, "variants", False)))
        if not as_json:
            print_forces(res)
    elif what == "step":
        res = bench_step(n, repeats)
        if not as_json:
            print_step(res)
    elif what == "threads":
        res = bench_threads(n, repeats)
        if not as_json:
            print_threads(res)
    elif what == "fem":
        from reference_fem import bench
        from reference_fem.bench import _print as print_fem

        t0 = time.perf_counter()
        res = bench(n, verbose=False)
        res["machine"] = machine()
        res["seconds"] = time.perf_counter() - t0
        if not as_json:
            print_fem(res, file=sys.stdout)  # its default stream is bound at import time
            print(f"  machine load average {res['machine']['load_average']}")
    else:  # argparse restricts the choices
        raise InputError(f"unknown benchmark {what!r}; valid: forces, fem, step, threads, tissue")
    if as_json:
        _print_json(res)
    return 0


def _print_json(res: dict) -> None:
    from springfem.files import jsonable as _jsonable

    print(json.dumps(_jsonable(res), indent=2, sort_keys=True))


def _bench_lockfree(args: argparse.Namespace) -> int:
    """``springfem bench lockfree`` (:mod:`studies.bench_lockfree`)."""
    from springfem.errors import InputError

    from ..bench_lockfree import DEFAULT_TETS, bench_lockfree, print_lockfree

    n = DEFAULT_TETS if args.tets is None else int(args.tets)
    repeats = int(args.repeats if args.repeats is not None else 7)
    solves = int(getattr(args, "solves", None) or 0)
    if n < 100 or repeats < 1 or solves < 0:
        raise InputError("bench lockfree: --tets >= 100, --repeats >= 1, --solves >= 0")
    res = bench_lockfree(n, repeats, solves)
    if args.json:
        _print_json(res)
    else:
        print_lockfree(res)
    return 0


def _bench_tissue(args: argparse.Namespace) -> int:
    """``springfem bench tissue`` (:mod:`studies.bench_tissue`)."""
    from springfem.errors import InputError

    from ..bench_tissue import (
        DEFAULT_DIVISIONS,
        DEFAULT_REPEATS,
        DEFAULT_SIZE,
        bench_tissue,
        print_tissue,
    )

    if args.tets is not None:
        raise InputError("bench tissue: --tets does not apply; use --size and --divisions")
    repeats = int(args.repeats if args.repeats is not None else DEFAULT_REPEATS)
    if repeats < 1:
        raise InputError(f"--repeats must be at least 1, got {repeats}")
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
    res = bench_tissue(repeats, args.cases, size, divisions)
    if args.json:
        _print_json(res)
    else:
        print_tissue(res)
    return 0


def _bench_scale(args: argparse.Namespace) -> int:
    """``springfem bench scale`` (:mod:`studies.bench_scale`)."""
    from pathlib import Path

    from springfem.errors import InputError

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

    if args.tets is not None:
        raise InputError("bench scale: --tets does not apply; use --sizes N,N,...")
    sizes: tuple[int, ...] = QUICK_SIZES if args.quick else DEFAULT_SIZES
    if args.sizes is not None:
        try:
            sizes = tuple(int(float(s)) for s in str(args.sizes).split(",") if s.strip())
        except ValueError:
            sizes = ()
        if not sizes or min(sizes) < 100:
            raise InputError(f"--sizes must be tet counts of at least 100, got {args.sizes!r}")
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
