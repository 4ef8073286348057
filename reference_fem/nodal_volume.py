"""Linear tets with nodal volumes: ``[fem] formulation = "nodal-volume"`` (P1 only).

Bonet & Burton (1998, Commun. Numer. Meth. Engng 14: 437–449) measure the volume ratio at
the nodes: with rest volumes ``V_e^0`` and ``J_e = det F_e``,

    V_a^0 = sum_{e ∋ a} V_e^0 / 4,   J_a = sum_{e ∋ a} J_e V_e^0 / 4 / V_a^0.

The law is split as ``W = W_base(F) + U(J)`` (:mod:`reference_fem.volumetric_split`):
``W_base`` stays per element, and the volumetric energy is shared between the nodes and,
with the stabilisation fraction ``f`` (``[fem] stabilisation``, in the manner of Puso &
Solberg 2006), the element:

    Pi = sum_e V_e^0 (W_base(F_e) + f U(J_e)) + (1 - f) sum_a V_a^0 U(J_a) - work of loads.

Its gradient is the P1 force with the element pressure replaced by the average nodal
pressure (Bonet & Burton's ANP tet), ``p_e = (1 - f) mean_{a ∈ e} U'(J_a) + f U'(J_e)``:
``f_e = V_e^0 (P_base + p_e J F^-T) grad N``. The tangent adds to the P1 blocks the nodal
term ``(1 - f) sum_a U''(J_a) / V_a^0 (dV_a/dx)(dV_a/dx)^T``, which couples the nodes of
neighbouring patches (a wider stencil than P1); direct solves factorise it in its
nodal-pressure form (:mod:`reference_fem.nodal_pressure_solve`). ``f = 1`` is plain P1;
``f = 0`` is pure nodal averaging. The linear law is the small-strain limit, the split of
the coupled neo-Hookean energy: ``D(mu, f lam)`` per element, ``(1 - f) lam`` on the nodal volumes.
Manual: docs/fem.rst#nodal-volume-tetrahedra.

Examples
--------
>>> import numpy as np
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({
...     "mesh": {"generator": "box", "size": [1, 1, 1], "divisions": [2, 2, 2]},
...     "material": {"law": "neo-hookean", "E": 10.0, "nu": 0.49},
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
...     "fem": {"formulation": "nodal-volume", "stabilisation": 0.0}})
>>> p = NodalVolumeProblem(scene)
>>> p.law_name
'neo-hookean/coupled/nodal-volume'
>>> u = np.zeros(p.n_dofs)
>>> u[0::3] = 0.01 * p.space.node_coordinates[:, 0]  # a uniform stretch
>>> J = p.nodal_volume_ratio(u)
>>> bool(np.allclose(J, 1.01))  # every node sees the elements' J
True
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import scipy.sparse as sp

from springfem.errors import InputError
from springfem.materials import lame_matrix
from springfem.materials.laws.kinematics import det as _det
from springfem.scene import Scene

from .assembly import _gradient_products, linear_element_blocks
from .newton import InvertedElements
from .nodal_pressure_solve import NodalPressureSolver, with_nodal_parts
from .options import FemOptions
from .problem import FemProblem
from .volumetric_split import volumetric_split

_I = np.eye(3)


class NodalVolumeProblem(FemProblem):
    """P1 with the volumetric energy on nodal volumes (same protocol as FemProblem).

    Parameters
    ----------
    scene, order, law
        As for :class:`~reference_fem.problem.FemProblem`; ``order`` must be 1.
    stabilisation
        The share ``f`` of the volumetric energy kept per element (default
        ``FemOptions.of(scene).volumetric_share``).
    """

    locking_free = True
    #: The share of the law's element part measured on the element's own ``F`` (1 here;
    #: :mod:`reference_fem.nodal_strain` measures the rest on nodal-averaged strain).
    element_share = 1.0

    def __init__(
        self,
        scene: Scene,
        order: int | None = None,
        law: str | None = None,
        stabilisation: float | None = None,
    ):
        opts = FemOptions.of(scene)
        order = int(opts.order if order is None else order)
        if order != 1:
            raise InputError(f"formulation nodal-volume is for linear tets (order 1), got {order}")
        super().__init__(scene, 1, law, 1)
        # a LinearSolver by duck type: the augmented direct solve, else the wrapped solver
        self.linear_solver = NodalPressureSolver(self.linear_solver)  # type: ignore[assignment]
        self.fraction = float(opts.volumetric_share if stabilisation is None else stabilisation)
        if not 0.0 <= self.fraction <= 1.0:
            raise InputError(f"stabilisation must lie in [0, 1], got {self.fraction}")
        if self.kind == "transverse-linear":
            raise InputError(
                "formulation nodal-volume needs an isotropic or hyperelastic law, got "
                "transverse-linear"
            )
        self.split = None if self.law is None else volumetric_split(self.law, scene.material)
        self.law_name = f"{self.law_name}/nodal-volume"
        if self.law is not None and self.kind == "neo-hookean":
            self.law_name = f"{self.law.name}/nodal-volume"
        tets = self.space.element_nodes
        self.V0 = self.space.dx[:, 0]
        self.node_volume0 = np.bincount(
            tets.ravel(), np.repeat(self.V0 / 4.0, 4), minlength=self.space.n_nodes
        )
        self.G = self.space.grads[:, 0]  # (m, 4, 3)
        m = len(tets)
        self._rows = np.broadcast_to(tets[:, :, None, None], (m, 4, 4, 3)).ravel()
        self._cols = np.broadcast_to(
            (3 * tets[:, None, :, None] + np.arange(3)), (m, 4, 4, 3)
        ).ravel()

    # -- kinematics --------------------------------------------------------------------------
    def _F(self, u: np.ndarray) -> np.ndarray:
        U = np.asarray(u).reshape(-1, 3)
        return _I + np.einsum("eaj,eai->eij", self.G, U[self.space.element_nodes])

    def _nodal_j(self, J: np.ndarray) -> np.ndarray:
        tets = self.space.element_nodes
        V = np.bincount(tets.ravel(), np.repeat(self.V0 * J / 4.0, 4), self.space.n_nodes)
        return V / self.node_volume0

    def nodal_volume_ratio(self, u: np.ndarray) -> np.ndarray:
        """``J_a``, the volume ratio of each node's patch, ``(n_vertices,)``."""
        return self._nodal_j(_det(self._F(u)))

    def _check(self, J: np.ndarray, Ja: np.ndarray) -> None:
        bad = ~(J > 0) | ~(Ja[self.space.element_nodes] > 0).all(axis=1)
        if bad.any():
            ids = np.flatnonzero(bad)
            at = self.scene.mesh.points[self.scene.mesh.tets[ids[0]]].mean(axis=0)
            raise InvertedElements(ids, f"(first at x = {np.round(at, 6).tolist()})")

    def _volume_gradient_matrix(self, g: np.ndarray) -> sp.csr_matrix:
        """``dV_a/dx`` as a sparse ``(n_nodes, 3 n_nodes)`` matrix; ``g`` is ``J F^-T grad N``."""
        vals = np.broadcast_to((self.V0 / 4.0)[:, None, None, None] * g[:, None], (len(g), 4, 4, 3))
        n = self.space.n_nodes
        return sp.csr_matrix((vals.ravel(), (self._rows, self._cols)), shape=(n, 3 * n))

    # -- linear law ----------------------------------------------------------------------------
    @cached_property
    def stiffness(self) -> sp.csr_matrix:
        """Small-strain stiffness: ``D(mu, f lam)`` per element plus ``(1 - f) lam`` nodal."""
        mat, f = self.scene.material, self.fraction
        if self.split is not None:  # a hyperelastic law: its tangent at rest
            return self.internal_force(np.zeros(self.n_dofs), tangent=True)[1]
        D = lame_matrix(f * mat.lam, self.element_share * mat.mu)[None]
        blocks = linear_element_blocks(self.space.grads, self.space.dx, D, np.zeros(len(D), int))
        B = self._volume_gradient_matrix(self.G)
        w = (1.0 - f) * mat.lam / self.node_volume0
        return (self.pattern.matrix(blocks) + B.T @ sp.diags(w) @ B).tocsr()

    # -- the NonlinearProblem protocol ---------------------------------------------------------
    def _split_at(self, scale: float):
        """The law's split at load factor ``scale`` (an active tension ramps with it)."""
        if self.split is None or not getattr(self.law, "active_tension", 0.0):
            return self.split
        return volumetric_split(self.law_at(scale), self.scene.material)

    def internal_force(self, u: np.ndarray, tangent: bool = False, scale: float = 1.0):
        """``f_int(u)`` and (optionally) its tangent matrix at load factor ``scale``."""
        if self.split is None:
            return self.stiffness @ u, (self.stiffness if tangent else None)
        f, split = self.fraction, self._split_at(scale)
        F = self._F(u)
        J = _det(F)
        Ja = self._nodal_j(J)
        self._check(J, Ja)
        _, dUa, ddUa = split.volumetric(Ja)
        _, dUe, ddUe = split.volumetric(J)
        p = (1.0 - f) * dUa[self.space.element_nodes].mean(axis=1) + f * dUe  # (m,)
        frames = None if self.frames is None else self.frames
        if tangent:
            P, A = split.base.stress_tangent(F, frames=frames)
            A = self.element_share * A
        else:
            P, A = split.base.stress(F, frames=frames), None
        P = self.element_share * P
        FiT = np.swapaxes(np.linalg.inv(F), -1, -2)
        JFiT = J[:, None, None] * FiT
        P = P + p[:, None, None] * JFiT
        fe = np.einsum("e,eij,eaj->eai", self.V0, P, self.G)
        fi = self.pattern.vector(fe)
        if not tangent:
            return fi, None
        dJFiT = np.einsum("eij,ekl->eijkl", JFiT, FiT) - J[:, None, None, None, None] * np.einsum(
            "eil,ekj->eijkl", FiT, FiT
        )
        A = A + p[:, None, None, None, None] * dJFiT
        A = A + (f * ddUe)[:, None, None, None, None] * np.einsum("eij,ekl->eijkl", JFiT, JFiT)
        A9 = A.transpose(0, 2, 4, 1, 3).reshape(-1, 9, 9)  # rows (j, l), columns (i, k)
        Ke = np.matmul(_gradient_products(self.space.grads, self.space.dx), A9)
        K = self.pattern.matrix(Ke.reshape(-1, 4, 4, 3, 3)).tocsr()
        if f < 1.0:
            g = np.einsum("eij,eaj->eai", JFiT, self.G)
            B = self._volume_gradient_matrix(g)
            d = (1.0 - f) * ddUa / self.node_volume0
            Ke = K
            K = K + B.T.tocsr() @ (B.multiply(d[:, None]).tocsr())
            K = with_nodal_parts(K, Ke, B, d)
        return fi, K

    def energy(self, u: np.ndarray, scale: float = 1.0) -> float | None:
        """``Pi(u)``: element energies, nodal volumetric energy, minus the dead loads' work."""
        if self.loads.has_follower:
            return None
        if self.split is None:
            return super().energy(u, scale)
        F = self._F(u)
        J = _det(F)
        Ja = self._nodal_j(J)
        if not ((J > 0).all() and (Ja > 0).all()):
            return np.nan
        W = self._split_at(scale).base.energy(F, frames=self.frames)
        Ue = self.split.volumetric(J)[0]
        Ua = self.split.volumetric(Ja)[0]
        f = self.fraction
        total = self.V0 @ (self.element_share * W + f * Ue) + (1.0 - f) * (self.node_volume0 @ Ua)
        return float(total) - scale * float(self.loads.dead @ u)

    def residual_tangent(self, u: np.ndarray, scale: float = 1.0):
        """Residual, tangent (CSR), whether it is symmetric, and the force scale."""
        fi, K = self.internal_force(u, tangent=True, scale=scale)
        fe, Kf = self.loads.vector_and_stiffness(u.reshape(-1, 3), scale)
        if Kf is not None:
            parts = getattr(K, "nodal_parts", None)
            K = (K - Kf).tocsr()
            if parts is not None:
                K = with_nodal_parts(K, (parts[0] - Kf).tocsr(), parts[1], parts[2])
        return fi - fe, K, Kf is None, self.force_scale(fi, fe, scale)

    def cell_data(self, u: np.ndarray) -> dict[str, np.ndarray]:
        """``J``, von Mises stress of the element part and the element's mean nodal ``J``."""
        out = super().cell_data(u) if self.split is None else self._cell_data(u)
        out["nodal_J"] = self.nodal_volume_ratio(u)[self.space.element_nodes].mean(axis=1)
        return out

    def _cell_data(self, u: np.ndarray) -> dict[str, np.ndarray]:
        F = self._F(u)
        assert self.split is not None  # a hyperelastic law
        sigma = self.split.base.cauchy(F, frames=self.frames)
        s = sigma - np.trace(sigma, axis1=-2, axis2=-1)[..., None, None] * _I / 3.0
        return {"J": _det(F), "von_mises": np.sqrt(1.5 * np.einsum("eij,eij->e", s, s))}
