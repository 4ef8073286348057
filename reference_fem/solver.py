"""The FEM reference solve: a scene in, a :class:`~springfem.result.Result` out.

:class:`FemProblem` gathers the space (P1 or P2 on the scene's vertices), the material
law, the constraints and the loads, and evaluates residual ``R = f_int - f_ext`` and
tangent. :func:`solve` runs one linear solve (linear laws) or Newton with adaptive load
stepping (neo-Hookean) and fills the result contract of docs/contract.rst#result-fields

Examples
--------
>>> from springfem.scene import parse_scene
>>> scene = parse_scene('''
... [mesh]
... generator = "box"
... size = [1.0, 1.0, 1.0]
... divisions = [2, 2, 2]
... [material]
... law = "linear"
... E = 100.0
... nu = 0.0
... [[boundary]]
... region = "x_min"
... fix = ["x", "y", "z"]
... [[load]]
... type = "traction"
... region = "x_max"
... value = [1.0, 0.0, 0.0]
... [[probe]]
... name = "end"
... point = [1.0, 0.5, 0.5]
... ''')
>>> sol = solve(scene, order=1)
>>> round(sol.result.probes["end"][0], 12), round(sol.result.reactions["x_min"][0], 12)
(0.01, -1.0)
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from springfem.errors import SolverError
from springfem.mechanics.memory import MemoryLimitExceeded, memory_limit, resident_bytes
from springfem.result import Result, frame_cell_data, volume_summary
from springfem.scene import Scene

from .cavity import cavity_recorder
from .constraints import check_rigid_motions
from .newton import NewtonOptions, solve_nonlinear
from .options import FemOptions
from .problem import FemProblem

#: Modified Newton for the mixed formulation (``NewtonOptions.reuse``): its tangent costs
#: about 13 residual evaluations and a factorisation, so reusing the last factorisation
#: while each iteration cuts the residual at least fourfold does the same solve (to the
#: same tolerance) in a third less CPU time on Land's ventricle and a fifth less on the
#: beam; the displacement formulation keeps a fresh tangent (quadratic convergence).
MIXED_REUSE = 0.25


@dataclass
class FemSolution:
    """A FEM solve: the result contract plus the fields for output and further study.

    Attributes
    ----------
    result
        :class:`~springfem.result.Result` (``model = "fem"``).
    u_vertices
        ``(n_vertices, 3)`` displacement at the mesh vertices.
    u
        Full DOF vector (``3 * node + component``; P2 edge nodes after the vertices).
    cell_data
        Per-element arrays for the VTU file (``J``, ``von_mises``).
    problem
        The :class:`FemProblem` (space, assembly, loads) for further evaluation.
    """

    result: Result
    u_vertices: np.ndarray
    u: np.ndarray
    cell_data: dict[str, np.ndarray] = field(default_factory=dict)
    problem: FemProblem | None = field(default=None, repr=False)


def solve_linear_problem(problem: FemProblem) -> np.ndarray:
    """Small-strain solve ``K u = f`` with the prescribed values.

    Parameters
    ----------
    problem
        A problem with a linear law (its :attr:`FemProblem.stiffness` is the operator).

    Returns
    -------
    ndarray
        DOF vector ``(n_dofs,)`` (m): the prescribed values on the fixed DOFs, the solution
        of ``K_ff u_f = f_f - K_fc u_c`` on the free ones.

    Raises
    ------
    SolverError
        If the linear solve fails (singular or not converged).
    """
    K = problem.stiffness
    u = np.zeros(problem.n_dofs)
    u[problem.fixed_dofs] = problem.fixed_values
    b = problem.loads.vector(None, 1.0) - K @ u
    return u + problem.solve_linear(K, b, True, "linear solve: ")


def make_problem(scene: Scene, order: int | None = None, law: str | None = None) -> FemProblem:
    """The discrete problem of a scene: displacement-only, or mixed u-p.

    Parameters
    ----------
    scene
        The scene; ``[fem] formulation`` ``"mixed"`` selects the Taylor–Hood problem,
        ``"nodal-volume"`` the nodal-volume P1 problem, ``"nodal-strain"`` the nodal-strain
        P1 problem, ``"mini"`` the MINI pair.
    order, law
        As for :class:`~reference_fem.problem.FemProblem`.

    Returns
    -------
    FemProblem
        A :class:`~reference_fem.problem.FemProblem`, or a
        :class:`~reference_fem.mixed.MixedProblem` (its subclass) for the mixed formulation.

    Raises
    ------
    InputError
        Unknown law or order, a law the material cannot provide, or an incompressible
        material without the mixed formulation.
    """
    formulation = FemOptions.of(scene).formulation
    if formulation == "mixed":
        from .mixed import MixedProblem

        return MixedProblem(scene, order, law)
    if formulation == "mini":
        from .mini import MiniProblem

        return MiniProblem(scene, order, law)
    if formulation == "nodal-volume":
        from .nodal_volume import NodalVolumeProblem

        return NodalVolumeProblem(scene, order, law)
    if formulation == "nodal-strain":
        from .nodal_strain import NodalStrainProblem

        return NodalStrainProblem(scene, order, law)
    return FemProblem(scene, order, law)


def solve(
    scene: Scene, order: int | None = None, law: str | None = None, verbose: bool = False
) -> FemSolution:
    """Solve a scene with the FEM reference.

    Parameters
    ----------
    scene
        The scene (mesh, material, boundaries, loads, probes, ``[fem]`` options).
    order
        1 (P1) or 2 (P2); default ``FemOptions.of(scene).order``.
    law
        ``linear``, ``transverse-linear``, ``neo-hookean`` (with the material's formulation),
        ``neo-hookean/coupled`` or ``neo-hookean/uncoupled/<log|quadratic|simo-taylor>``;
        default ``scene.material.law``.
    verbose
        Print the Newton residual history to stderr.

    Returns
    -------
    FemSolution
        The result contract, vertex displacements, DOF vector, cell data and the problem.

    Raises
    ------
    InputError
        Unknown law or order, or a law the material cannot provide.
    SolverError
        Singular system (rigid-body motion left free), failed linear solve, or Newton
        failure; ``.state`` holds the last converged vertex displacements when there is one.
    """
    t0 = time.perf_counter()
    problem = make_problem(scene, order, law)
    try:
        return _solve(problem, verbose, t0)
    except SolverError as exc:
        raise SolverError(
            f"{scene.name} (fem P{problem.order}, {problem.law_name}): {exc}",
            state=exc.state,
            load_factor=exc.load_factor,
        ) from None


#: Bytes per tangent entry an iterative solve holds at its peak, the assembly's element
#: arrays included: the organ's P2/P1 solve at 30k tets peaked at 1.89 GB with 12.7M
#: entries over the 0.40 GB of the problem (117 bytes per entry).
PEAK_BYTES_PER_NNZ = 120.0


def check_memory(problem: FemProblem) -> None:
    """Refuse, before it starts, a solve that cannot fit the memory limit even iteratively.

    The tangent's entries are counted from the displacement pattern (``9`` per node pair,
    a tenth more for a mixed problem's pressure coupling); the solve holds about
    :data:`PEAK_BYTES_PER_NNZ` bytes per entry at its peak (assembly arrays, the matrix and
    its copies, the AMG hierarchy), on top of what the process holds.

    Parameters
    ----------
    problem
        The discrete problem.

    Raises
    ------
    MemoryLimitExceeded
        The estimate is over :func:`~springfem.mechanics.memory.memory_limit`.
    """
    nnz = 9.0 * problem.pattern.indices.size * (1.1 if problem.mixed else 1.0)
    held = resident_bytes()
    need = held + PEAK_BYTES_PER_NNZ * nnz
    limit = memory_limit()
    if need > limit:
        raise MemoryLimitExceeded(
            f"{problem.scene.name} (fem P{problem.order}, {problem.law_name}, "
            f"{problem.n_dofs} DOFs): the solve needs about {need / 1e9:.2f} GB even with "
            f"an iterative linear solver, over the memory limit of {limit / 1e9:.2f} GB "
            "(SPRINGFEM_MAX_MEMORY, or free memory)"
        )


def _solve(problem: FemProblem, verbose: bool, t0: float) -> FemSolution:
    scene = problem.scene
    check_rigid_motions(problem.space, problem.fixed_dofs)
    check_memory(problem)
    info: dict = {
        "vertices": problem.space.n_vertices,
        "intorder": problem.space.intorder,
        "linear_solver": problem.linear_solver.kind(problem.n_dofs),
    }
    if not problem.nonlinear:
        u = solve_linear_problem(problem)
        iterations = 1
        if problem.loads.pressures:
            info["pressure"] = "reference surface (small-strain law)"
    else:
        fem, pv = FemOptions.of(scene), cavity_recorder(problem)  # P2: the quadratic facets
        opts = NewtonOptions(
            fem.tol, fem.max_iter, fem.load_steps, verbose=verbose, on_step=pv,
            reuse=MIXED_REUSE if problem.mixed else 0.0,
        )  # fmt: skip
        u, report = solve_nonlinear(problem, opts)
        if pv is not None:
            info["cavity"] = pv.summary(problem.state(u), u)
        iterations = report.iterations
        info["newton"] = report.steps
        info["load_steps"] = len(report.steps)
        info["cutbacks"] = report.cutbacks
        info["phase_seconds"] = report.phases.summary()  # wall seconds per phase
        if problem.loads.pressures:
            info["pressure"] = "follower (current surface)"
    R, _ = problem.residual(u, 1.0)
    reactions = problem.bc.reactions(R)
    u_vertices = problem.state(u)
    probes = problem.probe_values(u)
    volume = volume_summary(scene.mesh, u_vertices)
    if problem.order == 2:
        info["volume_p2"] = problem.p2_volume(u)
    cell_data = {**problem.cell_data(u), **frame_cell_data(scene, u_vertices)}
    stats = problem.linear_solver.stats
    info["krylov_iterations"] = stats["krylov_iterations"]
    if stats["krylov_iterations"]:
        info["krylov_solver"] = problem.linear_solver.name
    if getattr(problem.linear_solver, "reason", ""):
        info["direct_refused"] = problem.linear_solver.reason
    if stats["factorizations"]:
        info["direct_solver"] = problem.linear_solver.direct.backend
        info["factorizations"] = stats["factorizations"]
        info["symbolic_analyses"] = stats["analyses"]
    note = getattr(problem.linear_solver, "note", None)  # reference_fem.nodal_pressure_solve
    if note:
        info["nodal_pressure"] = note
    wall = time.perf_counter() - t0
    result = Result(
        scene=scene.name,
        model="fem",
        element=f"P{problem.order}",
        law=problem.law_name,
        counts={
            "nodes": int(problem.space.n_nodes),
            "tets": int(scene.mesh.n_tets),
            "dofs": int(problem.n_dofs),
            "fixed_dofs": int(problem.fixed_dofs.size),
        },
        probes=probes,
        volume=volume,
        reactions=reactions,
        wall_time=wall,
        converged=True,
        iterations=iterations,
        info=info,
    )
    return FemSolution(result, u_vertices, u, cell_data, problem)
