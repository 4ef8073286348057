"""The nearest point of a mesh's boundary to a point outside it, and the element there.

A probe placed on a curved surface (a sphere, an organ) lies on the smooth surface, not on
the flat facets of its mesh: a little outside the mesh where the surface bulges out.
:func:`nearest_boundary_point` finds the closest point of the boundary triangles, the tet
that owns the triangle, the point's barycentric coordinates in it and that tet's size
(its mean edge length), so that a caller can snap a point that is within a fraction of an
element of the mesh and refuse one farther out.

Examples
--------
>>> import numpy as np
>>> from springfem.mesh.generate import box_mesh
>>> m = box_mesh((1.0, 1.0, 1.0), (2, 2, 2))
>>> near = nearest_boundary_point(m, np.array([1.1, 0.5, 0.25]))
>>> near.point.round(12).tolist(), round(near.distance, 12)
([1.0, 0.5, 0.25], 0.1)
>>> bool(np.allclose(near.bary @ m.points[m.tets[near.tet]], near.point))
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .tetmesh import _FACES, TetMesh


@dataclass(frozen=True)
class NearestPoint:
    """The nearest boundary point of a mesh to a query point.

    Attributes
    ----------
    point
        ``(3,)`` the nearest point of the boundary triangles.
    distance
        Its distance from the query point.
    tet
        The tet whose face holds it.
    bary
        ``(4,)`` its barycentric coordinates in that tet (non-negative, summing to 1).
    size
        That tet's mean edge length.
    """

    point: np.ndarray
    distance: float
    tet: int
    bary: np.ndarray
    size: float


def _closest_on_segments(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Closest points to ``p`` of the segments ``a[i] b[i]`` (``(k, 3)`` each)."""
    ab = b - a
    t = np.einsum("ij,ij->i", p - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    return a + np.clip(t, 0.0, 1.0)[:, None] * ab


def closest_on_triangles(p: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """The closest point to ``p`` of each triangle ``tri`` ``(k, 3, 3)``: the projection on
    its plane when that falls inside, else the closest point of its three edges.

    Parameters
    ----------
    p
        ``(3,)`` the point.
    tri
        ``(k, 3, 3)`` triangle corners.

    Returns
    -------
    numpy.ndarray
        ``(k, 3)``.

    Examples
    --------
    >>> t = np.array([[[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]])
    >>> closest_on_triangles(np.array([0.2, 0.2, 3.0]), t).tolist()  # above the inside
    [[0.2, 0.2, 0.0]]
    >>> closest_on_triangles(np.array([2.0, -1.0, 0.5]), t).tolist()  # nearest the corner
    [[1.0, 0.0, 0.0]]
    """
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    n = np.cross(b - a, c - a)
    nn = np.maximum(np.einsum("ij,ij->i", n, n), 1e-300)
    q = p - (np.einsum("ij,ij->i", p - a, n) / nn)[:, None] * n  # projection on the plane
    # barycentric coordinates of q from the sub-triangle areas (signed along n)
    wa = np.einsum("ij,ij->i", np.cross(c - b, q - b), n) / nn
    wb = np.einsum("ij,ij->i", np.cross(a - c, q - c), n) / nn
    inside = (wa >= 0) & (wb >= 0) & (1.0 - wa - wb >= 0)
    edges = np.stack(
        [
            _closest_on_segments(p, a, b),
            _closest_on_segments(p, b, c),
            _closest_on_segments(p, c, a),
        ]
    )  # (3, k, 3)
    d = np.linalg.norm(edges - p, axis=2)
    on_edge = edges[np.argmin(d, axis=0), np.arange(len(tri))]
    return np.where(inside[:, None], q, on_edge)


def nearest_boundary_point(mesh: TetMesh, point: np.ndarray) -> NearestPoint:
    """The point of ``mesh``'s boundary nearest ``point`` (see the module docstring).

    Parameters
    ----------
    mesh
        The mesh.
    point
        ``(3,)`` the query point.

    Returns
    -------
    NearestPoint
    """
    point = np.asarray(point, dtype=float)
    faces = mesh.tets[:, _FACES].reshape(-1, 3)
    _, inverse, counts = np.unique(
        np.sort(faces, axis=1), axis=0, return_inverse=True, return_counts=True
    )
    outer = np.flatnonzero(counts[inverse.ravel()] == 1)  # flat face index = 4 tet + face
    near = closest_on_triangles(point, mesh.points[faces[outer]])
    dist = np.linalg.norm(near - point, axis=1)
    best = int(np.argmin(dist))
    tet, face = divmod(int(outer[best]), 4)
    x = mesh.points[mesh.tets[tet]]
    lam = np.linalg.solve((x[1:] - x[0]).T, near[best] - x[0])
    bary = np.clip(np.concatenate([[1.0 - lam.sum()], lam]), 0.0, None)
    bary[face] = 0.0  # the point is on the face opposite this vertex
    bary /= bary.sum()
    edges = x[[0, 0, 0, 1, 1, 2]] - x[[1, 2, 3, 2, 3, 3]]
    size = float(np.linalg.norm(edges, axis=1).mean())
    return NearestPoint(bary @ x, float(dist[best]), tet, bary, size)
