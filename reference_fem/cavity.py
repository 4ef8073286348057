"""The P2 field's endocardial facet nodes for the cardiac outputs (model-neutral form).

:class:`springfem.cardiac.PressureVolume` integrates the cavity volume over the field's own
facets when the model hands it the deformed positions of each facet's 6 nodes (its vertices,
then the midside nodes of edges (0,1), (1,2), (2,0)). For P2 (and the displacement block of
the mixed P2/P1 formulation) those are the space's vertex and edge nodes plus the nodal
displacement; P1 has no midside nodes (the facets are flat): ``None``.

Examples
--------
>>> from springfem.mesh import box_mesh
>>> from reference_fem.space import Space
>>> s = Space(box_mesh((1.0, 1.0, 1.0), (1, 1, 1)), order=2)
>>> nodes = facet_nodes(s)
>>> x = nodes(np.zeros(s.n_dofs), np.array([[0, 1, 3]]))
>>> x.shape, bool(np.allclose(x[0, 3], 0.5 * (x[0, 0] + x[0, 1])))
((1, 6, 3), True)
"""

from __future__ import annotations

import numpy as np

from springfem.cardiac import PressureVolume, pressure_volume
from springfem.errors import InputError
from springfem.quadratic_facets import FACET_EDGES


def facet_nodes(space):
    """``(state, tris) -> (k, 6, 3)`` deformed facet nodes of a P2 space, ``None`` for P1.

    Parameters
    ----------
    space
        A :class:`~reference_fem.space.Space`; the state's first ``space.n_dofs`` entries
        are the nodal displacements (``3 * node + component``).

    Returns
    -------
    callable or None
    """
    if space.order != 2:
        return None
    n = space.n_vertices
    edges = np.sort(space.edges, axis=1)
    keys = edges[:, 0] * n + edges[:, 1]
    order = np.argsort(keys)
    sorted_keys = keys[order]
    coords = space.node_coordinates

    def nodes(state: np.ndarray, tris: np.ndarray) -> np.ndarray:
        tris = np.asarray(tris, dtype=np.int64)
        pairs = np.sort(tris[:, list(FACET_EDGES)], axis=2)  # (k, 3, 2)
        want = pairs[..., 0] * n + pairs[..., 1]
        pos = np.minimum(np.searchsorted(sorted_keys, want), len(keys) - 1)
        if not np.array_equal(sorted_keys[pos], want):
            raise InputError("cavity volume: facet edges that are not edges of the mesh")
        idx = np.concatenate([tris, n + order[pos]], axis=1)  # (k, 6) node indices
        U = np.asarray(state)[: space.n_dofs].reshape(-1, 3)
        return coords[idx] + U[idx]

    return nodes


def cavity_recorder(problem) -> PressureVolume | None:
    """The pressure-volume recorder of a ventricle problem (P2: over its quadratic facets).

    Parameters
    ----------
    problem
        A FEM problem (``scene``, ``space``, ``state``).

    Returns
    -------
    PressureVolume or None
        ``None`` unless the scene is a ventricle loaded on ``endo``.
    """
    return pressure_volume(problem.scene, problem.state, facet_nodes(problem.space))
