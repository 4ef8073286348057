"""``springfem inspect SCENE [--json]``: the mesh file's regions, mesh quality, axes, ray
casting, calibration."""

from __future__ import annotations

import argparse
import dataclasses
import sys

from .. import guards
from ..scenes import scene_path
from .common import print_json


def cmd_inspect(args: argparse.Namespace) -> int:
    """Print the mesh file's named regions with their sizes
    (:func:`springfem.regions.named_sets`) and the spring model's statistics of a scene
    (:func:`springmodel.inspect`).

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
    from springfem.regions import named_sets
    from springfem.scene import load_scene
    from springmodel.inspect import inspect_scene

    scene = load_scene(scene_path(args.scene))
    report = inspect_scene(scene)
    regions = named_sets(scene.mesh)
    # the regions right after the mesh's own numbers
    at = list(report).index("bounding_box") + 1
    items = list(report.items())
    report = dict([*items[:at], ("regions", [dataclasses.asdict(r) for r in regions]), *items[at:]])
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
            if key == "regions":
                lines = [r.line for r in regions] or ["none named in the mesh file"]
                for n, line in enumerate(lines):
                    print(f"{'regions' if n == 0 else '':<{width}}  {line}")
            elif key != "modes":
                print(f"{key:<{width}}  {value}")
        for c in counts:
            print(c.line)
    return 0
