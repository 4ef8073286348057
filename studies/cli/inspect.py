"""``springfem inspect SCENE [--json]``: mesh, quality, axes, ray casting, calibration."""

from __future__ import annotations

import argparse
import sys

from .. import guards
from ..scenes import scene_path
from .common import print_json


def cmd_inspect(args: argparse.Namespace) -> int:
    """Print the spring model's statistics of a scene (:func:`springmodel.inspect`).

    Parameters
    ----------
    args
        Parsed options ``scene``, ``json``, ``modes`` (the zero-energy modes of each
        model's tangent at rest, :mod:`studies.modes_report`).

    Returns
    -------
    int
        The exit code (0).
    """
    from springfem.scene import load_scene
    from springmodel.inspect import inspect_scene

    scene = load_scene(scene_path(args.scene))
    report = inspect_scene(scene)
    for note in scene.mesh.notes:
        print(f"note: {note}", file=sys.stderr)
    for line in guards.locking_warnings(scene):
        print(f"warning: {line}", file=sys.stderr)
    counts = []
    if getattr(args, "modes", False):
        from ..modes_report import scene_modes

        counts = scene_modes(scene)
        report["modes"] = {
            c.model: {"near_zero": c.count, "expected": c.expected, "spurious": c.spurious}
            for c in counts
        }
    if args.json:
        print_json(report)
    else:
        width = max(len(k) for k in report if k != "modes")
        for key, value in report.items():
            if key != "modes":
                print(f"{key:<{width}}  {value}")
        for c in counts:
            print(c.line)
    return 0
