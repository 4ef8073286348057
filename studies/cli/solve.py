"""``springfem solve SCENE --model spring|fem``: one scene, one model, ``result.json`` + VTU
(+ a time series)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from reference_fem.options import FemOptions
from springfem.errors import InputError, SolverError
from springfem.mechanics.limits import SolveStopped, solve_limits
from springfem.plausibility import check_solution
from springfem.result import write_result
from springfem.scene import OutputOptions

from .. import guards
from ..solve import default_out, model_label, solve_scene, warn, write_last_good_state
from .common import print_json, scene_of


def _write(out: Path, *args, **kw) -> tuple[Path, Path]:
    """:func:`write_result`, with an unwritable output folder reported as bad input."""
    try:
        return write_result(out, *args, **kw)
    except OSError as exc:
        raise InputError(f"cannot write to {out}: {exc.strerror or exc}") from None


def cmd_solve(args: argparse.Namespace) -> int:
    scene = scene_of(args)  # sweeps: --set
    for note in scene.mesh.notes:
        print(f"note: {note}", file=sys.stderr)
    if (w := guards.modulus_warning(scene.material, scene.units)) is not None:
        warn(w)
    if (w := guards.size_warning(scene)) is not None:
        warn(w)
    for line in guards.locking_warnings(scene, (args.model,)):
        warn(line)
    tag = (
        args.model if args.model == "spring" else f"fem-p{args.order or FemOptions.of(scene).order}"
    )
    out = Path(args.out) if args.out else default_out(scene.name, tag)
    limits = {
        "max_time": getattr(args, "max_time", None),
        "max_steps": getattr(args, "max_steps", None),
    }
    try:
        with solve_limits(**limits):
            sol = solve_scene(scene, args.model, args.order, args.law, args.verbose, out / "series")
    except (SolverError, SolveStopped) as exc:
        written = write_last_good_state(out, scene, args.model, exc)
        if isinstance(exc, SolveStopped):
            raise SolveStopped(
                f"{exc}; {written}", state=exc.state, load_factor=exc.load_factor
            ) from None
        text = f"{exc} ({written})"
        raise SolverError(text, state=exc.state, load_factor=exc.load_factor) from None
    for finding in check_solution(scene, sol.u, sol.result.law):
        warn(finding.line)
    js, vtu = _write(out, sol.result, scene.mesh, sol.u, cell_data=sol.cell_data)
    anim = None
    series = sol.result.info.get("series")
    fmt = OutputOptions.of(scene).animation
    if series and fmt:
        from ..animation import animate_frames, animation_path

        frames = sorted(Path(series).parent.glob("frame_*.vtu"))
        try:
            anim = animate_frames(frames, animation_path(Path(series).parent, fmt))
        except Exception as exc:  # noqa: BLE001 - no ffmpeg/OpenGL must not lose the solve
            warn(f"animation not written: {type(exc).__name__}: {exc}")
        else:
            sol.result.info["animation"] = str(anim)
            js, vtu = _write(out, sol.result, scene.mesh, sol.u, cell_data=sol.cell_data)
    if args.json:
        print_json(sol.result.to_dict())
    else:
        r = sol.result
        state = r.status if r.status and r.status != "converged" else f"converged={r.converged}"
        print(
            f"{r.scene}: {model_label(r)}: {state} "
            f"iterations={r.iterations} wall={r.wall_time:.3g}s"
        )
        for name, u in r.probes.items():
            print(f"  probe {name}: u = [{u[0]:.6g}, {u[1]:.6g}, {u[2]:.6g}]")
        print(f"  volume change {r.volume['relative_change']:.3e}; wrote {js} and {vtu}")
        if series:
            print(f"  time series {series} ({r.info.get('frames')} frames)")
        if anim is not None:
            print(f"  animation {anim}")
        if "vertex_output" in r.info:
            print(f"  note: {r.info['vertex_output']}")
    return 0
