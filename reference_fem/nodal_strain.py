"""Linear tets with a nodal-averaged strain: ``[fem] formulation = "nodal-strain"`` (P1 only).

Nodal volumes (:mod:`reference_fem.nodal_volume`) free P1 of volumetric locking; what is
left is P1's stiffness in bending and shear, which only refinement or a softer strain
measure cures. This formulation measures the law's element part ``W_base`` (the law without
its volumetric energy, :mod:`reference_fem.volumetric_split`) on the deformation gradient
averaged over each node's patch,

    Fbar_a = sum_{e ni a} V_e^0 F_e / sum_{e ni a} V_e^0,

blended with the element's own ``F_e`` by the share ``alpha`` (``[fem] strain_stabilisation``):
the alpha finite element method of Liu, Nguyen-Thoi & Lam (2008), which is also the
stabilisation Puso & Solberg (2006) give nodally integrated tetrahedra. With the volumetric
energy on nodal volumes as in the nodal-volume formulation (share ``f``,
``[fem] stabilisation``),

    Pi = sum_e V_e^0 [alpha W_base,e(F_e) + f U(J_e)]
         + (1 - alpha) sum_e V_e^0 / 4 sum_{a in e} W_base,e(Fbar_a)
         + (1 - f) sum_a V_a^0 U(J_a) - work of loads,

where ``W_base,e`` carries element ``e``'s fibre frame, so that an anisotropic law needs no
nodal frame. ``alpha = 1`` is the nodal-volume formulation; ``alpha = 0`` is node-based
smoothing, which is too soft and has spurious low-energy modes: the element share
stabilises them (``inspect --modes`` counts them). Any homogeneous deformation gives
``Fbar_a = F_e = F`` on every patch, so the patch test is passed exactly. With the
sparse nodal gradient ``B`` (``Fbar = I + B u``) the forces are ``B^T T`` and the tangent
``B^T diag(A_a) B``, with ``T_a``, ``A_a`` the nodal stress and moduli summed over the
patch; it couples the nodes of two rings. Manual: docs/fem.rst#nodal-strain-tetrahedra.

Examples
--------
>>> import numpy as np
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({
...     "mesh": {"generator": "box", "size": [2, 1, 1], "divisions": [2, 1, 1]},
...     "material": {"law": "neo-hookean", "E": 10.0, "nu": 0.49},
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
...     "fem": {"formulation": "nodal-strain"}})
>>> p = NodalStrainProblem(scene)
>>> p.law_name
'neo-hookean/coupled/nodal-strain'
>>> u = (p.space.node_coordinates @ np.array([[0.1, 0.2, 0], [0, -0.1, 0], [0.1, 0, 0]]).T)
>>> Fbar = p.nodal_deformation_gradients(u.ravel())
>>> bool(np.allclose(Fbar, np.eye(3) + [[0.1, 0.2, 0], [0, -0.1, 0], [0.1, 0, 0]]))
True
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import scipy.sparse as sp

from springfem.errors import InputError
from springfem.materials.laws.kinematics import det as _det
from springfem.mesh.nodal_average import NodalAverage
from springfem.scene import Scene

from .newton import InvertedElements
from .nodal_pressure_solve import with_nodal_parts
from .nodal_volume import NodalVolumeProblem
from .options import FemOptions


class NodalStrainProblem(NodalVolumeProblem):
    """P1 with the law measured on nodal-averaged strain (same protocol as FemProblem).

    Parameters
    ----------
    scene, order, law
        As for :class:`~reference_fem.nodal_volume.NodalVolumeProblem`.
    stabilisation
        The share ``f`` of the volumetric energy kept per element (default ``[fem]
        stabilisation``, else :meth:`default_share`).
    strain_stabilisation
        The share ``alpha`` of the element part kept on the element's own ``F``
        (default ``FemOptions.of(scene).strain_stabilisation``).
    """

    def __init__(
        self,
        scene: Scene,
        order: int | None = None,
        law: str | None = None,
        stabilisation: float | None = None,
        strain_stabilisation: float | None = None,
    ):
        super().__init__(scene, order, law, stabilisation)
        opts = FemOptions.of(scene)
        alpha = opts.strain_stabilisation if strain_stabilisation is None else strain_stabilisation
        self.alpha = self.element_share = float(alpha)
        if not 0.0 <= self.alpha <= 1.0:
            raise InputError(f"strain_stabilisation must lie in [0, 1], got {self.alpha}")
        if stabilisation is None and opts.stabilisation is None:
            self.fraction = self.default_share()
        self.law_name = self.law_name.replace("/nodal-volume", "/nodal-strain")
        tets, n = self.space.element_nodes, self.space.n_nodes
        # Fbar = I + B u, B^T T and B^T diag(A) B on a pattern built once
        self.average = NodalAverage(tets, self.G, self.V0, n)
        # the pairs (e, a): element e's part measured at its vertex a, weight V_e / 4; pairs
        # of one node with equal frames (all of them for an isotropic law) are one evaluation
        self._pair_nodes, self._pair_weight, first = frame_pairs(tets, self.V0, self.frames)
        self._pair_frames = None if self.frames is None else self.frames[first]
        self._pair_sum = sp.csr_matrix(  # nodal sums of weighted pair values
            (self._pair_weight, (self._pair_nodes, np.arange(len(first)))),
            shape=(n, len(first)),
        )

    def default_share(self) -> float:
        """The default volumetric share ``f = alpha mu / kappa`` (at most 1).

        The element keeps a volumetric stiffness of ``alpha`` times the shear modulus, as it
        keeps ``alpha`` of the shear part, so the stabilisation does not grow with the bulk
        modulus and does not lock as ``nu -> 1/2`` (docs/fem.rst#nodal-strain-tetrahedra).
        """
        mat = self.scene.material
        kappa = self.split.kappa if self.split is not None else mat.lam + 2.0 * mat.mu / 3.0
        return min(1.0, self.alpha * mat.mu / kappa) if kappa > 0 else 1.0

    @cached_property
    def B_strain(self) -> sp.csr_matrix:
        """The nodal strain operator ``B`` as a sparse matrix (:func:`strain_gradient`); the
        solves use :attr:`average`, its compiled form."""
        return strain_gradient(self.space.element_nodes, self.V0, self.G, self.space.n_nodes)

    def nodal_deformation_gradients(self, u: np.ndarray) -> np.ndarray:
        """``Fbar_a``, the patch-averaged deformation gradient of each node, ``(n, 3, 3)``."""
        return self.average.gradients(np.asarray(u, dtype=float).reshape(-1, 3)) + np.eye(3)

    def _nodal_sum(self, values: np.ndarray) -> np.ndarray:
        """Sum weighted pair values into their nodes: ``(n, ...)``."""
        out = self._pair_sum @ values.reshape(len(values), -1)
        return out.reshape((self.space.n_nodes,) + values.shape[1:])

    def _check_nodal(self, Fbar: np.ndarray) -> None:
        bad_nodes = ~(_det(Fbar) > 0)
        if bad_nodes.any():
            ids = np.flatnonzero(bad_nodes[self.space.element_nodes].any(axis=1))
            at = self.space.node_coordinates[np.flatnonzero(bad_nodes)[0]]
            raise InvertedElements(ids, f"(patch inverted at x = {np.round(at, 6).tolist()})")

    # -- linear law ----------------------------------------------------------------------------
    @cached_property
    def stiffness(self) -> sp.csr_matrix:
        """Small strain: ``alpha`` of the shear part per element, the rest on the patches."""
        if self.split is not None:  # a hyperelastic law: its tangent at rest
            return self.internal_force(np.zeros(self.n_dofs), tangent=True)[1]
        mu, alpha = self.scene.material.mu, self.alpha
        K = super().stiffness  # the nodal-volume stiffness with alpha of the shear part
        # (1 - alpha) mu (delta_ik delta_jl + delta_il delta_jk) on the patch volumes
        eye = np.eye(3)
        C = np.einsum("ik,jl->ijkl", eye, eye) + np.einsum("il,jk->ijkl", eye, eye)
        A = (1.0 - alpha) * mu * C.reshape(9, 9)
        patch = self._nodal_sum(np.ones(len(self._pair_nodes)))
        return (K + self._nodal_tangent(patch[:, None, None] * A)).tocsr()

    def _nodal_tangent(self, A: np.ndarray) -> sp.csr_matrix:
        """``B^T diag(A_a) B`` for nodal moduli ``A`` of shape ``(n, 9, 9)`` (the two-ring
        pattern of :attr:`average`)."""
        return self.average.tangent(A)

    # -- the NonlinearProblem protocol ---------------------------------------------------------
    def internal_force(self, u: np.ndarray, tangent: bool = False, scale: float = 1.0):
        """``f_int(u)`` and (optionally) its tangent matrix at load factor ``scale``."""
        if self.split is None:
            return self.stiffness @ u, (self.stiffness if tangent else None)
        alpha = self.alpha
        fi, K = super().internal_force(u, tangent, scale)
        if alpha >= 1.0:
            return fi, K
        Fbar = self.nodal_deformation_gradients(u)
        self._check_nodal(Fbar)
        base = self._split_at(scale).base
        Fp = Fbar[self._pair_nodes]
        if tangent:
            P, A = base.stress_tangent(Fp, frames=self._pair_frames)
        else:
            P, A = base.stress(Fp, frames=self._pair_frames), None
        T = (1.0 - alpha) * self._nodal_sum(P)
        fi = fi + self.average.transpose(T).ravel()
        if not tangent:
            return fi, None
        An = (1.0 - alpha) * self._nodal_sum(A.reshape(-1, 9, 9))
        Kn = self._nodal_tangent(An)
        parts = getattr(K, "nodal_parts", None)
        K = (K + Kn).tocsr()
        if parts is not None:
            K = with_nodal_parts(K, (parts[0] + Kn).tocsr(), parts[1], parts[2])
        return fi, K

    def energy(self, u: np.ndarray, scale: float = 1.0) -> float | None:
        """``Pi(u)``: the nodal-volume energy with the element part blended (module text)."""
        if self.loads.has_follower:
            return None
        whole = super().energy(u, scale)
        if self.split is None or whole is None or not np.isfinite(whole):
            return whole
        Fbar = self.nodal_deformation_gradients(u)
        if not (_det(Fbar) > 0).all():
            return np.nan
        base = self._split_at(scale).base
        Wn = base.energy(Fbar[self._pair_nodes], frames=self._pair_frames)
        nodal = (1.0 - self.alpha) * float(self._pair_weight @ Wn)
        return float(whole) + nodal


def strain_gradient(tets: np.ndarray, V0: np.ndarray, G: np.ndarray, n: int) -> sp.csr_matrix:
    """The nodal strain operator ``B``: ``Fbar = I + B u``, ``(9 n, 3 n)``.

    ``B[(a, i, j), (c, k)] = delta_ik sum_{e ni a, c} V_e dN_c/dX_j / V_a`` with ``V_a``
    the volume of node ``a``'s patch (rows ``9 a + 3 i + j``, columns ``3 c + k``).

    Parameters
    ----------
    tets, V0, G
        Connectivity ``(m, 4)``, rest volumes ``(m,)`` and shape gradients ``(m, 4, 3)``.
    n
        Number of nodes.

    Returns
    -------
    scipy.sparse.csr_matrix

    Examples
    --------
    >>> X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    >>> G = np.linalg.inv(np.c_[np.ones(4), X])[1:].T[None]  # grad N of the one tet
    >>> B = strain_gradient(np.array([[0, 1, 2, 3]]), np.array([1 / 6]), G, 4)
    >>> H = np.array([[0.1, 0.2, 0.0], [0.0, -0.1, 0.3], [0.05, 0.0, 0.0]])
    >>> bool(np.allclose(B @ (X @ H.T).ravel(), np.tile(H.ravel(), 4)))  # exact if affine
    True
    """
    m = len(tets)
    patch = np.bincount(tets.ravel(), np.repeat(V0, 4), minlength=n)
    w = V0[:, None] / patch[tets]  # (m, 4 a)
    vals = w[:, :, None, None] * G[:, None, :, :]  # (m, 4 a, 4 c, 3 j)
    shape = (m, 4, 4, 3, 3)  # (e, a, c, i, j)
    vals = np.broadcast_to(vals[:, :, :, None, :], shape)
    a = tets[:, :, None, None, None]
    c = tets[:, None, :, None, None]
    i = np.arange(3)[None, None, None, :, None]
    j = np.arange(3)[None, None, None, None, :]
    rows = np.broadcast_to(9 * a + 3 * i + j, shape).ravel()
    cols = np.broadcast_to(3 * c + i, shape).ravel()
    return sp.csr_matrix((vals.ravel(), (rows, cols)), shape=(9 * n, 3 * n))


def frame_pairs(tets: np.ndarray, V0: np.ndarray, frames: np.ndarray | None):
    """The distinct (node, frame) pairs of the elements' vertices and their weights.

    Parameters
    ----------
    tets, V0
        Connectivity ``(m, 4)`` and rest volumes ``(m,)``.
    frames
        Element frames ``(m, 3, 3)``, or ``None`` (one pair per node).

    Returns
    -------
    nodes, weights, first
        Each pair's node, its weight (the sum of ``V_e / 4`` over its elements) and one
        element of it (whose frame it carries).

    Examples
    --------
    >>> tets = np.array([[0, 1, 2, 3], [1, 2, 3, 4]])
    >>> nodes, w, first = frame_pairs(tets, np.array([1.0, 2.0]), None)
    >>> nodes.tolist(), w.tolist()
    ([0, 1, 2, 3, 4], [0.25, 0.75, 0.75, 0.75, 0.5])
    """
    m = len(tets)
    frame_id = np.zeros(m, dtype=np.int64)
    if frames is not None:
        _, frame_id = np.unique(frames.reshape(m, 9), axis=0, return_inverse=True)
    k = int(frame_id.max()) + 1
    keys, pair = np.unique(tets.ravel() * k + np.repeat(frame_id.ravel(), 4), return_inverse=True)
    first = np.zeros(len(keys), dtype=np.int64)
    first[pair] = np.repeat(np.arange(m), 4)
    return keys // k, np.bincount(pair, np.repeat(V0 / 4.0, 4), len(keys)), first
