"""Named regions of a mesh: node sets and boundary facets.

A region is given in a scene as a name (box faces ``x_min`` … ``z_max`` of the bounding
box, or a node/cell/facet set from the mesh file), as ``{ box = [[x0,y0,z0],[x1,y1,z1]] }``
or as ``{ point = [x, y, z] }`` (the nearest node).

Examples
--------
>>> from springfem.mesh import box_mesh
>>> m = box_mesh((1.0, 1.0, 1.0), (2, 2, 2))
>>> r = resolve_region(m, "x_max")
>>> r.nodes.size, r.facets.shape  # a 3 x 3 grid of nodes, 2 x 2 squares of 2 triangles
(9, (8, 3))
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InputError
from .mesh import TetMesh

BOX_FACES = ("x_min", "x_max", "y_min", "y_max", "z_min", "z_max")


@dataclass(frozen=True)
class Region:
    """Nodes of a region and the boundary triangles (outward oriented) that lie in it.

    Attributes
    ----------
    name
        The region's label (:func:`region_label` of its spec).
    nodes
        Node indices ``(k,)``.
    facets
        Boundary triangles ``(f, 3)`` whose three nodes are in the region.
    """

    name: str
    nodes: np.ndarray
    facets: np.ndarray


def region_label(spec: str | dict) -> str:
    """Short human-readable label of a region spec (used in messages and result keys).

    Parameters
    ----------
    spec
        A name, ``{"box": [[x0, y0, z0], [x1, y1, z1]]}`` or ``{"point": [x, y, z]}``.

    Returns
    -------
    str
        The name, or ``box[[...], [...]]`` / ``point[x, y, z]`` with plain floats.

    Examples
    --------
    >>> region_label({"point": [1, 0, 0]})
    'point[1.0, 0.0, 0.0]'
    """
    if isinstance(spec, str):
        return spec
    if "box" in spec:
        return "box" + str([list(map(float, c)) for c in spec["box"]])
    return "point" + str(list(map(float, spec["point"])))


def resolve_region(mesh: TetMesh, spec: str | dict, where: str = "region") -> Region:
    """Resolve a region spec on ``mesh``.

    Parameters
    ----------
    mesh
        The mesh.
    spec
        A box face (``x_min`` … ``z_max`` of the bounding box, within ``1e-9`` of its
        largest extent), a node, cell or facet set of the mesh file,
        ``{"box": [[x0, y0, z0], [x1, y1, z1]]}`` or ``{"point": [x, y, z]}`` (the nearest
        node).
    where
        What to name in error messages (file and key).

    Returns
    -------
    Region

    Raises
    ------
    InputError
        If the name is unknown (listing the valid ones) or the region selects nothing.
    """
    label = region_label(spec)
    bf = mesh.boundary_facets()
    if isinstance(spec, str):
        if spec in BOX_FACES:
            axis = "xyz".index(spec[0])
            lo, hi = mesh.bounding_box()
            target = lo[axis] if spec.endswith("min") else hi[axis]
            tol = 1e-9 * float(np.ptp(mesh.points, axis=0).max())
            on = np.abs(mesh.points[:, axis] - target) <= tol
            nodes = np.flatnonzero(on)
            facets = bf[on[bf].all(axis=1)]
        elif spec in mesh.facet_sets:
            facets = outward_facets(mesh.facet_sets[spec], bf)
            nodes = np.unique(facets)
        elif spec in mesh.node_sets:
            nodes = np.unique(mesh.node_sets[spec])
            mask = np.zeros(mesh.n_points, dtype=bool)
            mask[nodes] = True
            facets = bf[mask[bf].all(axis=1)]
        elif spec in mesh.cell_sets:
            nodes = np.unique(mesh.tets[mesh.cell_sets[spec]])
            mask = np.zeros(mesh.n_points, dtype=bool)
            mask[nodes] = True
            facets = bf[mask[bf].all(axis=1)]
        else:
            valid = list(BOX_FACES) + sorted(
                set(mesh.facet_sets) | set(mesh.node_sets) | set(mesh.cell_sets)
            )
            shown = ", ".join(valid[:20]) + (f" … ({len(valid)} in all)" if len(valid) > 20 else "")
            name = repr(spec) if len(spec) <= 60 else repr(spec[:59]) + "…"
            raise InputError(
                f"{where}: unknown region {name}; valid names: {shown}, "
                "or { box = [[x0,y0,z0],[x1,y1,z1]] } or { point = [x,y,z] }"
            )
    elif "box" in spec:
        lo, hi = (np.asarray(c, dtype=float) for c in spec["box"])
        tol = 1e-9 * float(np.ptp(mesh.points, axis=0).max())
        inside = np.all((mesh.points >= lo - tol) & (mesh.points <= hi + tol), axis=1)
        nodes = np.flatnonzero(inside)
        facets = bf[inside[bf].all(axis=1)]
    else:
        p = np.asarray(spec["point"], dtype=float)
        nodes = np.array([int(np.argmin(((mesh.points - p) ** 2).sum(axis=1)))])
        facets = np.zeros((0, 3), dtype=np.int64)
    if nodes.size == 0:
        raise InputError(f"{where}: region {label} selects no nodes")
    return Region(name=label, nodes=nodes.astype(np.int64), facets=np.asarray(facets, np.int64))


def outward_facets(facets: np.ndarray, boundary: np.ndarray) -> np.ndarray:
    """A facet set with each of its boundary triangles oriented as in ``boundary`` (outward).

    A mesh file's facet set keeps the file's vertex order, which need not point out of the
    body (cardiac-geometries' gmsh ventricle orders every facet inward). A pressure's
    direction follows the order (:func:`springfem.loads.external_forces`), so each facet of
    the set that lies on the boundary takes the orientation of its boundary facet; the others
    keep theirs. A facet already outward keeps its vertex order; an inward one swaps its last
    two vertices.

    Parameters
    ----------
    facets
        Triangles ``(k, 3)`` in any order.
    boundary
        The mesh's outward boundary facets (:meth:`~springfem.mesh.TetMesh.boundary_facets`).

    Returns
    -------
    numpy.ndarray
        ``(k, 3)``: the same triangles, boundary ones outward.

    Examples
    --------
    >>> from springfem.mesh import box_mesh
    >>> m = box_mesh((1.0, 1.0, 1.0), (1, 1, 1))
    >>> bf = m.boundary_facets()
    >>> _, n = facet_areas_normals(m.points, bf)
    >>> _, flipped = facet_areas_normals(m.points, outward_facets(bf[:, ::-1], bf))
    >>> bool(np.allclose(flipped, n)), bool((outward_facets(bf, bf) == bf).all())
    (True, True)
    """
    facets = np.asarray(facets, dtype=np.int64).reshape(-1, 3)
    boundary = np.asarray(boundary, dtype=np.int64).reshape(-1, 3)
    if len(facets) == 0 or len(boundary) == 0:
        return facets
    both = np.sort(np.concatenate([boundary, facets]), axis=1)
    _, ids = np.unique(both, axis=0, return_inverse=True)
    ids = ids.ravel()
    kb, kf = ids[: len(boundary)], ids[len(boundary) :]
    order = np.argsort(kb)
    at = order[np.minimum(np.searchsorted(kb, kf, sorter=order), len(kb) - 1)]
    on = kb[at] == kf
    b, f = boundary[at], facets
    pos = np.argmax(b == f[:, :1], axis=1)  # where f's first vertex sits in b
    inward = on & (b[np.arange(len(f)), (pos + 1) % 3] != f[:, 1])
    out = facets.copy()
    out[inward] = facets[inward][:, [0, 2, 1]]
    return out


def facet_areas_normals(points: np.ndarray, facets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Areas and unit normals of triangles at ``points``.

    Parameters
    ----------
    points
        Node positions ``(n, 3)``.
    facets
        Triangles ``(k, 3)``; the normal follows the right-hand rule of their node order.

    Returns
    -------
    area : numpy.ndarray
        ``(k,)``.
    normal : numpy.ndarray
        ``(k, 3)`` unit normals (outward for :func:`~springfem.mesh.boundary_facets`).
    """
    x = points[facets]
    a = 0.5 * np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    area = np.linalg.norm(a, axis=1)
    return area, a / np.maximum(area, 1e-300)[:, None]


def locate_points(
    points: np.ndarray, tets: np.ndarray, query: np.ndarray, tol: float = 1e-9
) -> tuple[np.ndarray, np.ndarray]:
    """Find the tet containing each query point and its barycentric coordinates.

    Parameters
    ----------
    points, tets
        The mesh.
    query
        Points ``(q, 3)`` (or one point ``(3,)``).
    tol
        How far below 0 a barycentric coordinate may be for a point on a face.

    Returns
    -------
    tet_index : numpy.ndarray
        ``(q,)`` containing tet, ``-1`` for points outside the mesh.
    bary : numpy.ndarray
        ``(q, 4)`` barycentric coordinates in that tet (zeros outside).
    """
    from scipy.spatial import cKDTree

    query = np.atleast_2d(np.asarray(query, dtype=float))
    x = points[tets]
    centers = x.mean(axis=1)
    T = np.stack([x[:, 1] - x[:, 0], x[:, 2] - x[:, 0], x[:, 3] - x[:, 0]], axis=2)
    tree = cKDTree(centers)
    k = min(64, len(tets))
    out_idx = -np.ones(len(query), dtype=np.int64)
    out_bary = np.zeros((len(query), 4))
    for q, p in enumerate(query):
        _, cand = tree.query(p, k=k)
        cand = np.atleast_1d(cand)
        lam = np.linalg.solve(T[cand], (p - x[cand, 0])[..., None])[..., 0]
        bary = np.column_stack([1 - lam.sum(axis=1), lam])
        worst = bary.min(axis=1)
        best = int(np.argmax(worst))
        if worst[best] >= -tol:
            out_idx[q] = cand[best]
            out_bary[q] = bary[best]
        else:  # fall back to a full search (far from the centers of large tets)
            lam = np.linalg.solve(T, (p - x[:, 0])[..., None])[..., 0]
            bary = np.column_stack([1 - lam.sum(axis=1), lam])
            worst = bary.min(axis=1)
            best = int(np.argmax(worst))
            if worst[best] >= -tol:
                out_idx[q] = best
                out_bary[q] = bary[best]
    return out_idx, out_bary


@dataclass(frozen=True)
class NamedSet:
    """One named set of a mesh file, with its size (``springfem inspect`` lists them).

    Attributes
    ----------
    name
        The set's name, which a scene uses as a region.
    kind
        ``cells`` (tets), ``facets`` (boundary triangles) or ``nodes``.
    count
        How many tets, triangles or nodes it holds.
    nodes
        How many distinct nodes it touches.
    size
        Its volume (cells, in the mesh's length unit cubed) or area (facets, squared);
        ``None`` for a node set.
    """

    name: str
    kind: str
    count: int
    nodes: int
    size: float | None

    @property
    def line(self) -> str:
        """One line: ``hilum: 24 facets, 20 nodes, area 0.00171``."""
        what = {"cells": "tets", "facets": "facets", "nodes": "nodes"}[self.kind]
        text = f"{self.name}: {self.count} {what}"
        if self.kind != "nodes":
            measure = "volume" if self.kind == "cells" else "area"
            text += f", {self.nodes} nodes, {measure} {self.size:.4g}"
        return text


def named_sets(mesh: TetMesh) -> list[NamedSet]:
    """The named cell, facet and node sets the mesh file brought, with their sizes.

    The box faces ``x_min`` … ``z_max`` are not listed: they are names of any mesh's
    bounding box, not of the file.

    Parameters
    ----------
    mesh
        The mesh.

    Returns
    -------
    list of NamedSet
        Cell sets, then facet sets, then node sets, each by name.

    Examples
    --------
    >>> from springfem.mesh import box_mesh
    >>> m = box_mesh((2.0, 1.0, 1.0), (2, 1, 1))
    >>> left = np.flatnonzero(m.points[m.tets].mean(axis=1)[:, 0] < 1.0)
    >>> m.cell_sets["left"] = left
    >>> [s.line for s in named_sets(m)]
    ['left: 6 tets, 8 nodes, volume 1']
    """
    out = []
    volumes = mesh.volumes()
    for name in sorted(mesh.cell_sets):
        cells = np.asarray(mesh.cell_sets[name], dtype=np.int64)
        nodes = np.unique(mesh.tets[cells]).size
        out.append(NamedSet(name, "cells", cells.size, nodes, float(volumes[cells].sum())))
    for name in sorted(mesh.facet_sets):
        facets = np.asarray(mesh.facet_sets[name], dtype=np.int64).reshape(-1, 3)
        areas, _ = facet_areas_normals(mesh.points, facets)
        nodes = np.unique(facets).size
        out.append(NamedSet(name, "facets", len(facets), nodes, float(areas.sum())))
    for name in sorted(mesh.node_sets):
        nodes = np.unique(mesh.node_sets[name]).size
        out.append(NamedSet(name, "nodes", nodes, nodes, None))
    return out
