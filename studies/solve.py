"""Solving one scene with one model: its solution, its last good state, its output.

Examples
--------
>>> model_label(Result("s", "spring", "spring", "spring[axial=linear]", {}, {}, {}, {},
...                    0.0, True, 1))
'spring [axial=linear]'
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from reference_fem.options import FemOptions
from springfem.cardiac import cavity_summary, is_ventricle
from springfem.errors import InputError, SolverError
from springfem.files import output_folder
from springfem.mechanics.limits import SolveStopped
from springfem.model_api import ModelSolution as Solution  # the one solution type
from springfem.result import Result, volume_summary, write_result
from springfem.scene import OutputOptions, Scene

#: ``info["vertex_output"]`` of a P2 solve: what its VTU holds.
P2_VERTEX_NOTE = (
    "P2 solution reduced to the mesh vertices in result.vtu (the mid-edge nodes are not "
    "written); probes and volume_p2 use the full P2 field"
)


def solve_scene(
    scene: Scene,
    model: str,
    order: int | None = None,
    law: str | None = None,
    verbose: bool = False,
    series_dir: str | Path | None = None,
) -> Solution:
    """Solve ``scene`` with the spring model or the FEM reference.

    Parameters
    ----------
    scene
        The scene.
    model
        ``spring`` or ``fem``.
    order, law
        FEM order and law (FEM only: an :class:`InputError` for the spring model).
    verbose
        Solver progress on stderr (Newton residuals, relaxation residuals, progress bars).
    series_dir
        Folder of the time series of a dynamic run with ``[output] interval``.

    Returns
    -------
    Solution
    """
    if model == "fem":
        if FemOptions.of(scene).solver != "static":
            return solve_fem_dynamic(scene, order, law, verbose, series_dir)
        import reference_fem

        sol = reference_fem.solve(scene, order=order, law=law, verbose=verbose)
        if sol.result.element == "P2":
            sol.result.info["vertex_output"] = P2_VERTEX_NOTE
        return Solution(sol.result, sol.u_vertices, dict(sol.cell_data))
    if order is not None or law is not None:
        flag = "--order" if order is not None else "--law"
        raise InputError(f"{flag} applies to --model fem only; the spring model has neither")
    from springmodel.model import solve_spring

    sol = solve_spring(scene, verbose=verbose, series_dir=series_dir)
    return Solution(sol.result, sol.u, dict(sol.cell_data))


def solve_fem_dynamic(
    scene: Scene, order: int | None, law: str | None, verbose: bool, series_dir
) -> Solution:
    """A time integration of the P1 FEM (``[fem] solver = "explicit"`` or ``"implicit"``)."""
    from reference_fem.dynamics import dynamic_system, solve_dynamic
    from springfem.loads import reactions
    from springmodel.run_series import end_of_run

    t0 = time.perf_counter()
    opts = FemOptions.of(scene)
    system = dynamic_system(scene, order, law)
    writer = None
    out = OutputOptions.of(scene)
    if series_dir is not None and out.interval is not None:
        from springfem.series import SeriesWriter

        writer = SeriesWriter(
            Path(series_dir), scene.mesh, out.interval, masses=system.masses,
            potential=system.energy,
            probes=scene.probe_displacements if out.probes_history else None,
        )  # fmt: skip
    try:
        traj = solve_dynamic(system, opts, callback=writer, progress=verbose)
    except (SolverError, SolveStopped) as exc:
        if writer is not None:
            writer.close(plot=False)
        state = None if exc.state is None else np.asarray(exc.state).reshape(-1, 3) - system.x0
        raise type(exc)(f"{scene.name} (fem P1 {opts.solver}): {exc}", state=state) from None
    u = traj.x - system.x0
    extra = {
        "solver": opts.solver,
        "dt": traj.dt,
        "steps": traj.steps,
        "integrator": traj.integrator,
    }
    extra.update(end_of_run(traj, writer))
    result = Result(
        scene=scene.name,
        model="fem",
        element="P1",
        law=system.law,
        counts={"nodes": scene.mesh.n_points, "tets": scene.mesh.n_tets,
                "dofs": 3 * scene.mesh.n_points, "fixed_dofs": int(system.fixed_dofs.size)},
        probes=scene.probe_displacements(u),
        volume=volume_summary(scene.mesh, u),
        reactions=reactions(scene, system.forces(traj.x, None)),
        wall_time=time.perf_counter() - t0,
        converged=False,
        iterations=int(traj.iterations or traj.steps),
        info=extra,
        status=extra["status"],
    )  # fmt: skip
    return Solution(result, u, {})


def model_label(r: Result) -> str:
    """``spring [axial=…]`` or ``fem P1 linear``: the model, element and law, once each."""
    if r.model == "spring":
        return f"spring {r.law.removeprefix('spring')}".rstrip()
    return f"{r.model} {r.element} {r.law}"


def default_out(scene_name: str, tag: str) -> Path:
    """``out/solve-<name>-<tag>`` (:func:`springfem.files.output_folder`)."""
    return output_folder("solve", f"{scene_name}-{tag}")


def state_result(
    scene: Scene,
    model: str,
    u: np.ndarray,
    exc: Exception,
    element: str,
    status: str,
    info: dict | None = None,
    wall_time: float = float("nan"),
) -> Result:
    """The :class:`Result` of a displacement state a failed or stopped solve left behind.

    Parameters
    ----------
    scene
        The scene solved.
    model
        ``spring`` or ``fem``.
    u
        The state's nodal displacement ``(n, 3)``.
    exc
        The solve's error (its text goes to ``info["error"]``; a ``load_factor`` on it is
        the load of this state).
    element, status
        The result's ``element`` and ``status`` labels.
    info
        More ``info`` entries (after ``error``).
    wall_time
        Seconds the solve ran.

    Returns
    -------
    Result
        Probes and volume change of ``u`` (none when it is not finite), ``load_factor``
        and, on a ventricle, the cavity at that load.
    """
    finite = bool(np.isfinite(u).all())
    res = Result(
        scene=scene.name,
        model=model,
        element=element,
        law="",
        counts={"nodes": scene.mesh.n_points, "tets": scene.mesh.n_tets},
        probes=scene.probe_displacements(u),
        volume=volume_summary(scene.mesh, u) if finite else {},
        reactions={},
        wall_time=float(wall_time),
        converged=False,
        iterations=0,
        info={"error": str(exc), **(info or {})},
        status=status,
    )
    load_factor = getattr(exc, "load_factor", None)
    if load_factor is not None and finite:
        res.info["load_factor"] = float(load_factor)  # the load of this state
        if is_ventricle(scene.mesh):
            res.info["cavity"] = cavity_summary(scene.mesh, u)
    return res


def write_last_good_state(
    out: Path, scene: Scene, model: str, exc: SolverError | SolveStopped
) -> str:
    """Write ``last_good_state.json``/``.vtu`` for a failed solve; say what was written.

    ``exc.state`` is the last good nodal displacement; a solve that failed before its first
    step (a singular system) has none, and its last good state is the initial one (zero).
    """
    initial = exc.state is None
    u = np.zeros((scene.mesh.n_points, 3)) if initial else np.asarray(exc.state).reshape(-1, 3)
    stopped = isinstance(exc, SolveStopped)
    res = state_result(
        scene, model, u, exc, element="last-good-state",
        status=str(exc) if stopped else "failed",
        info={"state": "initial" if initial else "last good"},
    )  # fmt: skip
    try:
        write_result(out, res, scene.mesh, u, stem="last_good_state")
    except OSError as err:
        what = "last state" if stopped else "last good state"
        return f"the {what} could not be written to {out}: {err.strerror or err}"
    if stopped:
        return f"last state written to {out}"
    what = "initial state (failed before the first step)" if initial else "last good state"
    return f"{what} written to {out}"


def warn(line: str) -> None:
    """One ``warning: …`` line on stderr."""
    print(f"warning: {line}", file=sys.stderr, flush=True)
