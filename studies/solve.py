"""``springfem solve``: one scene, one model, ``result.json`` + VTU."""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from springmodel.errors import SolverError
from springmodel.result import Result, write_result
from springmodel.scene import Scene, load_scene


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


def cmd_solve(args: argparse.Namespace) -> int:
    from .cli import _print_json, scene_path

    scene = load_scene(scene_path(args.scene))
    for note in scene.mesh.notes:
        print(f"note: {note}", file=sys.stderr)
    tag = args.model if args.model == "spring" else f"fem-p{args.order or scene.fem.order}"
    out = Path(args.out) if args.out else Path("out") / f"{scene.name}-{tag}"
    try:
        sol = solve_scene(scene, args.model, args.order, args.law, args.verbose)
    except SolverError as exc:
        if exc.state is not None:
            u = np.asarray(exc.state).reshape(-1, 3)
            res = Result(
                scene=scene.name,
                model=args.model,
                element="last-good-state",
                law="",
                counts={"nodes": scene.mesh.n_points, "tets": scene.mesh.n_tets},
                probes=scene.probe_displacements(u),
                volume={},
                reactions={},
                wall_time=float("nan"),
                converged=False,
                iterations=0,
                info={"error": str(exc)},
            )
            write_result(out, res, scene.mesh, u, stem="last_good_state")
            raise SolverError(f"{exc} (last good state written to {out})") from None
        raise
    js, vtu = write_result(out, sol.result, scene.mesh, sol.u, cell_data=sol.cell_data)
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
