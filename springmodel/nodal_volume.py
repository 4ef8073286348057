"""The nodal-averaged volume term: the average nodal pressure tetrahedron.

Bonet & Burton (1998, Commun. Numer. Meth. Engng 14: 437-449) measure the volume ratio of a
linear tetrahedral mesh on the nodes instead of the elements. With the tet volumes ``V_e``
(current) and ``V_e0`` (rest), the nodal volumes and ratios are

    V_a = sum_{e ni a} V_e / 4,   V_a0 = sum_{e ni a} V_e0 / 4,   J_a = V_a / V_a0,

and the volumetric energy is ``W = sum_a V_a0 U_a(J_a)`` with the scene's ``U(J)``
(:mod:`springfem.volumetric`) and the nodal bulk modulus ``kappa_a = sum_{e ni a} V_e0
kappa_e / 4 / V_a0`` (the rest-volume average of the elements' calibrated ``kappa_e``). A
node has one pressure ``p_a = U_a'(J_a)`` instead of one per element, so a mesh of ``m``
tets has about ``m / 5`` volume constraints instead of ``m``: the P1 volumetric locking of
nearly incompressible scenes goes away. Forces and tangent:

    f = -sum_e pbar_e dV_e/dx,                      pbar_e = mean_{a in e} p_a,
    K = sum_a U_a''(J_a) / V_a0 g_a g_a^T + sum_e pbar_e d^2V_e/dx^2,
    g_a = dV_a/dx = sum_{e ni a} dV_e/dx / 4.

The first part of ``K`` couples the whole patch of a node (a wider pattern than one tet);
it is assembled as ``G^T diag(U''/V_a0) G`` with the sparse ``G`` of the ``g_a``.

Examples
--------
>>> import numpy as np
>>> X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]])
>>> t = NodalVolume(X, np.array([[0, 1, 2, 3], [1, 2, 3, 4]]), np.array([1.0, 1.0]))
>>> bool(np.allclose(t.ratios(1.1 * X), 1.1**3)), round(t.energy(X), 12)
(True, 0.0)
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from springfem.mesh import tet_volumes
from springfem.volumetric import volumetric_energy

from .nodal_volume_kernels import (
    add_volume_hessians,
    nodal_volumes,
    volume_forces,
    volume_gradients,
)

# a = x1 - x0, b = x2 - x0, c = x3 - x0 from the nodes: edge = _T @ nodes
_T = np.array([[-1.0, 1, 0, 0], [-1, 0, 1, 0], [-1, 0, 0, 1]])
_EPS = np.zeros((3, 3, 3))
_EPS[0, 1, 2] = _EPS[1, 2, 0] = _EPS[2, 0, 1] = 1.0
_EPS[0, 2, 1] = _EPS[2, 1, 0] = _EPS[1, 0, 2] = -1.0


def tet_volumes_and_gradients(x: np.ndarray, tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Signed volumes of the tets and their gradients.

    Parameters
    ----------
    x
        Node positions ``(n, 3)``.
    tets
        Connectivity ``(m, 4)``.

    Returns
    -------
    V, dV
        ``V (m,)`` with ``V = a . (b x c) / 6`` and ``dV (m, 4, 3)`` = ``dV / dx_i``.
    """
    p = x[tets]
    a, b, c = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
    bc, ca, ab = np.cross(b, c), np.cross(c, a), np.cross(a, b)
    V = np.einsum("kc,kc->k", a, bc) / 6.0
    dV = np.empty(p.shape)
    dV[:, 1], dV[:, 2], dV[:, 3] = bc / 6.0, ca / 6.0, ab / 6.0
    dV[:, 0] = -(dV[:, 1] + dV[:, 2] + dV[:, 3])
    return V, dV


def tet_volume_hessians(x: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """``d^2 V_e / dx_i dx_j`` of every tet, ``(m, 4, 4, 3, 3)`` (``[e, i, j, alpha, beta]``).

    ``V`` is linear in each node, so the diagonal blocks vanish; in the edges
    ``(a, b, c)``: ``d^2V / da db = E(c) / 6``, ``d^2V / db dc = E(a) / 6``,
    ``d^2V / dc da = E(b) / 6`` with ``E(v)_{alpha beta} = eps_{alpha beta gamma} v_gamma``.

    Parameters
    ----------
    x, tets
        As in :func:`tet_volumes_and_gradients`.

    Returns
    -------
    numpy.ndarray
        The symmetric ``12 x 12`` Hessian of each tet as ``(m, 4, 4, 3, 3)``.
    """
    p = x[tets]
    e = p[:, 1:] - p[:, :1]  # (m, 3 edges, 3)
    E = np.einsum("abg,kpg->kpab", _EPS, e) / 6.0  # E(edge p)
    H = np.zeros((p.shape[0], 3, 3, 3, 3))
    for p_, q_, r_ in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        H[:, p_, q_] = E[:, r_]
        H[:, q_, p_] = -E[:, r_]  # the transpose of an antisymmetric block
    return np.einsum("pi,qj,kpqab->kijab", _T, _T, H)


class NodalVolume:
    """Nodal-averaged volumetric energy ``sum_a V_a0 U_a(J_a)`` on a tet mesh.

    Parameters
    ----------
    X
        Rest positions ``(n, 3)``.
    tets
        Connectivity ``(m, 4)`` (positively oriented).
    kappa
        Bulk modulus of each element ``(m,)`` (Pa), e.g. the calibrated ``k_axis_volume``.
    kind
        ``U(J)``: ``quadratic``, ``log`` or ``simo-taylor``.
    """

    def __init__(self, X: np.ndarray, tets: np.ndarray, kappa: np.ndarray, kind: str = "quadratic"):
        from .nodal_groups import mesh_average

        given = tets
        tets = np.asarray(tets, dtype=np.int64)
        self.n = int(np.asarray(X).shape[0])
        self.kind = kind
        V0 = tet_volumes(np.asarray(X, float), tets)
        flip = V0 < 0  # orient every tet positively (the volume measure is signed)
        if flip.any():
            tets = tets.copy()
            tets[flip] = tets[flip][:, [0, 2, 1, 3]]
            given = tets
        self.tets = np.ascontiguousarray(tets)
        # the nodal average of the mesh (shared with the nodal strain): its tangent pattern
        self.average = mesh_average(X, given)
        V0 = np.abs(V0)
        self.Va0 = self._to_nodes(V0 / 4.0)
        kV = self._to_nodes(np.asarray(kappa, float) * V0 / 4.0)
        safe = np.where(self.Va0 > 0, self.Va0, 1.0)
        self.kappa = kV / safe  # (n,) nodal bulk modulus
        self.Va0_safe = safe
        self._pattern = None  # the tets' CSR pattern, on the first tangent

    def _to_nodes(self, per_element: np.ndarray) -> np.ndarray:
        """Sum ``per_element (m,)`` into each of the element's four nodes, ``(n,)``."""
        return np.bincount(self.tets.ravel(), np.repeat(per_element, 4), minlength=self.n)

    def _ratios_of_nodal(self, Vn: np.ndarray) -> np.ndarray:
        """``J_a`` from the nodal volumes ``Vn (n,)``."""
        return np.where(self.Va0 > 0, Vn / self.Va0_safe, 1.0)

    def _ratios_of(self, V: np.ndarray) -> np.ndarray:
        """``J_a`` from the element volumes ``V (m,)``."""
        return self._ratios_of_nodal(self._to_nodes(V / 4.0))

    def ratios(self, x: np.ndarray) -> np.ndarray:
        """Nodal volume ratios ``J_a = V_a / V_a0`` ``(n,)`` (1 for nodes in no element)."""
        Vn = np.zeros(self.n)
        nodal_volumes(np.ascontiguousarray(x, dtype=float).reshape(-1, 3), self.tets, Vn)
        return self._ratios_of_nodal(Vn)

    def _state(self, x):
        U, dU, d2U = volumetric_energy(self.ratios(x), self.kappa, self.kind)
        return U, dU, d2U

    def energy(self, x: np.ndarray) -> float:
        """``sum_a V_a0 U_a(J_a)`` (J)."""
        U, _, _ = self._state(x)
        return float(np.dot(self.Va0, U))

    def forces(self, x: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Nodal forces ``-dW/dx`` ``(n, 3)`` (N) (added to ``out`` when given)."""
        x = np.ascontiguousarray(x, dtype=float).reshape(-1, 3)
        _, dU, _ = self._state(x)
        out = np.zeros((self.n, 3)) if out is None else out
        volume_forces(x, self.tets, np.ascontiguousarray(dU, dtype=float), out)
        return out

    def add_tangent(self, x: np.ndarray, data: np.ndarray) -> np.ndarray:
        """``data +=`` the tangent on the two-ring pattern of :attr:`average`."""
        x = np.ascontiguousarray(x, dtype=float).reshape(-1, 3)
        _, dU, d2U = self._state(x)
        op = self.average
        dV = np.empty((self.tets.shape[0], 4, 3))
        volume_gradients(x, self.tets, dV)
        G = op.row_entries(dV, 0.25)  # g_a = sum_{e ni a} dV_e / 4
        w = np.where(self.Va0 > 0, d2U / self.Va0_safe, 0.0)
        op.add_outer(w, G, data)
        pbar = 0.25 * dU[self.tets].sum(axis=1)
        add_volume_hessians(x, self.tets, pbar, op.pattern[7], data)
        return data

    def tangent(self, x: np.ndarray) -> sp.csr_matrix:
        """Tangent ``d^2W/dx^2`` ``(3n, 3n)`` (CSR, symmetric, the two-ring pattern).

        Parameters
        ----------
        x
            Node positions ``(n, 3)``.

        Returns
        -------
        scipy.sparse.csr_matrix
            ``G^T diag(U''/V_a0) G + sum_e pbar_e d^2V_e/dx^2``.
        """
        return self.average.matrix(self.add_tangent(x, self.average.zeros()))

    def reference_tangent(self, x: np.ndarray) -> sp.csr_matrix:
        """:meth:`tangent` by numpy and scipy products (the reference the tests compare)."""
        x = np.asarray(x, float)
        V, dV = tet_volumes_and_gradients(x, self.tets)
        U, dU, d2U = volumetric_energy(self._ratios_of(V), self.kappa, self.kind)
        m = self.tets.shape[0]
        cols = (3 * self.tets[:, :, None] + np.arange(3)).reshape(m, 12)  # (m, 12)
        # G[a, :] = sum_{e ni a} dV_e / 4: row a = tets[e, p] for every p, all 12 columns
        rows = np.broadcast_to(self.tets[:, :, None], (m, 4, 12))
        vals = np.broadcast_to(dV.reshape(m, 1, 12) / 4.0, (m, 4, 12))
        cc = np.broadcast_to(cols[:, None, :], (m, 4, 12))
        G = sp.csr_matrix((vals.ravel(), (rows.ravel(), cc.ravel())), shape=(self.n, 3 * self.n))
        w = np.where(self.Va0 > 0, d2U / self.Va0_safe, 0.0)
        K1 = (G.T @ sp.diags(w) @ G).tocsr()
        pbar = dU[self.tets].mean(axis=1)
        He = tet_volume_hessians(x, self.tets) * pbar[:, None, None, None, None]
        He = He.transpose(0, 1, 3, 2, 4).reshape(m, 12, 12)
        K2 = self._element_sum(np.ascontiguousarray(He))
        return (K1 + K2).tocsr()

    def _element_sum(self, Ke: np.ndarray) -> sp.csr_matrix:
        """``sum_e`` of ``12 x 12`` element matrices ``Ke (m, 12, 12)`` into the ``3n x 3n``
        CSR pattern of the tets (built once, as the spring Hessian's)."""
        from .hessian_numba import _scatter_add
        from .hessian_pattern import csr_pattern

        if self._pattern is None:
            self._pattern = csr_pattern(self.tets, self.n)
        indptr, indices, index_map = self._pattern
        data = np.zeros(indices.size)
        _scatter_add(data, index_map, Ke)
        return sp.csr_matrix((data, indices, indptr), shape=(3 * self.n, 3 * self.n))


class NodalPart:
    """The nodal volume term of a :class:`~springmodel.model.SpringModel`.

    It replaces the per-tet axis-volume energy (all of it, or the share ``fraction``): the
    spring kernel and Hessian get the elements with the rest of ``k_axis_volume``
    (:meth:`kernel_elements`) and the model adds this
    part's forces, energy and tangent.

    Parameters
    ----------
    X, tets
        Rest positions ``(n, 3)`` and connectivity ``(m, 4)``.
    elements
        The calibrated spring elements (their ``k_axis_volume`` is the elements' ``kappa``).
    kind
        ``U(J)`` (the options' ``volumetric``).
    fraction
        Share of ``kappa`` on the nodal volumes (the options' ``nodal_fraction``); the rest
        stays on the tets in the spring kernel.
    stabilisation
        The options' ``volume_stabilisation`` ``beta``: each tet keeps ``beta kappa V0 U(J)``
        besides (its own volume, which the nodal volumes do not see,
        docs/volumetric.rst#stabilised-nodal-strain).
    """

    def __init__(
        self, X: np.ndarray, tets: np.ndarray, elements, kind: str, fraction=1.0, stabilisation=0.0
    ):
        self.fraction = float(fraction)
        self.stabilisation = float(stabilisation)
        self.term = NodalVolume(X, tets, self.fraction * elements.k_axis_volume, kind)
        self._coloured = None
        self._same: bool | None = None

    def _same_tets(self, hessian) -> bool:
        """Whether the Hessian's elements are the term's tets in its order (their element
        matrices then sum into the two-ring pattern directly)."""
        if self._same is None:
            self._same = bool(np.array_equal(hessian.elements.tets, self.term.tets))
        return self._same

    @classmethod
    def split(cls, mesh, elements, options, material=None) -> tuple[NodalPart | None, object]:
        """The nodal part of a model (None when off) and the elements for its kernel.

        Parameters
        ----------
        mesh
            The scene's mesh (``points``, ``tets``).
        elements
            The calibrated :class:`~springmodel.elements.SpringElements`.
        options
            :class:`~springmodel.options.SpringOptions` (``nodal_volume``,
            ``volumetric``, ``nodal_fraction``).
        material
            The scene's material: the default ``volume_stabilisation`` scales with its
            ``mu / kappa`` (:meth:`~springmodel.options.SpringOptions.volume_stabilisation_share`).

        Returns
        -------
        tuple
            ``(NodalPart or None, elements for the spring kernel and Hessian)``.
        """
        if not options.nodal_volume:
            return None, elements
        part = cls(
            mesh.points, mesh.tets, elements, options.volumetric, options.nodal_fraction,
            options.volume_stabilisation_share(material),
        )  # fmt: skip
        return part, part.kernel_elements(elements)

    def kernel_elements(self, elements):
        """A copy of ``elements`` with the per-tet share ``1 - fraction + stabilisation`` of
        ``kappa``."""
        from dataclasses import replace

        share = 1.0 - self.fraction + self.stabilisation
        return replace(elements, k_axis_volume=share * elements.k_axis_volume)

    def stiffness(self, x: np.ndarray, hessian, rest_fn) -> sp.csr_matrix:
        """Tangent of the whole model: the springs' part plus :meth:`NodalVolume.tangent`.

        The springs' part is their analytic Hessian (``hessian.matrix``) or, when there is
        none (follower loads, non-conservative laws), the coloured finite-difference
        Jacobian of ``rest_fn``, the model's forces without this term: they couple only the
        nodes of one element, which the element colouring assumes; the nodal term's wider
        patch coupling is added analytically.

        Parameters
        ----------
        x
            Node positions ``(n, 3)``.
        hessian
            :class:`~springmodel.hessian.SpringHessian` or None.
        rest_fn
            ``x -> forces (n, 3)`` of the springs and loads (without this term).

        Returns
        -------
        scipy.sparse.csr_matrix
            ``K = -d f / dx`` ``(3n, 3n)``.
        """
        if hessian is not None and self._same_tets(hessian):
            op = self.term.average
            data = op.zeros()
            m = hessian.elements.n_elements
            for lo in range(0, m, hessian.chunk):  # bounded memory, as SpringHessian.matrix
                hi = min(lo + hessian.chunk, m)
                op.add_elements(hessian.element_matrices(x, lo=lo, hi=hi), data, lo)
            return op.matrix(self.term.add_tangent(x, data))
        if hessian is not None:
            K = hessian.matrix(x)
        else:
            from springfem.mechanics.fd_jacobian import ColoredJacobian

            if self._coloured is None:
                self._coloured = ColoredJacobian(self.term.tets, self.term.n)
            K = self._coloured(rest_fn, x)
        return (sp.csr_matrix(K) + self.term.tangent(x)).tocsr()
