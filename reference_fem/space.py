"""The discrete space: P1 or P2 Lagrange tets on the scene's own vertices.

A :class:`Space` holds, per element and quadrature point, the gradients of the scalar
shape functions and the integration weights; vector DOFs are interleaved,
``dof = 3 * node + component``, as in scikit-fem's ``ElementVector`` and in
``Scene.dirichlet``. P2 nodes are the mesh vertices (numbered first, as in the scene)
followed by one node per edge (``n_vertices + edge``).

P1 with one quadrature point (``intorder=1``, exact for constant gradients) computes the
gradients directly from the vertex coordinates; every other case takes them from a
scikit-fem :class:`~skfem.CellBasis`.

Examples
--------
>>> from springfem.mesh import box_mesh
>>> s = Space(box_mesh((1.0, 1.0, 1.0), (2, 2, 2)), order=2)
>>> s.n_nodes, s.n_dofs, s.grads.shape
(125, 375, (48, 4, 10, 3))
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import skfem
from skfem.mapping import MappingAffine, MappingIsoparametric

from springfem.errors import InputError
from springfem.mesh import TetMesh


def p1_gradients(points: np.ndarray, tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Constant P1 shape-function gradients ``(m, 4, 3)`` and signed volumes ``(m,)``.

    Parameters
    ----------
    points, tets
        Vertex coordinates ``(n, 3)`` and node indices ``(m, 4)``.

    Returns
    -------
    G, V
        ``G[k, a] = grad N_a`` ``(m, 4, 3)`` and signed volumes ``(m,)``.

    Examples
    --------
    >>> G, V = p1_gradients(np.eye(4)[:, 1:], np.array([[0, 1, 2, 3]]))  # the unit corner tet
    >>> G[0].sum(axis=0).tolist(), round(float(V[0]), 12)
    ([0.0, 0.0, 0.0], 0.166666666667)
    """
    x = points[tets]
    T = x[:, 1:] - x[:, :1]  # rows: edge vectors x_a - x_0
    Tinv = np.linalg.inv(T)  # columns: gradients of the barycentric coordinates 1..3
    G = np.concatenate([-Tinv.sum(axis=2, keepdims=True), Tinv], axis=2).transpose(0, 2, 1)
    return G, np.linalg.det(T) / 6.0


def edge_list(mesh: TetMesh) -> np.ndarray:
    """``(n_edges, 2)`` vertex pairs in scikit-fem's edge order (the P2 edge nodes' order).

    Examples
    --------
    >>> from springfem.mesh import box_mesh
    >>> edge_list(box_mesh((1.0, 1.0, 1.0), (1, 1, 1))).shape
    (19, 2)
    """
    m = skfem.MeshTet(np.ascontiguousarray(mesh.points.T), np.ascontiguousarray(mesh.tets.T))
    return np.ascontiguousarray(m.edges.T, dtype=np.int64)


def default_intorder(order: int, nonlinear: bool = False) -> int:
    """Quadrature order: 1 point for P1 (constant gradients), 4 points for P2.

    The 4-point rule is exact for the linear P2 stiffness on straight tets; for
    hyperelastic P2 it is the usual full integration (as in Abaqus' C3D10).

    Parameters
    ----------
    order
        Element order, 1 or 2.
    nonlinear
        Hyperelastic problem (the same rule today).

    Returns
    -------
    int
        scikit-fem ``intorder``: 1 for P1, 2 (4 points) for P2.
    """
    return 1 if order == 1 else 2


class CurvedMapping(MappingIsoparametric):
    """scikit-fem's isoparametric map of a ``MeshTet2`` whose inverse starts from the
    straight tet's.

    scikit-fem's own inverse starts every point at ``(0.5, 0.5, 0.5)`` and clips to the unit
    cube, which cycles on some curved boundary tets; starting from the affine inverse of the
    same tet (exact for its straight part) Newton converges in a few steps.
    """

    def __init__(self, mesh: skfem.MeshTet2, straight: skfem.MeshTet):
        super().__init__(mesh, mesh.elem(), mesh.bndelem)
        self.affine = MappingAffine(straight)

    def invF(self, x, tind=None, newton_max_iters=50, newton_tol=1e-12):
        X = self.affine.invF(x, tind=tind)
        for _ in range(newton_max_iters):
            dX = np.einsum("ijkl,jkl->ikl", self.invDF(X, tind), x - self.F(X, tind))
            X = X + dX
            if (np.linalg.norm(dX, 1, (0, 2)) < newton_tol).all():
                return X
        raise InputError(f"curved geometry: the inverse map did not converge to {newton_tol}")


class Space:
    """Scalar Lagrange space of ``order`` 1 or 2 on a :class:`TetMesh`, used component-wise.

    Attributes
    ----------
    mesh
        The scene mesh.
    order, intorder
        Polynomial order and quadrature order.
    element_nodes
        ``(m, nloc)`` node indices per element (``nloc`` = 4 or 10).
    grads
        ``(m, nq, nloc, 3)`` shape-function gradients at the quadrature points.
    dx
        ``(m, nq)`` quadrature weights times the Jacobian.
    values
        ``(nq, nloc)`` shape-function values at the quadrature points.
    edge_nodes
        ``None`` (straight-sided tets), or ``(n_edges, 3)`` positions of the P2 edge nodes:
        the isoparametric (curved) geometry of a scikit-fem ``MeshTet2``, e.g. from
        :func:`springfem.ellipsoid.curved_edge_nodes`.
    """

    #: Straight-sided unless a subclass or ``__init__`` says otherwise.
    edge_nodes: np.ndarray | None = None

    def __init__(
        self,
        mesh: TetMesh,
        order: int = 1,
        intorder: int | None = None,
        edge_nodes: np.ndarray | None = None,
    ):
        if order not in (1, 2):
            raise InputError(f"fem order must be 1 or 2, got {order!r}")
        if edge_nodes is not None and order != 2:
            raise InputError("curved geometry (edge nodes) needs fem order 2")
        self.mesh = mesh
        self.edge_nodes = None if edge_nodes is None else np.asarray(edge_nodes, dtype=float)
        self.order = order
        self.intorder = default_intorder(order) if intorder is None else int(intorder)
        self.n_vertices = mesh.n_points
        if order == 1 and self.intorder == 1:
            G, V = p1_gradients(mesh.points, mesh.tets)
            self.element_nodes = np.ascontiguousarray(mesh.tets, dtype=np.int64)
            self.grads = G[:, None]
            self.dx = V[:, None]
            self.values = np.full((1, 4), 0.25)
            self.n_nodes = mesh.n_points
        else:
            basis = self.basis
            self.element_nodes = np.ascontiguousarray(basis.element_dofs.T, dtype=np.int64)
            self.grads = np.ascontiguousarray(
                np.stack([b[0].grad for b in basis.basis], axis=0).transpose(2, 3, 0, 1)
            )
            self.dx = np.asarray(basis.dx)
            self.values = np.stack([np.asarray(b[0])[0] for b in basis.basis], axis=1)
            self.n_nodes = int(basis.N)

    @property
    def n_dofs(self) -> int:
        return 3 * self.n_nodes

    @property
    def n_elements(self) -> int:
        return self.mesh.n_tets

    @property
    def nloc(self) -> int:
        return self.element_nodes.shape[1]

    @cached_property
    def skmesh(self) -> skfem.MeshTet:
        """The scikit-fem mesh on the same vertices and tets (same element order); a
        quadratic ``MeshTet2`` through :attr:`edge_nodes` when they are given."""
        p = np.ascontiguousarray(self.mesh.points.T)
        t = np.ascontiguousarray(self.mesh.tets.T)
        if self.edge_nodes is None:
            return skfem.MeshTet(p, t)
        straight = skfem.MeshTet2.from_mesh(skfem.MeshTet(p, t))
        nv = self.mesh.n_points
        if straight.doflocs.shape[1] != nv + len(self.edge_nodes):
            raise InputError(
                f"curved geometry: {len(self.edge_nodes)} edge nodes for "
                f"{straight.doflocs.shape[1] - nv} edges"
            )
        doflocs = np.hstack([p, self.edge_nodes.T])
        return skfem.MeshTet2(np.ascontiguousarray(doflocs), t)

    @cached_property
    def mapping(self):
        """The reference map: affine, or (curved) :class:`CurvedMapping`."""
        if self.edge_nodes is None:
            return self.skmesh.mapping()
        p = np.ascontiguousarray(self.mesh.points.T)
        return CurvedMapping(self.skmesh, skfem.MeshTet(p, np.ascontiguousarray(self.mesh.tets.T)))

    @cached_property
    def element(self) -> skfem.Element:
        """The scalar scikit-fem element."""
        return skfem.ElementTetP1() if self.order == 1 else skfem.ElementTetP2()

    @cached_property
    def basis(self) -> skfem.CellBasis:
        """Scalar scikit-fem basis with this space's quadrature."""
        return skfem.Basis(self.skmesh, self.element, self.mapping, intorder=self.intorder)

    @cached_property
    def edges(self) -> np.ndarray:
        """``(n_edges, 2)`` vertex pairs; P2 edge ``e`` has node ``n_vertices + e``."""
        return edge_list(self.mesh)

    @cached_property
    def node_coordinates(self) -> np.ndarray:
        """``(n_nodes, 3)`` coordinates of the nodes (vertices, then edge midpoints)."""
        if self.order == 1:
            return self.mesh.points
        if self.edge_nodes is not None:
            return np.vstack([self.mesh.points, self.edge_nodes])
        mid = 0.5 * (self.mesh.points[self.edges[:, 0]] + self.mesh.points[self.edges[:, 1]])
        return np.vstack([self.mesh.points, mid])

    def quadrature_points(self) -> np.ndarray:
        """``(m, nq, 3)`` physical coordinates of the quadrature points."""
        if self.order == 1 and self.intorder == 1:
            return self.mesh.centers()[:, None]
        return np.asarray(self.basis.global_coordinates()).transpose(1, 2, 0)

    def region_nodes(self, vertices: np.ndarray) -> np.ndarray:
        """Nodes of a vertex set: the vertices plus (P2) every edge with both ends in it."""
        vertices = np.asarray(vertices, dtype=np.int64)
        if self.order == 1:
            return vertices
        mask = np.zeros(self.n_vertices, dtype=bool)
        mask[vertices] = True
        on = np.flatnonzero(mask[self.edges].all(axis=1))
        return np.concatenate([vertices, self.n_vertices + on])

    def facet_indices(self, facets: np.ndarray) -> np.ndarray:
        """scikit-fem facet indices of boundary triangles given by vertex triples."""
        facets = np.asarray(facets, dtype=np.int64).reshape(-1, 3)
        n = self.n_vertices
        sk = np.sort(self.skmesh.facets.T.astype(np.int64), axis=1)
        keys = (sk[:, 0] * n + sk[:, 1]) * n + sk[:, 2]
        order = np.argsort(keys)
        q = np.sort(facets, axis=1)
        qk = (q[:, 0] * n + q[:, 1]) * n + q[:, 2]
        pos = np.searchsorted(keys[order], qk)
        pos = np.minimum(pos, len(keys) - 1)
        found = keys[order][pos] == qk
        if not found.all():
            raise InputError(f"{int((~found).sum())} region facets are not faces of the mesh")
        return order[pos]

    def facet_basis(self, facets: np.ndarray, intorder: int) -> skfem.FacetBasis:
        """Scalar facet basis on the given boundary triangles (vertex triples)."""
        return skfem.FacetBasis(
            self.skmesh,
            self.element,
            self.mapping,
            facets=self.facet_indices(facets),
            intorder=intorder,
        )

    def interpolation_matrix(self, tets: np.ndarray, points: np.ndarray):
        """Sparse ``(len(points), n_nodes)`` matrix evaluating a nodal field at ``points``.

        ``tets[p]`` is the element containing ``points[p]`` (e.g. from the scene's probes);
        the shape functions are evaluated through scikit-fem's inverse mapping.
        """
        import scipy.sparse as sp

        tets = np.asarray(tets, dtype=np.int64)
        points = np.atleast_2d(np.asarray(points, dtype=float))
        if len(points) == 0:
            return sp.csr_matrix((0, self.n_nodes))
        mapping = self.mapping
        X = mapping.invF(points.T[:, :, None], tind=tets)
        phis = np.array(
            [self.element.gbasis(mapping, X, k, tind=tets)[0][:, 0] for k in range(self.nloc)]
        )  # (nloc, npts)
        rows = np.tile(np.arange(len(points)), self.nloc)
        cols = self.element_nodes[tets].T.ravel()
        return sp.csr_matrix((phis.ravel(), (rows, cols)), shape=(len(points), self.n_nodes))
