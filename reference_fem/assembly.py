"""Vectorised assembly: element arrays with ``einsum``, global matrices in 3x3 blocks.

Element matrices are stored as blocks ``Ke[e, a, b, i, k]`` = stiffness between component
``i`` of node ``a`` and component ``k`` of node ``b``; a :class:`BlockPattern` sums them
into a block sparse (BSR, 3x3) matrix by one sort computed once per mesh, which is several
times faster than ``coo_matrix(...).tocsr()`` and hands pyamg the block structure it wants.

Examples
--------
>>> from springfem.mesh import box_mesh
>>> from springfem.materials import isotropic_matrix
>>> m = box_mesh((1.0, 1.0, 1.0), (1, 1, 1))
>>> K = element_stiffness_p1(m.points, m.tets, isotropic_matrix(1.0, 0.3))
>>> K.shape, bool(abs(K.sum(axis=2)).max() < 1e-12)  # translations carry no force
((6, 12, 12), True)
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from springfem.materials import voigt_to_tensor

from .space import Space, p1_gradients

#: Elements per chunk when quadrature-point arrays would otherwise get large.
CHUNK = 20_000


class BlockPattern:
    """Sparsity pattern of a matrix with 3x3 blocks over element node lists.

    Parameters
    ----------
    element_nodes
        ``(m, nloc)`` node indices per element.
    n_nodes
        Number of nodes (the matrix is ``3 n_nodes`` square).
    """

    def __init__(self, element_nodes: np.ndarray, n_nodes: int):
        en = np.asarray(element_nodes, dtype=np.int64)
        nloc = en.shape[1]
        a, b = np.meshgrid(np.arange(nloc), np.arange(nloc), indexing="ij")
        key = (en[:, a.ravel()] * n_nodes + en[:, b.ravel()]).ravel()
        self.order = np.argsort(key)
        ks = key[self.order]
        self.start = np.flatnonzero(np.r_[True, ks[1:] != ks[:-1]])
        uk = ks[self.start]
        rows = uk // n_nodes
        self.indices = (uk % n_nodes).astype(np.int32)
        self.indptr = np.searchsorted(rows, np.arange(n_nodes + 1)).astype(np.int32)
        self.element_nodes = en
        self.n_nodes = n_nodes

    @property
    def shape(self) -> tuple[int, int]:
        return (3 * self.n_nodes, 3 * self.n_nodes)

    def matrix(self, blocks: np.ndarray) -> sp.bsr_matrix:
        """Sum element blocks ``(m, nloc, nloc, 3, 3)`` into a BSR matrix."""
        data = np.add.reduceat(blocks.reshape(-1, 9)[self.order], self.start, axis=0)
        return sp.bsr_matrix(
            (data.reshape(-1, 3, 3), self.indices, self.indptr), shape=self.shape, copy=False
        )

    def vector(self, fe: np.ndarray) -> np.ndarray:
        """Sum element vectors ``(m, nloc, 3)`` into a global vector ``(3 n_nodes,)``."""
        return assemble_vector(self.element_nodes, fe, self.n_nodes)


def assemble_vector(element_nodes: np.ndarray, fe: np.ndarray, n_nodes: int) -> np.ndarray:
    """Sum element vectors ``(m, nloc, 3)`` at ``element_nodes`` into ``(3 n_nodes,)``.

    Parameters
    ----------
    element_nodes
        ``(m, nloc)`` node indices per element.
    fe
        Element vectors ``(m, nloc, 3)``.
    n_nodes
        Number of nodes.

    Returns
    -------
    ndarray
        Global vector ``(3 n_nodes,)``, DOF ``3 node + component``.
    """
    dofs = (3 * np.asarray(element_nodes, dtype=np.int64)[..., None] + np.arange(3)).ravel()
    return np.bincount(dofs, weights=np.asarray(fe).ravel(), minlength=3 * n_nodes)


def _c9(D: np.ndarray) -> np.ndarray:
    """Voigt ``(..., 6, 6)`` -> ``(..., 9, 9)`` with rows ``(j, l)`` and columns ``(i, k)``."""
    C = voigt_to_tensor(D)  # C[i, j, k, l]
    return np.moveaxis(C, (-4, -3, -2, -1), (-2, -4, -1, -3)).reshape(C.shape[:-4] + (9, 9))


def _gradient_products(grads: np.ndarray, dx: np.ndarray) -> np.ndarray:
    """``GG[e, a, b, j, l] = sum_q dx G[e, q, a, j] G[e, q, b, l]`` as ``(m, nloc^2, 9)``."""
    m, nq, nloc, _ = grads.shape
    if nq == 1:
        g = grads[:, 0]
        GG = (g[:, :, None, :, None] * g[:, None, :, None, :]) * dx[:, 0, None, None, None, None]
    else:
        GG = np.einsum("eq,eqaj,eqbl->eabjl", dx, grads, grads, optimize=True)
    return GG.reshape(m, nloc * nloc, 9)


def linear_element_blocks(
    grads: np.ndarray, dx: np.ndarray, D_groups: np.ndarray, group: np.ndarray
) -> np.ndarray:
    """Linear elastic element blocks ``(m, nloc, nloc, 3, 3)``.

    ``Ke[e, a, b, i, k] = sum_q dx sum_jl G_aj C_ijkl G_bl`` with the Voigt matrix
    ``D_groups[group[e]]``; one matrix product per material group.

    Parameters
    ----------
    grads, dx
        Shape-function gradients ``(m, nq, nloc, 3)`` and quadrature weights ``(m, nq)``.
    D_groups, group
        Voigt stiffness per material group ``(g, 6, 6)`` and each element's group ``(m,)``.

    Returns
    -------
    ndarray
        Element blocks ``(m, nloc, nloc, 3, 3)``.
    """
    m, _, nloc, _ = grads.shape
    C9 = _c9(np.asarray(D_groups).reshape(-1, 6, 6))
    out = np.empty((m, nloc * nloc, 9))
    for start in range(0, m, CHUNK):
        sl = slice(start, min(m, start + CHUNK))
        GG = _gradient_products(grads[sl], dx[sl])
        g = group[sl]
        if len(C9) == 1:
            out[sl] = GG @ C9[0]
        elif len(C9) <= 64:
            for k in np.unique(g):
                idx = np.flatnonzero(g == k)
                out[sl][idx] = GG[idx] @ C9[k]
        else:
            out[sl] = np.matmul(GG, C9[g])
    return out.reshape(m, nloc, nloc, 3, 3)


def blocks_to_dense(blocks: np.ndarray) -> np.ndarray:
    """Element blocks ``(m, nloc, nloc, 3, 3)`` -> matrices ``(m, 3 nloc, 3 nloc)``.

    Parameters
    ----------
    blocks
        Element blocks ``(m, nloc, nloc, 3, 3)``.

    Returns
    -------
    ndarray
        Element matrices ``(m, 3 nloc, 3 nloc)``, DOF ``3 a + i``.
    """
    m, nloc = blocks.shape[:2]
    return blocks.transpose(0, 1, 3, 2, 4).reshape(m, 3 * nloc, 3 * nloc)


def element_stiffness_p1(points: np.ndarray, tets: np.ndarray, Cmat: np.ndarray) -> np.ndarray:
    """P1 linear elastic element stiffness matrices ``(m, 12, 12)``, DOF ``3 a + i``.

    Parameters
    ----------
    points, tets
        Mesh (tets positively oriented).
    Cmat
        Voigt stiffness ``(6, 6)`` or per element ``(m, 6, 6)``.

    Returns
    -------
    ndarray
        Element stiffness matrices ``(m, 12, 12)``.
    """
    G, V = p1_gradients(points, tets)
    Cmat = np.asarray(Cmat, dtype=float)
    if Cmat.ndim == 2:
        blocks = linear_element_blocks(G[:, None], V[:, None], Cmat[None], np.zeros(len(G), int))
    else:
        blocks = linear_element_blocks(G[:, None], V[:, None], Cmat, np.arange(len(G)))
    return blocks_to_dense(blocks)


def stiffness_matrix(
    space: Space,
    D_groups: np.ndarray,
    group: np.ndarray,
    pattern: BlockPattern | None = None,
) -> sp.bsr_matrix:
    """Global linear elastic stiffness (BSR, 3x3 blocks) on ``space``.

    Parameters
    ----------
    space
        Function space (P1 or P2) on the mesh.
    D_groups, group
        Voigt stiffness per material group ``(g, 6, 6)`` and each element's group ``(m,)``.
    pattern
        Block pattern of ``space`` (built when None).

    Returns
    -------
    scipy.sparse.bsr_matrix
        Stiffness ``(3 n_nodes, 3 n_nodes)``.
    """
    pattern = pattern or BlockPattern(space.element_nodes, space.n_nodes)
    return pattern.matrix(linear_element_blocks(space.grads, space.dx, D_groups, group))


def displacement_gradient(space: Space, U: np.ndarray, sl: slice = slice(None)) -> np.ndarray:
    """``grad u`` at the quadrature points ``(m, nq, 3, 3)``; ``U`` is nodal ``(n_nodes, 3)``.

    Parameters
    ----------
    space
        Function space.
    U
        Nodal displacements ``(n_nodes, 3)``.
    sl
        Slice of the elements to evaluate.

    Returns
    -------
    ndarray
        ``grad u[e, q, i, j] = du_i / dX_j``, ``(m, nq, 3, 3)``.
    """
    Ue = U[space.element_nodes[sl]]  # (m, nloc, 3)
    return np.einsum("eqaj,eai->eqij", space.grads[sl], Ue)


def hyperelastic_element_arrays(
    space: Space, law, U: np.ndarray, tangent: bool = True, frames: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray | None]:
    """Internal force ``(m, nloc, 3)`` and tangent blocks ``(m, nloc, nloc, 3, 3)``.

    ``f_ai = sum_q dx P_ij G_aj``, ``K_abik = sum_q dx G_aj A_ijkl G_bl`` with ``P, A`` from
    ``law.stress_tangent(F)``, ``F = I + grad u``. NaN entries mark inverted elements.

    Parameters
    ----------
    space
        Function space.
    law
        Hyperelastic law with ``stress(F)`` and ``stress_tangent(F)``.
    U
        Nodal displacements ``(n_nodes, 3)`` (or flat ``(3 n_nodes,)``).
    tangent
        Also compute the tangent blocks.
    frames
        Element frames ``(m, 3, 3)`` or frames per quadrature point ``(m, nq, 3, 3)``
        (anisotropic laws), passed as ``frames=``.

    Returns
    -------
    fe, Ke
        Element forces ``(m, nloc, 3)``; tangent blocks ``(m, nloc, nloc, 3, 3)`` or None.
    """
    m, nq, nloc, _ = space.grads.shape
    U = np.asarray(U).reshape(-1, 3)
    fe = np.empty((m, nloc, 3))
    Ke = np.empty((m if tangent else 0, nloc * nloc, 9))  # unused (empty) without tangent
    eye = np.eye(3)
    for start in range(0, m, CHUNK):
        sl = slice(start, min(m, start + CHUNK))
        G, dx = space.grads[sl], space.dx[sl]
        F = eye + displacement_gradient(space, U, sl)
        if frames is None:
            kw = {}
        else:  # element frames (m, 3, 3) or frames per quadrature point (m, nq | 1, 3, 3)
            kw = {"frames": frames[sl] if frames.ndim == 4 else frames[sl, None]}
        if tangent:
            P, A = law.stress_tangent(F, **kw)
        else:
            P = law.stress(F, **kw)
        fe[sl] = np.einsum("eq,eqij,eqaj->eai", dx, P, G)
        if tangent:
            # A[i, j, k, l] -> rows (j, l), columns (i, k)
            A9 = A.transpose(0, 1, 3, 5, 2, 4).reshape(A.shape[0], nq, 9, 9)
            if nq == 1:
                GG = _gradient_products(G, dx)
                Ke[sl] = np.matmul(GG, A9[:, 0])
            else:
                acc = 0.0
                for q in range(nq):
                    GG = _gradient_products(G[:, q : q + 1], dx[:, q : q + 1])
                    acc = acc + np.matmul(GG, A9[:, q])
                Ke[sl] = acc
    return fe, (Ke.reshape(m, nloc, nloc, 3, 3) if tangent else None)
