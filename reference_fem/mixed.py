"""Mixed u–p formulation: Taylor–Hood P2 displacement / P1 pressure (``[fem] formulation
= "mixed"``), for incompressible (``incompressible = true``) or nearly incompressible tissue.

The potential is ``Pi(u, p) = int W(F) - p (J - 1) - p^2 / (2 kappa) dX - work of the
loads``, with ``W`` the law without its volumetric energy (``kappa = inf`` when
incompressible: ``J = 1`` weakly): :func:`~reference_fem.volumetric_split.volumetric_split`
of a tissue law or of neo-Hookean (uncoupled: the isochoric part and its ``kappa``; coupled:
``mu/2 (I1 - 3) - mu ln J`` and ``kappa = lam``). Eliminating ``p`` leaves the volumetric
energy ``kappa/2 (J - 1)^2`` whatever the law's ``U``; both agree at small strain. Its
stationarity gives the block system

    [K_uu  K_up] [du]     [R_u]        R_u = int (P_W - p J F^-T) : grad du* dX - f_ext
    [K_pu  K_pp] [dp] = - [R_p],       R_p = -int (J - 1 + p / kappa) p* dX,

``K_up = -int J F^-T : grad du* p dX = K_pu^T``, ``K_pp = -int p* p / kappa dX``,
``K_uu = int grad du* : (A_W - p d(J F^-T)/dF) : grad du dX`` (minus the follower-pressure
stiffness). DOFs: the ``3 n_nodes`` displacement DOFs of the P2 space, then one pressure
per mesh vertex. The saddle-point system is factorised (``LinearSolver(saddle_point=True)``),
or, when that is too large, solved by GMRES with a block preconditioner whose Schur
complement approximation is the lumped pressure mass matrix times ``1/(2 mu) + 1/kappa``
(:meth:`MixedProblem.schur_diagonal`, :mod:`springfem.mechanics.saddle`).

Examples
--------
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({
...     "mesh": {"generator": "box", "size": [1, 1, 1], "divisions": [1, 1, 1]},
...     "material": {"law": "guccione", "C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0,
...                  "incompressible": True},
...     "boundary": [{"region": "x_min", "fix": ["x"]}, {"region": "y_min", "fix": ["y"]},
...                  {"region": "z_min", "fix": ["z"]}],
...     "load": [{"type": "traction", "region": "x_max", "value": [1.0, 0.0, 0.0]}],
...     "fem": {"formulation": "mixed", "order": 2}})
>>> import numpy as np
>>> problem = MixedProblem(scene)
>>> problem.law_name, problem.n_dofs - problem.nu == scene.mesh.n_points  # a p per vertex
('guccione/mixed-P2P1', True)
>>> f = problem.internal_force(np.zeros(problem.n_dofs))[0]
>>> float(np.abs(f).max())  # the rest state is stress-free and volume-preserving
0.0
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import scipy.sparse as sp
import skfem

from springfem.errors import InputError
from springfem.materials.laws import TissueLaw
from springfem.materials.laws.kinematics import det as _det
from springfem.scene import Scene

from .assembly import CHUNK, _gradient_products, displacement_gradient
from .options import FemOptions
from .problem import FemProblem
from .volumetric_split import volumetric_split

#: The pressure unknowns are ``q = p / (P_SCALE mu)`` and the constraint rows are scaled by
#: the same factor (a symmetric scaling), so both residual blocks are forces of similar size
#: and the Newton line search, which measures ``|R|``, weighs them alike.
P_SCALE = 1.0


class MixedProblem(FemProblem):
    """The Taylor–Hood discretisation of a tissue scene (same protocol as FemProblem).

    Parameters
    ----------
    scene, order, law, intorder
        As for :class:`~reference_fem.problem.FemProblem`; ``order`` must be 2.
    """

    mixed = True
    #: The displacement order of the pair and its name in ``law_name``.
    pair_order, pair_label = 2, "mixed-P2P1"

    def __init__(
        self,
        scene: Scene,
        order: int | None = None,
        law: str | None = None,
        intorder: int | None = None,
    ):
        order = int(FemOptions.of(scene).order if order is None else order)
        if order != self.pair_order:
            raise InputError(
                f"formulation {self.pair_label} needs order {self.pair_order}, got {order}"
            )
        super().__init__(scene, order, law, intorder)
        if self.law is None:
            raise InputError(
                "formulation mixed needs a hyperelastic law (neo-hookean, guccione, "
                f"holzapfel-ogden), got {self.law_name}"
            )
        label = self.law.label if isinstance(self.law, TissueLaw) else self.law.name
        split = volumetric_split(self.law)  # W = W_base + U(J): p carries U
        self.bulk = split.kappa if split.kappa > 0 else np.inf
        self.law = split.base
        self.law_name = f"{label}/{self.pair_label}"
        self.nu = self.space.n_dofs
        self.n_p = scene.mesh.n_points
        pb = skfem.Basis(
            self.space.skmesh,
            skfem.ElementTetP1(),
            self.space.mapping,
            intorder=self.space.intorder,
        )
        self.p_nodes = np.ascontiguousarray(pb.element_dofs.T, dtype=np.int64)
        self.p_values = np.stack([np.asarray(b[0])[0] for b in pb.basis], axis=1)  # (nq, 4)
        self.p_scale = P_SCALE * scene.material.mu
        self.linear_solver.schur = self.schur_diagonal()

    def schur_diagonal(self) -> np.ndarray:
        """The Schur complement's diagonal approximation in the scaled pressure unknowns:
        ``p_scale^2 (1/(2 mu) + 1/kappa)`` times the lumped P1 pressure mass matrix.

        Returns
        -------
        numpy.ndarray
            ``(n_p,)`` positive entries.
        """
        mass = np.einsum("eq,qa->ea", self.space.dx, self.p_values)
        lumped = np.bincount(self.p_nodes.ravel(), weights=mass.ravel(), minlength=self.n_p)
        mu = self.scene.material.mu
        inv_bulk = 1.0 / self.bulk if np.isfinite(self.bulk) else 0.0
        scale = self.p_scale**2 * (0.5 / mu + inv_bulk)
        return scale * np.maximum(lumped, 1e-300)

    @property
    def n_dofs(self) -> int:
        return self.nu + self.n_p

    @cached_property
    def free(self) -> np.ndarray:
        return np.concatenate([self.bc.free, np.ones(self.n_p, dtype=bool)])

    def split(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Nodal displacement ``(n_nodes, 3)`` and vertex pressure ``(n_vertices,)``."""
        return np.asarray(x[: self.nu]).reshape(-1, 3), self.p_scale * np.asarray(x[self.nu :])

    def internal_force(self, x: np.ndarray, tangent: bool = False, scale: float = 1.0):
        """``[R_u + f_ext, R_p]`` (the internal part) and the block tangent at load factor
        ``scale`` (which ramps an active tension)."""
        U, p = self.split(x)
        law = self.law_at(scale)
        space = self.space
        m, nq, nloc, _ = space.grads.shape
        fu = np.empty((m, nloc, 3))
        fp = np.empty((m, 4))
        mt = m if tangent else 0  # the tangent's blocks are filled only when asked for
        Kuu = np.empty((mt, nloc * nloc, 9))
        Kup = np.empty((mt, nloc, 4, 3))
        eye = np.eye(3)
        Np = self.p_values
        for start in range(0, m, CHUNK):
            sl = slice(start, min(m, start + CHUNK))
            G, dx = space.grads[sl], space.dx[sl]
            F = eye + displacement_gradient(space, U, sl)
            J = _det(F)
            if not (J > 0).all():
                from .newton import InvertedElements

                ids = start + np.flatnonzero(~(J > 0).all(axis=1))
                raise InvertedElements(ids)
            FiT = np.swapaxes(np.linalg.inv(F), -1, -2)
            pq = np.einsum("qa,ea->eq", Np, p[self.p_nodes[sl]])
            frames = None if self.qframes is None else self.qframes[sl]
            if tangent:
                P, A = law.stress_tangent(F, frames=frames)
            else:
                P = law.stress(F, frames=frames)
            JFiT = J[..., None, None] * FiT
            P = P - pq[..., None, None] * JFiT
            fu[sl] = np.einsum("eq,eqij,eqaj->eai", dx, P, G)
            vol = J - 1.0 + (pq / self.bulk if np.isfinite(self.bulk) else 0.0)
            fp[sl] = -np.einsum("eq,eq,qa->ea", dx, vol, Np)
            if not tangent:
                continue
            dJFiT = np.einsum("...ij,...kl->...ijkl", JFiT, FiT) - np.einsum(
                "...il,...kj->...ijkl", JFiT, FiT
            )
            A = A - pq[..., None, None, None, None] * dJFiT
            A9 = A.transpose(0, 1, 3, 5, 2, 4).reshape(A.shape[0], nq, 9, 9)
            acc = 0.0
            for q in range(nq):
                GG = _gradient_products(G[:, q : q + 1], dx[:, q : q + 1])
                acc = acc + np.matmul(GG, A9[:, q])
            Kuu[sl] = acc
            Kup[sl] = -np.einsum("eq,eqij,eqaj,qb->eabi", dx, JFiT, G, Np)
        f = np.concatenate(
            [
                self.pattern.vector(fu),
                self.p_scale
                * np.bincount(self.p_nodes.ravel(), weights=fp.ravel(), minlength=self.n_p),
            ]
        )
        if not tangent:
            return f, None
        return f, self._block_matrix(Kuu.reshape(m, nloc, nloc, 3, 3), Kup)

    def _block_matrix(self, Kuu: np.ndarray, Kup: np.ndarray) -> sp.csr_matrix:
        uu = self.pattern.matrix(Kuu).tocsr()
        en = self.space.element_nodes
        rows = (3 * en[:, :, None, None] + np.arange(3)[None, None, None, :]).repeat(4, axis=2)
        cols = np.broadcast_to(self.p_nodes[:, None, :, None], rows.shape)
        up = sp.csr_matrix(
            (self.p_scale * Kup.ravel(), (rows.ravel(), cols.ravel())), shape=(self.nu, self.n_p)
        )
        if np.isfinite(self.bulk):
            Ne = np.einsum("eq,qa,qb->eab", self.space.dx, self.p_values, self.p_values)
            r = np.broadcast_to(self.p_nodes[:, :, None], Ne.shape).ravel()
            c = np.broadcast_to(self.p_nodes[:, None, :], Ne.shape).ravel()
            w = -(self.p_scale**2) / self.bulk
            pp = sp.csr_matrix((w * Ne.ravel(), (r, c)), shape=(self.n_p, self.n_p))
        else:
            pp = sp.csr_matrix((self.n_p, self.n_p))
        # all blocks CSR: scipy stacks them without a COO copy of the whole matrix
        return sp.bmat([[uu, up], [up.T.tocsr(), pp]], format="csr")

    def _external(self, x: np.ndarray, scale: float, tangent: bool):
        U, _ = self.split(x)
        if tangent:
            fe, Kf = self.loads.vector_and_stiffness(U, scale)
        else:
            fe, Kf = self.loads.vector(U, scale), None
        return np.concatenate([fe, np.zeros(self.n_p)]), Kf

    def residual(self, x: np.ndarray, scale: float = 1.0) -> tuple[np.ndarray, float]:
        fi, _ = self.internal_force(x, scale=scale)
        fe, _ = self._external(x, scale, False)
        return fi - fe, self.force_scale(fi, fe, scale)

    def energy(self, x: np.ndarray, scale: float = 1.0) -> None:
        """``None``: a saddle point has no energy to decrease (the line search uses |R|)."""
        return None

    def residual_tangent(self, x: np.ndarray, scale: float = 1.0):
        fi, K = self.internal_force(x, tangent=True, scale=scale)
        fe, Kf = self._external(x, scale, True)
        if Kf is not None:
            pad = sp.csr_matrix((self.n_p, self.n_p))
            K = K - sp.block_diag([Kf.tocsr(), pad], format="csr")
        return fi - fe, K, False, self.force_scale(fi, fe, scale)

    def state(self, x: np.ndarray) -> np.ndarray:
        return self.split(x)[0][: self.space.n_vertices].copy()

    def probe_values(self, x: np.ndarray) -> dict[str, list[float]]:
        return super().probe_values(np.asarray(x[: self.nu]))

    def cell_data(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """``J``, von Mises (the pressure is hydrostatic) and the element's mean pressure."""
        out = super().cell_data(np.asarray(x[: self.nu]))
        out["pressure"] = self.split(x)[1][self.p_nodes].mean(axis=1)
        return out

    def p2_volume(self, x: np.ndarray) -> float:
        return super().p2_volume(np.asarray(x[: self.nu]))
