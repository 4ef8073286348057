"""``springfem compare [SCENE]``: the spring model against FEM P1 and P2 on the same mesh."""

from __future__ import annotations

import argparse
import sys

from springfem.mechanics.limits import solve_limits
from springfem.result import write_result

from ..compare import compare_scene
from ..compare_output import printable, render_comparison, summary_lines
from ..guards import locking_warnings, size_warning
from ..tables import write_table
from .common import out_folder, print_payload, progress_log, scene_of


def cmd_compare(args: argparse.Namespace) -> int:
    """``springfem compare [SCENE] [--out DIR] [--json] [--models M,..] [-v] [--max-time S]``.

    Parameters
    ----------
    args
        Parsed arguments: ``scene``, ``out``, ``json``, ``models``, ``verbose``,
        ``max_time`` (per model).

    Returns
    -------
    int
        Exit code: 0, or 3 when a model failed (one of the locking-free models the defaults
        add on a nearly incompressible scene fails with a note only).
    """
    scene = scene_of(args)  # sweeps: --set
    quiet = bool(getattr(args, "json", False))
    out = out_folder(args, "compare", scene.name)
    log = progress_log(quiet)
    for note in scene.mesh.notes:
        print(f"note: {note}", file=sys.stderr)
    for line in locking_warnings(scene):
        print(f"warning: {line}", file=sys.stderr)
    if (w := size_warning(scene)) is not None:
        print(f"warning: {w}", file=sys.stderr)
    log(
        f"{scene.name}: {scene.mesh.n_points} nodes, {scene.mesh.n_tets} tets, "
        f"law {scene.material.law}"
    )
    models = getattr(args, "models", None)
    verbose = bool(getattr(args, "verbose", False))
    with solve_limits(max_time=getattr(args, "max_time", None)):
        cmp = compare_scene(scene, models, log=log, allow_no_reference=True, verbose=verbose)
    md = write_table(cmp.table, out / "compare")
    for name, sol in cmp.solutions.items():
        write_result(
            out / name,
            sol.result,
            scene.mesh,
            sol.u,
            cell_data=sol.cell_data,
            point_data={"error": cmp.error_field(name)} if cmp.reference else None,
        )
    for name, sol in cmp.partial.items():  # the state a failed model stopped at
        write_result(out / name, sol.result, scene.mesh, sol.u, stem="partial")
    png = None
    try:
        if cmp.reference:
            png = render_comparison(cmp, out / "compare.png")
    except Exception as exc:  # noqa: BLE001 - a missing OpenGL must not lose the table
        print(f"springfem: warning: figure not rendered: {type(exc).__name__}: {exc}",
              file=sys.stderr)  # fmt: skip
    files = {"csv": str(md.with_suffix(".csv")), "markdown": str(md)}
    if png is not None:
        files["png"] = str(png)
    if quiet:
        payload = {
            "scene": scene.name,
            "reference": cmp.reference,
            "max_principal_strain_p1": cmp.strain,
            "notes": cmp.notes,
            "failures": cmp.failures,
            "summary": summary_lines(cmp),
            "rows": cmp.table.to_dict(orient="records"),
            "files": files,
        }
        print_payload(payload)
    else:
        print()
        print(printable(cmp.table))
        print()
        for note in cmp.notes:
            print(f"note: {note}")
        print(f"reference: {cmp.reference or 'none (FAILED)'}")
        for line in summary_lines(cmp):
            print(line)
        print("wrote " + ", ".join(files.values()) + f" and {out}/<model>/result.json + .vtu")
    failed = {n: m for n, m in cmp.failures.items() if n not in cmp.extra}
    for name, msg in cmp.failures.items():
        if name in failed:
            print(f"springfem: solver failure: {name}: {msg}", file=sys.stderr)
        else:  # a locking-free method added to the defaults: its row says it failed
            print(f"note: {name} (a locking-free method weighed too) failed: {msg}",
                  file=sys.stderr)  # fmt: skip
    return 3 if failed else 0
