"""The tetrahedral mesh type both models share: nodes, tets, named sets; volumes and quality.

A :class:`TetMesh` holds node coordinates, positively oriented linear tetrahedra and the
named sets found in a mesh file (node sets, cell sets, boundary facet sets) plus cell data
such as per-cell fiber vectors.

Examples
--------
>>> import numpy as np
>>> m = TetMesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]), np.array([[0, 1, 2, 3]]))
>>> m.n_points, m.n_tets, round(float(m.volumes()[0]), 12)
(4, 1, 0.166666666667)
>>> m.boundary_facets().shape
(4, 3)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class TetMesh:
    """A linear tetrahedral mesh.

    Attributes
    ----------
    points
        Node coordinates, shape ``(n, 3)``.
    tets
        Node indices, shape ``(m, 4)``, positively oriented.
    node_sets, cell_sets, facet_sets
        Named regions read from a file: node indices, tet indices and boundary
        triangles ``(k, 3)``.
    cell_data
        Per-tet arrays read from a file (e.g. ``fiber``, ``sheet``), first axis ``m``.
    notes
        What validation repaired or dropped, one sentence each.
    source
        File the mesh came from, or the generator description.
    """

    points: np.ndarray
    tets: np.ndarray
    node_sets: dict[str, np.ndarray] = field(default_factory=dict)
    cell_sets: dict[str, np.ndarray] = field(default_factory=dict)
    facet_sets: dict[str, np.ndarray] = field(default_factory=dict)
    cell_data: dict[str, np.ndarray] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    source: str = ""

    @property
    def n_points(self) -> int:
        """Number of nodes."""
        return int(self.points.shape[0])

    @property
    def n_tets(self) -> int:
        """Number of tets."""
        return int(self.tets.shape[0])

    def volumes(self, points: np.ndarray | None = None) -> np.ndarray:
        """Signed tet volumes at ``points`` (default: the rest configuration).

        Parameters
        ----------
        points
            Node positions ``(n, 3)``, e.g. deformed ones.

        Returns
        -------
        numpy.ndarray
            ``(m,)``, positive for positively oriented tets.
        """
        return tet_volumes(self.points if points is None else points, self.tets)

    def quality(self) -> np.ndarray:
        """Mean-ratio quality per tet, 1 for a regular tet, 0 for a degenerate one.

        Returns
        -------
        numpy.ndarray
            ``(m,)`` (see :func:`mean_ratio_quality`).
        """
        return mean_ratio_quality(self.points, self.tets)

    def bounding_box(self) -> tuple[np.ndarray, np.ndarray]:
        """Smallest and largest node coordinates.

        Returns
        -------
        lo, hi : numpy.ndarray
            ``(3,)`` each.
        """
        return self.points.min(axis=0), self.points.max(axis=0)

    def boundary_facets(self) -> np.ndarray:
        """Boundary triangles, ordered so their normal points outward (computed once).

        Returns
        -------
        numpy.ndarray
            ``(k, 3)`` node indices (see :func:`boundary_facets`).
        """
        if not hasattr(self, "_boundary"):
            self._boundary = boundary_facets(self.tets)
        return self._boundary

    def centers(self) -> np.ndarray:
        """Tet barycenters.

        Returns
        -------
        numpy.ndarray
            ``(m, 3)``.
        """
        return self.points[self.tets].mean(axis=1)


def tet_volumes(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Signed volumes ``det[x1-x0, x2-x0, x3-x0] / 6`` of the tets.

    Parameters
    ----------
    points
        Node positions ``(n, 3)``.
    tets
        Node indices ``(m, 4)``.

    Returns
    -------
    numpy.ndarray
        ``(m,)``.
    """
    x = points[tets]
    d = x[:, 1:] - x[:, :1]
    return np.einsum("ij,ij->i", d[:, 0], np.cross(d[:, 1], d[:, 2])) / 6.0


def displacement_gradients(points: np.ndarray, tets: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Gradient ``H = du/dX`` of the P1 interpolation of vertex displacements, per tet.

    Parameters
    ----------
    points
        Rest node positions ``(n, 3)``.
    tets
        Node indices ``(m, 4)``.
    u
        Vertex displacements ``(n, 3)``.

    Returns
    -------
    numpy.ndarray
        ``(m, 3, 3)``; ``H[k, i, j] = du_i / dX_j`` (the deformation gradient is ``I + H``).

    Examples
    --------
    >>> X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    >>> displacement_gradients(X, np.array([[0, 1, 2, 3]]), 0.1 * X[:, [1, 0, 2]])[0, 0]
    array([0. , 0.1, 0. ])
    """
    u = np.asarray(u).reshape(-1, 3)
    D0 = np.swapaxes(points[tets[:, 1:]] - points[tets[:, :1]], 1, 2)  # columns: rest edges
    Du = np.swapaxes(u[tets[:, 1:]] - u[tets[:, :1]], 1, 2)
    return Du @ np.linalg.inv(D0)


def mean_ratio_quality(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Mean-ratio quality ``12 (3|V|)^(2/3) / sum of squared edge lengths``, in [0, 1].

    Parameters
    ----------
    points
        Node positions ``(n, 3)``.
    tets
        Node indices ``(m, 4)``.

    Returns
    -------
    numpy.ndarray
        ``(m,)``: 1 for a regular tet, 0 for a flat one.
    """
    x = points[tets]
    edges = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    l2 = sum(((x[:, a] - x[:, b]) ** 2).sum(axis=1) for a, b in edges)
    vol = np.abs(tet_volumes(points, tets))
    with np.errstate(invalid="ignore", divide="ignore"):
        q = 12.0 * (3.0 * vol) ** (2.0 / 3.0) / l2
    return np.nan_to_num(q)


_FACES = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])  # outward for positive tets


def boundary_facets(tets: np.ndarray) -> np.ndarray:
    """Triangles that belong to exactly one tet, oriented outward (tets positively oriented).

    Parameters
    ----------
    tets
        Node indices ``(m, 4)``.

    Returns
    -------
    numpy.ndarray
        ``(k, 3)`` node indices; the right-hand normal of each points out of its tet.
    """
    faces = tets[:, _FACES].reshape(-1, 3)
    key = np.sort(faces, axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return faces[counts[inverse.ravel()] == 1]
