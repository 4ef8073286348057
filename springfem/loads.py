"""External loads as nodal forces on linear (P1) tets, and reactions per fixed region.

Used by the spring model (whose nodes are the mesh vertices) and by tests as an
independent check of the FEM load vectors. Tractions are dead loads on the reference
surface; pressure is a follower load ``t = -p n`` on the current surface; gravity is
lumped to vertices with ``rho V / 4``; a total force is spread over a region by facet
area (or equally over its nodes when it has no boundary facets).

Examples
--------
>>> from springfem.scene import scene_from_dict
>>> s = scene_from_dict({
...     "mesh": {"generator": "box", "size": [1.0, 1.0, 1.0], "divisions": [1, 1, 1]},
...     "material": {"law": "linear", "E": 1.0, "nu": 0.25, "density": 2.0},
...     "load": [{"type": "gravity", "value": [0.0, 0.0, -10.0]}]})
>>> external_forces(s).sum(axis=0).round(12).tolist()  # the weight, rho V g
[0.0, 0.0, -20.0]
"""

from __future__ import annotations

import numpy as np

from .regions import facet_areas_normals
from .scene import Scene


def lumped_masses(scene: Scene) -> np.ndarray:
    """Nodal masses: each tet gives ``rho V / 4`` to each of its vertices.

    Parameters
    ----------
    scene
        The scene (its mesh and material density).

    Returns
    -------
    numpy.ndarray
        ``(n,)`` mass per node (kg).
    """
    m = np.zeros(scene.mesh.n_points)
    np.add.at(m, scene.mesh.tets, (scene.material.density * scene.mesh.volumes() / 4)[:, None])
    return m


def _spread_on_facets(n_points: int, facets: np.ndarray, per_facet: np.ndarray) -> np.ndarray:
    f = np.zeros((n_points, 3))
    for a in range(3):
        np.add.at(f, facets[:, a], per_facet / 3.0)
    return f


def external_forces(scene: Scene, x: np.ndarray | None = None, scale: float = 1.0) -> np.ndarray:
    """Nodal external force ``(n, 3)`` of all the scene's loads, times ``scale``.

    Parameters
    ----------
    scene
        The scene.
    x
        Current node positions for follower (pressure) loads; default: the rest positions.
    scale
        Load factor (for load stepping).

    Returns
    -------
    numpy.ndarray
        ``(n, 3)`` force per node (N).
    """
    mesh = scene.mesh
    n = mesh.n_points
    f = np.zeros((n, 3))
    for load in scene.loads:
        if load.type == "gravity":
            f += lumped_masses(scene)[:, None] * load.value[None, :]
            continue
        reg = load.region
        assert reg is not None  # every load but gravity acts on a region
        if load.type == "traction":
            area, _ = facet_areas_normals(mesh.points, reg.facets)
            f += _spread_on_facets(n, reg.facets, area[:, None] * load.value[None, :])
        elif load.type == "pressure":
            pts = mesh.points if x is None else x
            area, normal = facet_areas_normals(pts, reg.facets)
            f += _spread_on_facets(n, reg.facets, -load.value[0] * (area[:, None] * normal))
        elif load.type == "force":
            if reg.facets.size:
                area, _ = facet_areas_normals(mesh.points, reg.facets)
                w = area / area.sum()
                f += _spread_on_facets(n, reg.facets, w[:, None] * load.value[None, :])
            else:
                f[reg.nodes] += load.value / reg.nodes.size
    return scale * f


def has_follower_loads(scene: Scene) -> bool:
    """Whether any load depends on the deformed configuration.

    Parameters
    ----------
    scene
        The scene.

    Returns
    -------
    bool
        ``True`` when the scene has a (follower) pressure load.
    """
    return any(load.type == "pressure" for load in scene.loads)


def reactions(scene: Scene, residual: np.ndarray) -> dict[str, list[float]]:
    """Total support force per boundary region.

    Parameters
    ----------
    scene
        The scene (its boundaries name the regions).
    residual
        Nodal force ``(n, 3)`` the body feels without its supports (internal + external).
        At equilibrium the supports supply ``-residual`` on the constrained DOFs.

    Returns
    -------
    dict
        Region name -> total reaction ``[Fx, Fy, Fz]`` over its constrained components
        (regions named twice are summed).
    """
    r = np.asarray(residual).reshape(-1, 3)
    out: dict[str, list[float]] = {}
    for b in scene.boundaries:
        total = np.zeros(3)
        for c in b.components:
            total[c] = -r[b.region.nodes, c].sum()
        key = b.region.name
        out[key] = (np.asarray(out.get(key, np.zeros(3))) + total).tolist()
    return out
