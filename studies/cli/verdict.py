"""``springfem verdict SCENE``: is the spring model good enough here, and how fast is it?"""

from __future__ import annotations

import argparse
import sys

from ..compare_output import printable
from ..guards import size_warning
from ..tables import write_table
from ..verdict import verdict, write_verdict_markdown
from .common import command_seconds, out_folder, print_payload, progress_log, scene_of


def cmd_verdict(args: argparse.Namespace) -> int:
    """Weigh every applicable model against the scene's reference; print the verdict.

    Parameters
    ----------
    args
        Parsed options ``scene``, ``set``, ``tolerance``, ``budget``, ``models``, ``out``,
        ``json``.

    Returns
    -------
    int
        The exit code (0; 3 when no reference could be solved).
    """
    scene = scene_of(args)
    if getattr(args, "frame_rate", None):
        return _frame_verdict(args, scene)
    quiet = bool(args.json)
    log = progress_log(quiet)
    warning = size_warning(scene)
    if warning is not None:
        print(f"warning: {warning}", file=sys.stderr)
    log(f"{scene.name}: {scene.mesh.n_tets} tets, law {scene.material.law}")
    out = out_folder(args, "verdict", scene.name)

    def keep(v) -> None:  # the table of the models done so far, after every model
        write_verdict_markdown(v, write_table(v.table, out / "verdict"))

    v = verdict(scene, args.tolerance, args.budget, args.models, log=log, on_update=keep,
                spent=command_seconds())  # fmt: skip
    md = out / "verdict.md"
    if quiet:
        payload = {
            "scene": v.scene,
            "tolerance": v.tolerance,
            "reference": v.reference,
            "static": v.static_pick,
            "dynamic": v.dynamic_pick,
            "sentence": v.sentence,
            "ranking": v.ranking,
            "notes": v.notes,
            "warnings": [warning] if warning is not None else [],
            "rows": v.table.to_dict(orient="records"),
            "files": {"csv": str(md.with_suffix(".csv")), "markdown": str(md)},
        }
        print_payload(payload)
    else:
        print()
        print(printable(v.table.drop(columns=["message"])))
        print()
        for note in v.notes:
            print(f"note: {note}")
        print(f"verdict: {v.sentence}")
        if v.ranking:
            print(v.ranking)
        print(f"wrote {md.with_suffix('.csv')} and {md}")
    return 0 if v.reference else 3


def _frame_verdict(args: argparse.Namespace, scene) -> int:
    """``--frame-rate``: :func:`studies.verdict_frames.frame_verdict`, its table and files."""
    from ..verdict_frames import frame_verdict, write_frame_verdict

    quiet = bool(args.json)
    log = progress_log(quiet)
    budget = args.budget if args.budget is not None else 600.0
    v = frame_verdict(scene, args.frame_rate, names=args.models, log=log,
                      budget=max(1.0, budget - command_seconds()))  # fmt: skip
    md = write_frame_verdict(v, out_folder(args, "verdict", scene.name))
    if quiet:
        print(v.to_json())
    else:
        print()
        print(printable(v.table.rename_axis("model").reset_index()))
        print(f"verdict: {v.sentence}")
        print(f"wrote {md} and {md.with_suffix('.json')}")
    return 0
