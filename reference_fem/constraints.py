"""Prescribed displacements on P1/P2 nodes, support reactions, and the rigid-motion check.

A scene boundary prescribes components of a constant displacement on a region's vertices
(:meth:`Scene.dirichlet`); on P2 the same value goes to every edge node whose two vertices
are in the region. Later boundaries override earlier ones on shared DOFs, as in the scene.

Reactions follow :func:`springfem.loads.reactions`: the support force on a constrained
DOF is ``-(f_ext - f_int) = R`` with the residual ``R = f_int - f_ext``, summed per
boundary region (key ``boundary.region.name``).

Examples
--------
>>> from reference_fem.scenes import bench_scene
>>> from reference_fem.space import Space
>>> scene = bench_scene(100)  # clamped on x_min: 9 vertices, 3 components each
>>> space = Space(scene.mesh, order=1)
>>> d = dirichlet(scene, space)
>>> len(d.dofs), int(d.free.sum())
(27, 108)
>>> check_rigid_motions(space, d.dofs) is None  # the clamp removes all six
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse.csgraph import connected_components

from springfem.errors import SolverError
from springfem.mechanics import rigid_body_modes
from springfem.scene import Scene

from .space import Space


@dataclass
class Dirichlet:
    """Constrained DOFs, their prescribed values, and the DOFs of each boundary.

    Attributes
    ----------
    dofs, values
        Constrained DOF indices and their prescribed displacements (m).
    boundary_dofs
        Per boundary: ``(region name, dofs, components)``, for the reactions.
    n_dofs
        Number of DOFs of the space.
    """

    dofs: np.ndarray
    values: np.ndarray
    boundary_dofs: list[tuple[str, np.ndarray, np.ndarray]]  # (name, dofs, components)
    n_dofs: int

    @property
    def free(self) -> np.ndarray:
        """Boolean mask of the free DOFs."""
        mask = np.ones(self.n_dofs, dtype=bool)
        mask[self.dofs] = False
        return mask

    def reactions(self, residual: np.ndarray) -> dict[str, list[float]]:
        """Total support force per boundary region from ``R = f_int - f_ext``."""
        out: dict[str, np.ndarray] = {}
        for name, dofs, comps in self.boundary_dofs:
            total = np.bincount(comps, weights=residual[dofs], minlength=3)
            out[name] = out.get(name, np.zeros(3)) + total
        return {k: v.tolist() for k, v in out.items()}


def dirichlet(scene: Scene, space: Space) -> Dirichlet:
    """Constrained DOFs and values on ``space`` for the scene's boundaries.

    Parameters
    ----------
    scene
        Scene whose boundaries prescribe displacement components on regions.
    space
        P1 or P2 space (P2 edge nodes inside a region get the same value).

    Returns
    -------
    Dirichlet
        The constraints (later boundaries override earlier ones on shared DOFs).
    """
    values = np.full(space.n_dofs, np.nan)
    per_boundary = []
    for b in scene.boundaries:
        nodes = space.region_nodes(b.region.nodes)
        comps = np.array(b.components, dtype=np.int64)
        dofs = (3 * nodes[:, None] + comps[None, :]).ravel()
        values[dofs] = np.tile(b.value[comps], len(nodes))
        per_boundary.append((b.region.name, dofs, np.tile(comps, len(nodes))))
    dofs = np.flatnonzero(~np.isnan(values))
    return Dirichlet(dofs, values[dofs], per_boundary, space.n_dofs)


def check_rigid_motions(space: Space, fixed_dofs: np.ndarray, where: str = "") -> None:
    """Raise :class:`SolverError` if the constraints leave a rigid-body motion free.

    Each connected piece of the mesh needs constraints whose restriction of the six
    rigid-body modes has rank 6; otherwise the stiffness matrix is singular.

    Parameters
    ----------
    space
        Function space.
    fixed_dofs
        Indices of the constrained DOFs.
    where
        Context appended to the error message.

    Raises
    ------
    SolverError
        Naming the free translations and the number of free rotations.
    """
    tets = space.mesh.tets
    n_v = space.n_vertices
    import scipy.sparse as sp

    rows = np.repeat(tets[:, 0], 3)
    cols = tets[:, 1:].ravel()
    graph = sp.coo_matrix((np.ones(rows.size), (rows, cols)), shape=(n_v, n_v))
    n_comp, label = connected_components(graph, directed=False)
    node_label = label
    if space.order == 2:
        node_label = np.concatenate([label, label[space.edges[:, 0]]])
    coords = space.node_coordinates
    fixed = np.zeros(space.n_dofs, dtype=bool)
    fixed[fixed_dofs] = True
    for k in range(n_comp):
        nodes = np.flatnonzero(node_label == k)
        dofs = (3 * nodes[:, None] + np.arange(3)).ravel()
        B = rigid_body_modes(coords[nodes])
        Bf = B[fixed[dofs]]
        scale = np.linalg.norm(B, axis=0)
        Bf = Bf / np.maximum(scale, 1e-300)
        n_free = 6
        if Bf.shape[0]:
            w = np.linalg.eigvalsh(Bf.T @ Bf)  # squared singular values
            n_free = int((w <= 1e-12 * max(w.max(), 1e-300)).sum())  # sigma ratio 1e-6
        if n_free == 0:
            continue
        # a translation is free when no node of the piece has that component prescribed
        held = fixed[dofs].reshape(-1, 3).any(axis=0)
        names = [f"translation {'xyz'[c]}" for c in range(3) if not held[c]]
        n_rot = n_free - len(names)
        if n_rot:
            names.append(f"{n_rot} rotation{'s' if n_rot > 1 else ''}")
        piece = f" (mesh piece {k + 1} of {n_comp})" if n_comp > 1 else ""
        what = (
            "no displacement is prescribed"
            if not fixed[dofs].any()
            else "the prescribed displacements leave rigid-body motion free"
        )
        raise SolverError(
            f"{where}singular stiffness matrix{piece}: {what} ({', '.join(names)}); "
            "add boundary conditions"
        )
