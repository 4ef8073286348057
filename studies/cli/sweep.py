"""``springfem sweep SWEEP.toml``: a scene over a grid of values, in-process or on Dask."""

from __future__ import annotations

import argparse
import sys

from ..sweep import run_sweep, summary_lines
from ..sweep_file import load_sweep


def cmd_sweep(args: argparse.Namespace) -> int:
    """``springfem sweep SWEEP.toml [--out DIR] [--workers [N] | --scheduler ADDRESS]``."""
    spec = load_sweep(args.file, sets=getattr(args, "set", None))
    run = run_sweep(spec, args.out, workers=args.workers, scheduler=args.scheduler)
    print(
        f"sweep {spec.name}: {len(spec.cases)} cases x {len(spec.models)} models "
        f"({run.computed} computed, {run.cached} cached) in {run.seconds:.1f} s; "
        f"reference {spec.reference}"
    )
    for line in summary_lines(run):
        print(line)
    for note in run.notes:
        print(f"note: {note}")
    for _, row in run.implausible.iterrows():
        print(f"warning: case {row['case']} {row['model']}: implausible: {row['message']}",
              file=sys.stderr)  # fmt: skip
    print("wrote " + ", ".join(str(f) for f in run.files) + f" and {run.out / 'cases'}/")
    bad = run.failed
    for _, row in bad.iterrows():
        print(f"springfem: solver failure: case {row['case']} {row['model']}: {row['status']}"
              f"{': ' + row['message'] if row['message'] else ''}", file=sys.stderr)  # fmt: skip
    return 3 if len(bad) else 0
