"""The FEM reference solve: a scene in, a :class:`~springfem.result.Result` out.

:class:`FemProblem` gathers the space (P1 or P2 on the scene's vertices), the material
law, the constraints and the loads, and evaluates residual ``R = f_int - f_ext`` and
tangent. :func:`solve` runs one linear solve (linear laws) or Newton with adaptive load
stepping (neo-Hookean) and fills the result contract of DESIGN §6.

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
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from springfem.errors import InputError, SolverError
from springfem.materials import voigt_to_tensor
from springfem.mechanics import LinearSolver, rigid_body_modes
from springfem.result import Result, frame_cell_data, volume_summary
from springfem.scene import FORMULATIONS, VOLUMETRIC, Scene

from .assembly import (
    BlockPattern,
    displacement_gradient,
    hyperelastic_element_arrays,
    linear_element_blocks,
)
from .cavity import cavity_recorder
from .constraints import check_rigid_motions, dirichlet
from .hyperelastic import NeoHookean, _det
from .laws import TISSUE_LAWS, TissueLaw, tissue_law
from .loads import ExternalLoads
from .materials import material_groups
from .newton import InvertedElements, NewtonOptions, solve_nonlinear
from .options import FemOptions
from .space import Space, default_intorder

LINEAR_LAWS = ("linear", "transverse-linear")
LAW_NAMES = (
    ("linear", "transverse-linear", "neo-hookean", "neo-hookean/coupled")
    + tuple(f"neo-hookean/uncoupled/{v}" for v in VOLUMETRIC)
    + tuple(TISSUE_LAWS)
)


def parse_law(scene: Scene, law: str | None) -> tuple[str, NeoHookean | TissueLaw | None]:
    """Resolve a law name (default: the scene's) to a kind and, if nonlinear, a law object.

    ``neo-hookean`` takes the formulation and volumetric function of the scene's material;
    ``neo-hookean/coupled`` or ``neo-hookean/uncoupled[/log|quadratic|simo-taylor]``
    override them.
    """
    mat = scene.material
    name = law or mat.law
    kind, _, rest = name.partition("/")
    if kind in TISSUE_LAWS or mat.law in TISSUE_LAWS:  # issue 11: tissue laws
        if rest or kind != mat.law:
            raise InputError(f"law {name!r} does not apply to {mat.law}; use law {mat.law}")
        return kind, tissue_law(mat)
    if kind not in ("linear", "transverse-linear", "neo-hookean"):
        raise InputError(f"law {name!r} is not one of {', '.join(LAW_NAMES)}")
    if kind == "transverse-linear":
        if rest or mat.E_fiber is None:
            raise InputError(
                f"law {name!r} needs a transverse-linear material (E_fiber, E_cross, "
                "nu_fiber_cross, nu_cross, G_fiber)"
            )
        return kind, None
    if mat.law == "transverse-linear":
        raise InputError(
            f"law {name!r} is isotropic but the scene's material is transverse-linear; "
            "use law transverse-linear"
        )
    if kind == "linear":
        if rest:
            raise InputError(f"law {name!r} is not one of {', '.join(LAW_NAMES)}")
        return kind, None
    form, _, vol = rest.partition("/")
    if form and form not in FORMULATIONS:
        raise InputError(f"formulation {form!r} is not one of {', '.join(FORMULATIONS)}")
    if vol and (form != "uncoupled" or vol not in VOLUMETRIC):
        raise InputError(f"law {name!r} is not one of {', '.join(LAW_NAMES)}")
    return kind, NeoHookean.from_material(mat, form or None, vol or None)


class FemProblem:
    """Discrete problem of a scene: space, law, constraints, loads and linear solver.

    Parameters
    ----------
    scene
        The scene.
    order
        1 or 2 (default ``FemOptions.of(scene).order``).
    law
        Law name (default ``scene.material.law``), see :func:`parse_law`.
    intorder
        Quadrature order (default: 1 for P1, 2 (4 points) for P2).
    """

    mixed = False  # the u-p formulation is reference_fem.mixed.MixedProblem

    def __init__(
        self,
        scene: Scene,
        order: int | None = None,
        law: str | None = None,
        intorder: int | None = None,
    ):
        self.scene = scene
        self.order = int(FemOptions.of(scene).order if order is None else order)
        self.kind, self.law = parse_law(scene, law)
        self.nonlinear = self.law is not None
        if scene.material.incompressible and not self.mixed:
            raise InputError('incompressible = true needs [fem] formulation = "mixed"')
        # per-element frames for anisotropic laws (issue 11), broadcast over quadrature
        self.frames = scene.frames if getattr(self.law, "anisotropic", False) else None
        self.qframes = None if self.frames is None else self.frames[:, None]
        self.law_name = self.law.name if self.law is not None else self.kind
        q = default_intorder(self.order, self.nonlinear) if intorder is None else intorder
        self.space = Space(scene.mesh, self.order, q)
        self.pattern = BlockPattern(self.space.element_nodes, self.space.n_nodes)
        self.bc = dirichlet(scene, self.space)
        self.loads = ExternalLoads.from_scene(scene, self.space, follower=self.nonlinear)
        self.linear_solver = LinearSolver(
            FemOptions.of(scene).linear_solver,
            near_nullspace=rigid_body_modes(self.space.node_coordinates),
        )
        if not self.nonlinear:
            self.D_groups, self.group = material_groups(scene.material, scene.frames, self.kind)
        else:
            self.D_groups, self.group = material_groups(scene.material, scene.frames, "linear")

    # -- the NonlinearProblem protocol ------------------------------------------------------
    @property
    def n_dofs(self) -> int:
        return self.space.n_dofs

    @cached_property
    def free(self) -> np.ndarray:
        return self.bc.free

    @property
    def fixed_dofs(self) -> np.ndarray:
        return self.bc.dofs

    @property
    def fixed_values(self) -> np.ndarray:
        return self.bc.values

    @cached_property
    def stiffness(self) -> sp.bsr_matrix:
        """Small-strain stiffness matrix (the linear law, or the neo-Hookean tangent at 0)."""
        blocks = linear_element_blocks(self.space.grads, self.space.dx, self.D_groups, self.group)
        return self.pattern.matrix(blocks)

    def internal_force(self, u: np.ndarray, tangent: bool = False):
        """``f_int(u)`` and (optionally) its tangent matrix."""
        if not self.nonlinear:
            return self.stiffness @ u, (self.stiffness if tangent else None)
        fe, Ke = hyperelastic_element_arrays(
            self.space, self.law, u.reshape(-1, 3), tangent, self.frames
        )
        bad = ~np.isfinite(fe).all(axis=(1, 2))
        if bad.any():
            ids = np.flatnonzero(bad)
            at = self.scene.mesh.points[self.scene.mesh.tets[ids[0]]].mean(axis=0)
            raise InvertedElements(ids, f"(first at x = {np.round(at, 6).tolist()})")
        return self.pattern.vector(fe), (self.pattern.matrix(Ke) if tangent else None)

    def residual(self, u: np.ndarray, scale: float = 1.0) -> tuple[np.ndarray, float]:
        """``R = f_int - f_ext`` and the force scale ``max(|f_int|, |f_ext|)``."""
        fi, _ = self.internal_force(u)
        fe = self.loads.vector(u.reshape(-1, 3), scale)
        return fi - fe, max(np.linalg.norm(fi), np.linalg.norm(fe))

    def energy(self, u: np.ndarray, scale: float = 1.0) -> float | None:
        """Potential energy ``int psi dV - f_dead . u``; ``None`` with follower loads."""
        if self.loads.has_follower:
            return None
        if not self.nonlinear:
            return 0.5 * float(u @ (self.stiffness @ u)) - scale * float(self.loads.dead @ u)
        F = np.eye(3) + displacement_gradient(self.space, np.asarray(u).reshape(-1, 3))
        psi = self.law.energy(F, frames=self.qframes)
        return float((self.space.dx * psi).sum()) - scale * float(self.loads.dead @ u)

    def residual_tangent(self, u: np.ndarray, scale: float = 1.0):
        """Residual, tangent ``dR/du``, whether it is symmetric, and the force scale."""
        fi, K = self.internal_force(u, tangent=True)
        fe, Kf = self.loads.vector_and_stiffness(u.reshape(-1, 3), scale)
        if Kf is not None:
            K = (K - Kf).tobsr(blocksize=(3, 3))
        ref = max(np.linalg.norm(fi), np.linalg.norm(fe))
        return fi - fe, K, Kf is None, ref

    def solve_linear(self, K, b: np.ndarray, symmetric: bool = True, where: str = ""):
        return self.linear_solver.solve(K, b, self.free, symmetric, where)

    def state(self, u: np.ndarray) -> np.ndarray:
        """Vertex displacements ``(n_vertices, 3)`` of a DOF vector."""
        return np.asarray(u).reshape(-1, 3)[: self.space.n_vertices].copy()

    # -- post-processing ---------------------------------------------------------------------
    def probe_values(self, u: np.ndarray) -> dict[str, list[float]]:
        """Displacement at each scene probe, interpolated with the FE shape functions."""
        probes = self.scene.probes
        if not probes:
            return {}
        P = self.space.interpolation_matrix(
            np.array([p.tet for p in probes]), np.array([p.point for p in probes])
        )
        vals = P @ np.asarray(u).reshape(-1, 3)
        return {p.name: vals[i].tolist() for i, p in enumerate(probes)}

    def cell_data(self, u: np.ndarray) -> dict[str, np.ndarray]:
        """Per-element volume ratio ``J`` and von Mises (Cauchy) stress, quadrature averages."""
        H = displacement_gradient(self.space, np.asarray(u).reshape(-1, 3))
        F = np.eye(3) + H
        w = self.space.dx / self.space.dx.sum(axis=1, keepdims=True)
        if self.nonlinear:
            sigma = self.law.cauchy(F, frames=self.qframes)
        else:
            C = voigt_to_tensor(self.D_groups)[self.group]  # (m, 3, 3, 3, 3)
            eps = 0.5 * (H + np.swapaxes(H, -1, -2))
            sigma = np.einsum("eijkl,eqkl->eqij", C, eps)
        s = sigma - np.trace(sigma, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) / 3.0
        vm = np.sqrt(1.5 * np.einsum("eqij,eqij->eq", s, s))
        return {"J": (w * _det(F)).sum(axis=1), "von_mises": (w * vm).sum(axis=1)}

    def p2_volume(self, u: np.ndarray) -> float:
        """Exact deformed volume of the P2 field, ``int det(I + grad u) dX`` (degree 3)."""
        space = self.space if self.space.intorder >= 3 else Space(self.scene.mesh, 2, 3)
        F = np.eye(3) + displacement_gradient(space, np.asarray(u).reshape(-1, 3))
        return float((space.dx * _det(F)).sum())


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
    """Small-strain solve ``K u = f`` with the prescribed values."""
    K = problem.stiffness
    u = np.zeros(problem.n_dofs)
    u[problem.fixed_dofs] = problem.fixed_values
    b = problem.loads.vector(None, 1.0) - K @ u
    return u + problem.solve_linear(K, b, True, "linear solve: ")


def make_problem(scene: Scene, order: int | None = None, law: str | None = None) -> FemProblem:
    """:class:`FemProblem`, or the mixed u-p problem for ``[fem] formulation = "mixed"``."""
    if FemOptions.of(scene).formulation == "mixed":
        from .mixed import MixedProblem

        return MixedProblem(scene, order, law)
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
            f"{scene.name} (fem P{problem.order}, {problem.law_name}): {exc}", state=exc.state
        ) from None


def _solve(problem: FemProblem, verbose: bool, t0: float) -> FemSolution:
    scene = problem.scene
    check_rigid_motions(problem.space, problem.fixed_dofs)
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
        opts = NewtonOptions(fem.tol, fem.max_iter, fem.load_steps, verbose=verbose, on_step=pv)
        u, report = solve_nonlinear(problem, opts)
        if pv is not None:
            info["cavity"] = pv.summary(problem.state(u), u)
        iterations = report.iterations
        info["newton"] = report.steps
        info["load_steps"] = len(report.steps)
        info["cutbacks"] = report.cutbacks
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
    info["krylov_iterations"] = problem.linear_solver.stats["krylov_iterations"]
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
