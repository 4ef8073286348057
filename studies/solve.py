"""``springfem solve``: one scene, one model, ``result.json`` + VTU."""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from reference_fem.options import FemOptions
from springfem.errors import InputError, SolverError
from springfem.files import safe_filename
from springfem.result import Result, volume_summary, write_result
from springfem.scene import Scene, load_scene


@dataclass
class Solution:
    """What a model produced: the result record, nodal displacement and VTU cell data."""

    result: Result
    u: np.ndarray  # (n, 3) displacement at the mesh vertices
    cell_data: dict[str, np.ndarray] = field(default_factory=dict)


def solve_scene(
    scene: Scene,
    model: str,
    order: int | None = None,
    law: str | None = None,
    verbose: bool = False,
) -> Solution:
    """Solve ``scene`` with the spring model or the FEM reference."""
    if model == "fem":
        import reference_fem

        sol = reference_fem.solve(scene, order=order, law=law, verbose=verbose)
        return Solution(sol.result, sol.u_vertices, dict(sol.cell_data))
    from springmodel.model import solve_spring

    sol = solve_spring(scene, verbose=verbose)
    return Solution(sol.result, sol.u, dict(sol.cell_data))


def default_out(scene_name: str, tag: str) -> Path:
    """``out/<name>-<tag>``, with the scene name reduced to one safe folder name."""
    return Path("out") / f"{safe_filename(scene_name)}-{tag}"


def _write(out: Path, *args, **kw) -> tuple[Path, Path]:
    """:func:`write_result`, with an unwritable output folder reported as bad input."""
    try:
        return write_result(out, *args, **kw)
    except OSError as exc:
        raise InputError(f"cannot write to {out}: {exc.strerror or exc}") from None


def write_last_good_state(out: Path, scene: Scene, model: str, exc: SolverError) -> str:
    """Write ``last_good_state.json``/``.vtu`` for a failed solve; say what was written.

    ``exc.state`` is the last good nodal displacement; a solve that failed before its first
    step (a singular system) has none, and its last good state is the initial one (zero).
    """
    initial = exc.state is None
    u = np.zeros((scene.mesh.n_points, 3)) if initial else np.asarray(exc.state).reshape(-1, 3)
    finite = bool(np.isfinite(u).all())
    res = Result(
        scene=scene.name,
        model=model,
        element="last-good-state",
        law="",
        counts={"nodes": scene.mesh.n_points, "tets": scene.mesh.n_tets},
        probes=scene.probe_displacements(u),
        volume=volume_summary(scene.mesh, u) if finite else {},
        reactions={},
        wall_time=float("nan"),
        converged=False,
        iterations=0,
        info={"error": str(exc), "state": "initial" if initial else "last good"},
    )
    try:
        write_result(out, res, scene.mesh, u, stem="last_good_state")
    except OSError as err:
        return f"the last good state could not be written to {out}: {err.strerror or err}"
    what = "initial state (failed before the first step)" if initial else "last good state"
    return f"{what} written to {out}"


def cmd_solve(args: argparse.Namespace) -> int:
    from .cli import _print_json, scene_path

    scene = load_scene(scene_path(args.scene))
    for note in scene.mesh.notes:
        print(f"note: {note}", file=sys.stderr)
    tag = (
        args.model if args.model == "spring" else f"fem-p{args.order or FemOptions.of(scene).order}"
    )
    out = Path(args.out) if args.out else default_out(scene.name, tag)
    try:
        sol = solve_scene(scene, args.model, args.order, args.law, args.verbose)
    except SolverError as exc:
        written = write_last_good_state(out, scene, args.model, exc)
        raise SolverError(f"{exc} ({written})", state=exc.state) from None
    js, vtu = _write(out, sol.result, scene.mesh, sol.u, cell_data=sol.cell_data)
    if args.json:
        _print_json(sol.result.to_dict())
    else:
        r = sol.result
        print(
            f"{r.scene}: {r.model} {r.element} {r.law}: converged={r.converged} "
            f"iterations={r.iterations} wall={r.wall_time:.3g}s"
        )
        for name, u in r.probes.items():
            print(f"  probe {name}: u = [{u[0]:.6g}, {u[1]:.6g}, {u[2]:.6g}]")
        print(f"  volume change {r.volume['relative_change']:.3e}; wrote {js} and {vtu}")
    return 0
