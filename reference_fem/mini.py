"""The MINI element: P1-bubble displacement / P1 pressure (``[fem] formulation = "mini"``).

Arnold, Brezzi & Fortin (1984): each linear tet's displacement is enriched by the quartic
bubble ``256 L1 L2 L3 L4`` (scikit-fem's ``ElementTetMini``), which vanishes on the
element's faces; with a continuous P1 pressure the pair is inf-sup stable, the cheapest
stable mixed pair on the spring model's own vertices. The u–p potential, residual and
tangent are those of :mod:`reference_fem.mixed` on this space: DOFs are the vertex
displacements, then the three bubble DOFs of each element (node ``n_vertices + element``),
then one pressure per vertex. The bubbles are kept as unknowns of the one linear solve
(not condensed). Quadrature: the 11-point degree-4 rule (``intorder = 4``).
Manual: docs/fem.rst#mini-element.

Examples
--------
>>> import numpy as np
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({
...     "mesh": {"generator": "box", "size": [1, 1, 1], "divisions": [1, 1, 1]},
...     "material": {"law": "neo-hookean", "E": 1.0, "nu": 0.4999},
...     "fem": {"formulation": "mini"}})
>>> p = MiniProblem(scene)
>>> p.law_name, p.space.n_nodes == scene.mesh.n_points + scene.mesh.n_tets
('neo-hookean/coupled/mini-P1bP1', True)
>>> float(np.abs(p.internal_force(np.zeros(p.n_dofs))[0]).max())  # stress free at rest
0.0
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import skfem

from springfem.mesh import TetMesh
from springfem.scene import Scene

from .mixed import MixedProblem
from .space import Space

#: Quadrature of the MINI space: degree 4 (11 points).
MINI_INTORDER = 4


class MiniSpace(Space):
    """P1 plus one bubble per element, on the scene's vertices (vector DOFs interleaved).

    Parameters
    ----------
    mesh
        The scene mesh.
    intorder
        Quadrature order (default :data:`MINI_INTORDER`).
    """

    def __init__(self, mesh: TetMesh, intorder: int | None = None):
        self.mesh = mesh
        self.edge_nodes = None  # straight-sided tets only
        self.order = 1  # vertices are the only nodes on the boundary: regions as for P1
        self.intorder = MINI_INTORDER if intorder is None else int(intorder)
        self.n_vertices = mesh.n_points
        basis = self.basis
        self.element_nodes = np.ascontiguousarray(basis.element_dofs.T, dtype=np.int64)
        self.grads = np.ascontiguousarray(
            np.stack([b[0].grad for b in basis.basis], axis=0).transpose(2, 3, 0, 1)
        )
        self.dx = np.asarray(basis.dx)
        self.values = np.stack([np.asarray(b[0])[0] for b in basis.basis], axis=1)
        self.n_nodes = int(basis.N)

    @cached_property
    def element(self) -> skfem.Element:
        """scikit-fem's P1-bubble element."""
        return skfem.ElementTetMini()

    @cached_property
    def node_coordinates(self) -> np.ndarray:
        """Vertices, then the element centroids (the bubble nodes)."""
        return np.vstack([self.mesh.points, self.mesh.centers()])


class MiniProblem(MixedProblem):
    """The MINI discretisation (same protocol and block structure as MixedProblem).

    Parameters
    ----------
    scene, order, law, intorder
        As for :class:`~reference_fem.mixed.MixedProblem`; ``order`` must be 1.
    """

    pair_order, pair_label = 1, "mini-P1bP1"

    def __init__(
        self,
        scene: Scene,
        order: int | None = None,
        law: str | None = None,
        intorder: int | None = None,
    ):
        super().__init__(scene, 1 if order is None else order, law, intorder)

    def _make_space(self, scene: Scene, intorder: int | None) -> Space:
        return MiniSpace(scene.mesh, intorder)
