"""Consistent FE load vectors for the scene's loads, and the pressure load stiffness.

Conventions are those of :mod:`springfem.loads`: tractions are dead loads on the
reference surface, pressure is a follower load ``t = -p n`` on the current surface, gravity
is ``rho g`` per unit reference volume, and a total force is spread over its region by
facet area (a uniform traction ``F / A``), or equally over its nodes when the region has no
boundary facets. On P1 these consistent vectors equal the spring model's nodal forces.

The follower pressure uses Nanson's formula on the reference facet,
``n da = J F^-T N dA`` (with ``F`` of the adjacent element), so its load vector is
``f_ai = -p sum_q dx N_a J F^-T N`` and its derivative
``df_ai/du_bk = -p sum_q dx N_a J [(F^-T N)_i (F^-T G_b)_k - (F^-T G_b)_i (F^-T N)_k]``.

Examples
--------
>>> import numpy as np
>>> from springfem.mesh import box_mesh
>>> from reference_fem.space import Space
>>> space = Space(box_mesh((1.0, 2.0, 1.0), (2, 2, 2)), order=1)
>>> f = body_force_vector(space, np.array([0.0, 0.0, -1.0]))
>>> f.reshape(-1, 3).sum(axis=0).round(12).tolist()  # total force b V, V = 2
[0.0, 0.0, -2.0]
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from springfem.scene import Scene

from .assembly import BlockPattern, assemble_vector
from .space import Space


@dataclass
class FacetData:
    """Quadrature data of a set of boundary facets (from a scikit-fem ``FacetBasis``).

    Attributes
    ----------
    element_nodes
        ``(nf, nloc)`` nodes of each facet's adjacent element.
    values, grads
        Shape functions ``(nf, nq, nloc)`` and their gradients ``(nf, nq, nloc, 3)``.
    dx, normals
        Reference area weights ``(nf, nq)`` and outward unit normals ``(nf, nq, 3)``.
    """

    element_nodes: np.ndarray  # (nf, nloc) nodes of the adjacent element
    values: np.ndarray  # (nf, nq, nloc)
    grads: np.ndarray  # (nf, nq, nloc, 3) gradients of the adjacent element's functions
    dx: np.ndarray  # (nf, nq) reference area weights
    normals: np.ndarray  # (nf, nq, 3) outward reference unit normals

    @classmethod
    def build(cls, space: Space, facets: np.ndarray, intorder: int) -> FacetData:
        fb = space.facet_basis(facets, intorder)
        return cls(
            element_nodes=np.ascontiguousarray(fb.element_dofs.T, dtype=np.int64),
            values=np.stack([np.asarray(b[0]) for b in fb.basis], axis=-1),
            grads=np.stack([b[0].grad for b in fb.basis], axis=0).transpose(2, 3, 0, 1),
            dx=np.asarray(fb.dx),
            normals=np.asarray(fb.normals).transpose(1, 2, 0),
        )

    @property
    def area(self) -> float:
        return float(self.dx.sum())


def traction_vector(space: Space, fd: FacetData, traction: np.ndarray) -> np.ndarray:
    """``f_ai = int N_a t_i dA`` for a uniform dead traction ``t`` (3,).

    Parameters
    ----------
    space, fd
        Function space and the loaded facets.
    traction
        Traction ``(3,)`` (Pa) on the reference surface.

    Returns
    -------
    ndarray
        Load vector ``(3 n_nodes,)`` (N).
    """
    fe = np.einsum("fq,fqa,i->fai", fd.dx, fd.values, np.asarray(traction, dtype=float))
    return assemble_vector(fd.element_nodes, fe, space.n_nodes)


def body_force_vector(space: Space, force: np.ndarray | Callable) -> np.ndarray:
    """``f_ai = int N_a b_i dV`` for a uniform body force (3,) or a function of ``x``.

    Parameters
    ----------
    space
        Function space.
    force
        Body force per unit reference volume ``(3,)`` (N/m^3), or a callable taking the
        quadrature points ``(m, nq, 3)`` and returning ``(m, nq, 3)``.

    Returns
    -------
    ndarray
        Load vector ``(3 n_nodes,)`` (N).
    """
    if callable(force):
        b = np.asarray(force(space.quadrature_points()), dtype=float)
    else:
        b = np.broadcast_to(np.asarray(force, dtype=float), space.dx.shape + (3,))
    fe = np.einsum("eq,qa,eqi->eai", space.dx, space.values, b)
    return assemble_vector(space.element_nodes, fe, space.n_nodes)


def pressure_arrays(
    fd: FacetData, p: float, U: np.ndarray | None, tangent: bool = True
) -> tuple[np.ndarray, np.ndarray | None]:
    """Follower pressure: element forces ``(nf, nloc, 3)`` and ``d f / d u`` blocks.

    Parameters
    ----------
    fd
        The loaded facets.
    p
        Pressure (Pa), positive into the surface (``t = -p n``).
    U
        Nodal displacements ``(n_nodes, 3)``; None gives the dead (reference-surface) load
        and no stiffness.
    tangent
        Also compute the load stiffness.

    Returns
    -------
    fe, Ke
        Element forces ``(nf, nloc, 3)`` and blocks ``(nf, nloc, nloc, 3, 3)`` (or None).
    """
    nf, nq, nloc = fd.values.shape
    if U is None:
        fe = -p * np.einsum("fq,fqa,fqi->fai", fd.dx, fd.values, fd.normals)
        return fe, None
    Ue = np.asarray(U).reshape(-1, 3)[fd.element_nodes]
    F = np.eye(3) + np.einsum("fqaj,fai->fqij", fd.grads, Ue)
    J = np.linalg.det(F)
    FiT = np.swapaxes(np.linalg.inv(F), -1, -2)
    n = np.einsum("fqij,fqj->fqi", FiT, fd.normals)  # F^-T N
    w = fd.dx * J  # J dA
    fe = -p * np.einsum("fq,fqa,fqi->fai", w, fd.values, n)
    if not tangent:
        return fe, None
    g = np.einsum("fqkl,fqbl->fqbk", FiT, fd.grads)  # F^-T G_b
    Ke = -p * (
        np.einsum("fq,fqa,fqi,fqbk->fabik", w, fd.values, n, g)
        - np.einsum("fq,fqa,fqbi,fqk->fabik", w, fd.values, g, n)
    )
    return fe, Ke


@dataclass
class ExternalLoads:
    """All of a scene's loads on a space: a dead part and follower pressures.

    Parameters
    ----------
    follower
        Apply pressure on the current surface (nonlinear laws); ``False`` applies it on the
        reference surface (geometrically linear analysis).
    """

    space: Space
    dead: np.ndarray
    pressures: list[tuple[FacetData, float, BlockPattern]] = field(default_factory=list)
    follower: bool = True

    @classmethod
    def from_scene(cls, scene: Scene, space: Space, follower: bool = True) -> ExternalLoads:
        dead = np.zeros(space.n_dofs)
        pressures = []
        q = 2 * space.order  # exact for uniform tractions and gravity
        for load in scene.loads:
            if load.type == "gravity":
                dead += body_force_vector(space, scene.material.density * load.value)
                continue
            assert load.region is not None  # every load but gravity acts on a region
            if load.type == "traction":
                fd = FacetData.build(space, load.region.facets, q)
                dead += traction_vector(space, fd, load.value)
            elif load.type == "force":
                if load.region.facets.size:
                    fd = FacetData.build(space, load.region.facets, q)
                    dead += traction_vector(space, fd, load.value / fd.area)
                else:
                    nodes = load.region.nodes
                    for c in range(3):
                        np.add.at(dead, 3 * nodes + c, load.value[c] / nodes.size)
            elif load.type == "pressure":
                fd = FacetData.build(space, load.region.facets, 4 if space.order == 2 else 2)
                pat = BlockPattern(fd.element_nodes, space.n_nodes)
                pressures.append((fd, float(load.value[0]), pat))
        return cls(space, dead, pressures, follower)

    @property
    def has_follower(self) -> bool:
        return self.follower and bool(self.pressures)

    def vector(self, U: np.ndarray | None = None, scale: float = 1.0) -> np.ndarray:
        """External force ``(n_dofs,)`` at load factor ``scale`` and displacement ``U``."""
        f = scale * self.dead
        for fd, p, _ in self.pressures:
            fe, _ = pressure_arrays(fd, p, U if self.follower else None, tangent=False)
            f = f + scale * assemble_vector(fd.element_nodes, fe, self.space.n_nodes)
        return f

    def vector_and_stiffness(
        self, U: np.ndarray, scale: float = 1.0
    ) -> tuple[np.ndarray, sp.spmatrix | None]:
        """External force and its derivative ``d f_ext / d u`` (``None`` if constant)."""
        if not self.has_follower:
            return self.vector(U, scale), None
        f = scale * self.dead
        K = None
        for fd, p, pat in self.pressures:
            fe, Ke = pressure_arrays(fd, p, U, tangent=True)
            assert Ke is not None  # asked for
            f = f + scale * assemble_vector(fd.element_nodes, fe, self.space.n_nodes)
            Kp = pat.matrix(scale * Ke)
            K = Kp if K is None else K + Kp
        return f, K
