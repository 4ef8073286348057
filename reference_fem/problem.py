"""The discrete FEM problem of a scene: space, law, constraints, loads and linear solver.

:class:`FemProblem` evaluates the residual ``R = f_int - f_ext``, its tangent and the
energy for :mod:`springfem.mechanics` (the ``NonlinearProblem`` protocol), and the
post-processed fields (probes, ``J``, von Mises stress).

Examples
--------
>>> import numpy as np
>>> from springfem.mesh import box_mesh
>>> from springfem.scene import Material, scene_from_dict
>>> scene = scene_from_dict({
...     "mesh": box_mesh((1.0, 1.0, 1.0), (1, 1, 1)),
...     "material": Material("linear", 100.0, 0.3),
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}]})
>>> p = FemProblem(scene, order=1)
>>> p.n_dofs, p.fixed_dofs.size  # 8 vertices, the 4 on x = 0 fixed
(24, 12)
>>> R, scale = p.residual(np.zeros(p.n_dofs))  # no load: in equilibrium at rest
>>> float(abs(R).max()), float(scale)
(0.0, 0.0)
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import scipy.sparse as sp

from springfem.errors import InputError
from springfem.materials import voigt_to_tensor
from springfem.materials.laws.kinematics import det as _det
from springfem.mechanics import LinearSolver, rigid_body_modes
from springfem.scene import Scene

from .assembly import (
    BlockPattern,
    displacement_gradient,
    hyperelastic_element_arrays,
    linear_element_blocks,
)
from .constraints import dirichlet
from .law_names import parse_law
from .loads import ExternalLoads
from .materials import material_groups
from .newton import InvertedElements
from .options import FemOptions
from .point_fibres import quadrature_frames
from .space import Space, default_intorder, edge_list


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
    locking_free = False  # a formulation that takes a penalty for incompressible materials

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
        if scene.material.incompressible and not (self.mixed or self.locking_free):
            raise InputError(
                'incompressible = true needs [fem] formulation = "mixed", "nodal-volume", '
                '"nodal-strain" or "mini"'
            )
        # per-element frames for anisotropic laws, broadcast over quadrature
        self.frames = scene.frames if getattr(self.law, "anisotropic", False) else None
        self.qframes = None if self.frames is None else self.frames[:, None]
        self.law_name = self.law.name if self.law is not None else self.kind
        self.space = self._make_space(scene, intorder)
        if self.frames is not None:  # rule-based fibres: one per quadrature point (P2)
            point_frames = quadrature_frames(scene, self.space)
            if point_frames is not None:
                self.qframes = point_frames
        self.pattern = BlockPattern(self.space.element_nodes, self.space.n_nodes)
        self.bc = dirichlet(scene, self.space)
        self.loads = ExternalLoads.from_scene(scene, self.space, follower=self.nonlinear)
        self.linear_solver = LinearSolver(
            FemOptions.of(scene).linear_solver,
            near_nullspace=rigid_body_modes(self.space.node_coordinates),
            saddle_point=self.mixed,
        )
        if not self.nonlinear:
            self.D_groups, self.group = material_groups(scene.material, scene.frames, self.kind)
        else:
            self.D_groups, self.group = material_groups(scene.material, scene.frames, "linear")

    def _make_space(self, scene: Scene, intorder: int | None) -> Space:
        """The displacement space (a subclass may enrich it, :mod:`reference_fem.mini`)."""
        if intorder is None:
            intorder = FemOptions.of(scene).intorder
        q = default_intorder(self.order, self.nonlinear) if intorder is None else intorder
        return Space(scene.mesh, self.order, q, curved_edge_nodes_of(scene))

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

    def law_at(self, scale: float = 1.0):
        """The law at load factor ``scale``: an active tension ramps with the loads
        (docs/fem.rst#active-tension); other laws are load independent."""
        activated = getattr(self.law, "activated", None)
        return self.law if activated is None else activated(scale)

    @cached_property
    def active_force(self) -> float:
        """``|f_int(0)|`` at full activation: the size of the active tension's nodal forces
        (0 without one). It joins the force scale of the Newton stop, which ``|f_int|``
        and ``|f_ext|`` alone would lose where the active and passive stresses cancel."""
        if not getattr(self.law, "active_tension", 0.0):
            return 0.0
        return float(np.linalg.norm(self.internal_force(np.zeros(self.n_dofs))[0]))

    def force_scale(self, fi: np.ndarray, fe: np.ndarray, scale: float) -> float:
        """``max(|f_int|, |f_ext|, scale |f_active|)``, the reference of the Newton stop."""
        return max(float(np.linalg.norm(fi)), float(np.linalg.norm(fe)), scale * self.active_force)

    def internal_force(self, u: np.ndarray, tangent: bool = False, scale: float = 1.0):
        """``f_int(u)`` and (optionally) its tangent matrix at load factor ``scale``."""
        if not self.nonlinear:
            return self.stiffness @ u, (self.stiffness if tangent else None)
        fe, Ke = hyperelastic_element_arrays(
            self.space, self.law_at(scale), u.reshape(-1, 3), tangent, self.qframes
        )
        bad = ~np.isfinite(fe).all(axis=(1, 2))
        if bad.any():
            ids = np.flatnonzero(bad)
            at = self.scene.mesh.points[self.scene.mesh.tets[ids[0]]].mean(axis=0)
            raise InvertedElements(ids, f"(first at x = {np.round(at, 6).tolist()})")
        if not tangent:
            return self.pattern.vector(fe), None
        assert Ke is not None  # asked for
        return self.pattern.vector(fe), self.pattern.matrix(Ke)

    def residual(self, u: np.ndarray, scale: float = 1.0) -> tuple[np.ndarray, float]:
        """``R = f_int - f_ext`` and the force scale (:meth:`force_scale`)."""
        fi, _ = self.internal_force(u, scale=scale)
        fe = self.loads.vector(u.reshape(-1, 3), scale)
        return fi - fe, self.force_scale(fi, fe, scale)

    def energy(self, u: np.ndarray, scale: float = 1.0) -> float | None:
        """Potential energy ``int psi dV - f_dead . u``; ``None`` with follower loads."""
        if self.loads.has_follower:
            return None
        if not self.nonlinear:
            return 0.5 * float(u @ (self.stiffness @ u)) - scale * float(self.loads.dead @ u)
        F = np.eye(3) + displacement_gradient(self.space, np.asarray(u).reshape(-1, 3))
        psi = self.law_at(scale).energy(F, frames=self.qframes)
        return float((self.space.dx * psi).sum()) - scale * float(self.loads.dead @ u)

    def residual_tangent(self, u: np.ndarray, scale: float = 1.0):
        """Residual, tangent ``dR/du``, whether it is symmetric, and the force scale."""
        fi, K = self.internal_force(u, tangent=True, scale=scale)
        fe, Kf = self.loads.vector_and_stiffness(u.reshape(-1, 3), scale)
        if Kf is not None:
            K = (K - Kf).tobsr(blocksize=(3, 3))
        return fi - fe, K, Kf is None, self.force_scale(fi, fe, scale)

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
        if self.law is not None:
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


def curved_edge_nodes_of(scene: Scene) -> np.ndarray | None:
    """The P2 edge nodes of ``[fem] geometry = "curved"`` (``None`` when straight).

    The scene's mesh must come from ``[mesh] generator = "ellipsoid"``: its ``endo``,
    ``epi`` and ``base_z`` give the surfaces (:func:`springfem.ellipsoid.curved_edge_nodes`).
    """
    if FemOptions.of(scene).geometry != "curved":
        return None
    from springfem import ellipsoid

    table = scene.raw.get("mesh") or {}
    if table.get("generator") != "ellipsoid":
        raise InputError(
            'fem.geometry = "curved" needs [mesh] generator = "ellipsoid", got '
            f"{table.get('generator', 'a mesh file')!r}"
        )
    endo = tuple(table.get("endo", ellipsoid.ENDO))
    epi = tuple(table.get("epi", ellipsoid.EPI))
    base_z = float(table.get("base_z", ellipsoid.BASE_Z))
    return ellipsoid.curved_edge_nodes(scene.mesh, edge_list(scene.mesh), endo, epi, base_z)
