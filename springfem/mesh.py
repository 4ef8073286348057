"""Tetrahedral meshes: generation, validation, quality, meshio input/output.

A :class:`TetMesh` holds node coordinates, positively oriented linear tetrahedra and the
named sets found in a mesh file (node sets, cell sets, boundary facet sets) plus cell data
such as per-cell fiber vectors. Both models use the same :class:`TetMesh`.

Examples
--------
>>> m = box_mesh((1.0, 1.0, 1.0), (2, 2, 2), split="six")
>>> m.n_points, m.n_tets
(27, 48)
>>> round(float(m.volumes().sum()), 12)
1.0
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Literal, get_args

import numpy as np

from .errors import MeshError

Split = Literal["five", "six", "five-mirrored", "six-mirrored"]

# Hexahedron corners, local index -> (i, j, k) offsets.
_HEX_CORNERS = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]
)
# Six tets around the main diagonal 0-6 (Kuhn/Freudenthal split): conforming when every
# hexahedron is split the same way.
_SIX = np.array(
    [[0, 1, 2, 6], [0, 2, 3, 6], [0, 3, 7, 6], [0, 7, 4, 6], [0, 4, 5, 6], [0, 5, 1, 6]]
)
# Five tets: four corner tets and the central tet on the even corners 0, 2, 5, 7. Face
# diagonals alternate between opposite faces, so neighbours must use the mirrored split.
_FIVE_EVEN = np.array([[1, 0, 2, 5], [3, 2, 0, 7], [4, 5, 7, 0], [6, 7, 5, 2], [0, 2, 5, 7]])
_FIVE_ODD = np.array([[0, 1, 3, 4], [2, 3, 1, 6], [5, 4, 6, 1], [7, 6, 4, 3], [1, 3, 4, 6]])


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
        return int(self.points.shape[0])

    @property
    def n_tets(self) -> int:
        return int(self.tets.shape[0])

    def volumes(self, points: np.ndarray | None = None) -> np.ndarray:
        """Signed tet volumes at ``points`` (default: the rest configuration)."""
        return tet_volumes(self.points if points is None else points, self.tets)

    def quality(self) -> np.ndarray:
        """Mean-ratio quality per tet, 1 for a regular tet, 0 for a degenerate one."""
        return mean_ratio_quality(self.points, self.tets)

    def bounding_box(self) -> tuple[np.ndarray, np.ndarray]:
        return self.points.min(axis=0), self.points.max(axis=0)

    def boundary_facets(self) -> np.ndarray:
        """Boundary triangles ``(k, 3)``, ordered so their normal points outward."""
        if not hasattr(self, "_boundary"):
            self._boundary = boundary_facets(self.tets)
        return self._boundary

    def centers(self) -> np.ndarray:
        """Tet barycenters ``(m, 3)``."""
        return self.points[self.tets].mean(axis=1)


def tet_volumes(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Signed volumes ``det[x1-x0, x2-x0, x3-x0] / 6`` of the tets."""
    x = points[tets]
    d = x[:, 1:] - x[:, :1]
    return np.einsum("ij,ij->i", d[:, 0], np.cross(d[:, 1], d[:, 2])) / 6.0


def mean_ratio_quality(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Mean-ratio quality ``12 (3|V|)^(2/3) / sum of squared edge lengths``, in [0, 1]."""
    x = points[tets]
    edges = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    l2 = sum(((x[:, a] - x[:, b]) ** 2).sum(axis=1) for a, b in edges)
    vol = np.abs(tet_volumes(points, tets))
    with np.errstate(invalid="ignore", divide="ignore"):
        q = 12.0 * (3.0 * vol) ** (2.0 / 3.0) / l2
    return np.nan_to_num(q)


def _greedy_element_colouring(tets, node_ptr, node_elems):  # pragma: no cover - compiled
    """Smallest colour not used by an already coloured element sharing a node."""
    m = tets.shape[0]
    colour = np.full(m, -1, dtype=np.int64)
    mark = np.full(m + 1, -1, dtype=np.int64)  # mark[c] == k: colour c is taken near k
    for k in range(m):
        for a in range(4):
            node = tets[k, a]
            for p in range(node_ptr[node], node_ptr[node + 1]):
                c = colour[node_elems[p]]
                if c >= 0:
                    mark[c] = k
        c = 0
        while mark[c] == k:
            c += 1
        colour[k] = c
    return colour


_compiled_colouring = None


def element_colouring(tets: np.ndarray, n_points: int) -> np.ndarray:
    """Greedy element colouring: elements of one colour share no node.

    The race-free parallel scatter of both fused kernels (spring model and explicit FEM)
    runs the elements of one colour concurrently. Compiled with numba on first use.

    Examples
    --------
    >>> element_colouring(np.array([[0, 1, 2, 3], [1, 2, 3, 4], [5, 6, 7, 8]]), 9).tolist()
    [0, 1, 0]
    """
    global _compiled_colouring
    if _compiled_colouring is None:
        from numba import njit

        _compiled_colouring = njit(cache=True)(_greedy_element_colouring)
    tets = np.ascontiguousarray(tets, dtype=np.int64)
    if tets.size == 0:
        return np.zeros(0, dtype=np.int64)
    flat = tets.ravel()
    node_elems = (np.argsort(flat, kind="stable") // 4).astype(np.int64)
    node_ptr = np.zeros(n_points + 1, dtype=np.int64)
    np.cumsum(np.bincount(flat, minlength=n_points), out=node_ptr[1:])
    return _compiled_colouring(tets, node_ptr, node_elems)


_FACES = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])  # outward for positive tets


def boundary_facets(tets: np.ndarray) -> np.ndarray:
    """Triangles that belong to exactly one tet, oriented outward (tets positively oriented)."""
    faces = tets[:, _FACES].reshape(-1, 3)
    key = np.sort(faces, axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return faces[counts[inverse.ravel()] == 1]


def box_mesh(
    size: tuple[float, float, float],
    divisions: tuple[int, int, int],
    split: Split = "six",
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> TetMesh:
    """Structured box mesh, each hexahedron split into five or six tets.

    Parameters
    ----------
    size
        Box edge lengths.
    divisions
        Number of hexahedra along x, y, z.
    split
        ``six``: six tets around the main diagonal of every hexahedron (all alike).
        ``six-mirrored``: the same split mirrored across every other hexahedron along each
        axis, so each 2x2x2 block is symmetric. ``five``: five tets per hexahedron; a
        conforming five-tet mesh must alternate the two mirror-image splits, so ``five``
        starts with the even split at the origin and ``five-mirrored`` with the odd one
        (the mirror image of ``five``).
    origin
        Coordinates of the box corner with the smallest coordinates.

    Returns
    -------
    TetMesh
        With node sets ``x_min`` … ``z_max`` left to :mod:`springfem.regions`.
    """
    if split not in get_args(Split):
        raise MeshError(f"mesh split {split!r} is not one of {', '.join(get_args(Split))}")
    nx, ny, nz = (int(d) for d in divisions)
    if min(nx, ny, nz) < 1:
        raise MeshError(f"mesh divisions must be positive integers, got {list(divisions)}")
    if min(size) <= 0 or not np.all(np.isfinite(size)):
        raise MeshError(f"mesh size must be positive and finite, got {list(size)}")
    axes = [np.linspace(o, o + s, n + 1) for o, s, n in zip(origin, size, (nx, ny, nz))]
    _check_box_axes(axes, size, origin, (nx, ny, nz))
    X, Y, Z = np.meshgrid(*axes, indexing="ij")
    points = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])

    def node(i, j, k):
        return (i * (ny + 1) + j) * (nz + 1) + k

    I, J, K = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    I, J, K = I.ravel(), J.ravel(), K.ravel()
    if split.startswith("six"):
        if split == "six-mirrored":
            # mirror the corner offsets of odd hexahedra along each axis
            off = np.stack(
                [
                    np.where(
                        (I % 2)[:, None] == 1, 1 - _HEX_CORNERS[None, :, 0], _HEX_CORNERS[:, 0]
                    ),
                    np.where(
                        (J % 2)[:, None] == 1, 1 - _HEX_CORNERS[None, :, 1], _HEX_CORNERS[:, 1]
                    ),
                    np.where(
                        (K % 2)[:, None] == 1, 1 - _HEX_CORNERS[None, :, 2], _HEX_CORNERS[:, 2]
                    ),
                ],
                axis=-1,
            )
        else:
            off = np.broadcast_to(_HEX_CORNERS, (I.size, 8, 3))
        corners = node(I[:, None] + off[..., 0], J[:, None] + off[..., 1], K[:, None] + off[..., 2])
        tets = np.take_along_axis(
            corners[:, None, :].repeat(6, axis=1), _SIX[None].repeat(I.size, axis=0), axis=2
        ).reshape(-1, 4)
    else:
        corners = node(
            I[:, None] + _HEX_CORNERS[:, 0],
            J[:, None] + _HEX_CORNERS[:, 1],
            K[:, None] + _HEX_CORNERS[:, 2],
        )
        parity = (I + J + K + (1 if split == "five-mirrored" else 0)) % 2
        local = np.where(parity[:, None, None] == 0, _FIVE_EVEN[None], _FIVE_ODD[None])
        tets = np.take_along_axis(corners[:, None, :].repeat(5, axis=1), local, axis=2).reshape(
            -1, 4
        )
    tets = tets.astype(np.int64)
    vol = tet_volumes(points, tets)
    flip = vol < 0
    tets[flip] = tets[flip][:, [0, 2, 1, 3]]
    desc = f"box {list(size)} divisions {[nx, ny, nz]} split {split}"
    return TetMesh(points=points, tets=tets, source=desc)


#: Largest coordinate magnitude (m): squared lengths and volumes stay finite in float64.
MAX_COORDINATE = 1e100
#: Mean-ratio quality below which a tet is reported as a sliver (a note, not an error).
SLIVER_QUALITY = 1e-2


def _check_box_axes(axes: list[np.ndarray], size, origin, divisions) -> None:
    """Refuse box parameters whose nodes float64 can't hold apart or whose tets it can't measure.

    The same criteria as :func:`validate_mesh` (finite coordinates within
    :data:`MAX_COORDINATE`, no zero-volume tet), checked on the grid lines before the mesh
    is built.
    """
    desc = f"size {list(map(float, size))}, origin {list(map(float, origin))}"
    for a, name in zip(axes, "xyz"):
        if not np.isfinite(a).all() or np.abs(a).max() > MAX_COORDINATE:
            raise MeshError(
                f"mesh {desc}: {name} coordinates beyond ±{MAX_COORDINATE:g}; use other units"
            )
        if not (np.diff(a) > 0).all():
            raise MeshError(
                f"mesh {desc}, divisions {list(divisions)}: grid lines along {name} coincide in "
                "float64 (cells too small for the coordinates); move the origin or coarsen"
            )
    h_min = np.array([np.diff(a).min() for a in axes])
    h_max = np.array([np.diff(a).max() for a in axes])
    v_min = float(np.prod(h_min)) / 6.0  # the smallest tet of a five or six split
    if not (v_min >= np.finfo(float).tiny and v_min > 1e-12 * float(np.sum(h_max**2)) ** 1.5):
        raise MeshError(
            f"mesh {desc}, divisions {list(divisions)}: zero-volume tets (cells of "
            f"{h_min.tolist()} m can't be measured in float64); use other units"
        )


def validate_mesh(mesh: TetMesh, name: str = "mesh", rel_volume_tol: float = 1e-12) -> TetMesh:
    """Check and repair a mesh in place; raise :class:`MeshError` for what can't be repaired.

    Rejected: non-finite coordinates or coordinates beyond :data:`MAX_COORDINATE`, no tets,
    node indices out of range, zero-volume tets (``|V| <= rel_volume_tol l^3`` with ``l``
    the tet's longest edge), duplicate tets, coincident nodes used by tets, non-manifold
    facets (a triangle shared by three or more tets) and folds (two tets on the same side of
    their shared triangle): both mean overlapping tets.

    Repaired or reported (in ``mesh.notes``): inverted tets are reoriented, unreferenced
    nodes are removed; sliver tets (mean-ratio quality below :data:`SLIVER_QUALITY`),
    disconnected parts and non-manifold nodes (parts touching only at a node or an edge)
    are noted. Those three are legal meshes both models can solve, but each part needs its
    own boundary conditions, and slivers lower the stable explicit time step.
    """
    pts, tets = mesh.points, mesh.tets
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise MeshError(f"{name}: points must have shape (n, 3), got {pts.shape}")
    bad = np.flatnonzero(~np.isfinite(pts).all(axis=1))
    if bad.size:
        raise MeshError(f"{name}: non-finite coordinates at nodes {_ids(bad)}")
    bad = np.flatnonzero((np.abs(pts) > MAX_COORDINATE).any(axis=1))
    if bad.size:
        raise MeshError(
            f"{name}: coordinates beyond ±{MAX_COORDINATE:g} at nodes {_ids(bad)}; "
            "use other units (mesh.scale)"
        )
    if tets.ndim != 2 or tets.shape[1] != 4 or tets.shape[0] == 0:
        raise MeshError(f"{name}: contains no tetrahedra")
    if tets.min() < 0 or tets.max() >= len(pts):
        bad = np.flatnonzero((tets < 0).any(axis=1) | (tets >= len(pts)).any(axis=1))
        raise MeshError(f"{name}: tets {_ids(bad)} reference nodes that do not exist")
    repeated = np.flatnonzero(
        (np.sort(tets, axis=1)[:, 1:] == np.sort(tets, axis=1)[:, :-1]).any(1)
    )
    if repeated.size:
        raise MeshError(f"{name}: zero-volume tets {_ids(repeated)} (a node repeated)")
    key = np.sort(tets, axis=1)
    _, first, inverse, counts = np.unique(
        key, axis=0, return_index=True, return_inverse=True, return_counts=True
    )
    dup = np.flatnonzero(counts[inverse.ravel()] > 1)
    if dup.size:
        raise MeshError(f"{name}: duplicate tets {_ids(dup)} (same four nodes)")
    vol = tet_volumes(pts, tets)
    zero = np.flatnonzero(np.abs(vol) <= rel_volume_tol * _longest_edges(pts, tets) ** 3)
    if zero.size:
        raise MeshError(f"{name}: zero-volume tets {_ids(zero)}")
    used = np.zeros(len(pts), dtype=bool)
    used[tets.ravel()] = True
    upts = np.flatnonzero(used)
    rounded = np.round(pts[upts] / (np.ptp(pts, axis=0).max() * 1e-12 + 1e-300))
    _, uidx, uinv, ucnt = np.unique(
        rounded, axis=0, return_index=True, return_inverse=True, return_counts=True
    )
    if (ucnt > 1).any():
        grp = np.flatnonzero(ucnt[uinv.ravel()] > 1)
        raise MeshError(
            f"{name}: duplicate nodes {_ids(upts[grp])} (coincident coordinates; merge them)"
        )
    inverted = vol < 0
    if inverted.any():
        tets = tets.copy()
        tets[inverted] = tets[inverted][:, [0, 2, 1, 3]]
        mesh.notes.append(f"{name}: reoriented {int(inverted.sum())} inverted tets")
    mesh.notes.extend(_topology_notes(tets, name))
    q = mean_ratio_quality(pts, tets)
    slivers = np.flatnonzero(q < SLIVER_QUALITY)
    if slivers.size:
        worst = slivers[np.argsort(q[slivers], kind="stable")]
        mesh.notes.append(
            f"{name}: {slivers.size} sliver tet{'s' if slivers.size > 1 else ''} (mean-ratio "
            f"quality below {SLIVER_QUALITY:g}, "
            f"worst {q[worst[0]]:.2g}): {_ids(worst)}"
        )
    if not used.all():
        n_unused = int((~used).sum())
        remap = -np.ones(len(pts), dtype=np.int64)
        remap[used] = np.arange(used.sum())
        pts = pts[used]
        tets = remap[tets]
        mesh.node_sets = {k: remap[v][remap[v] >= 0] for k, v in mesh.node_sets.items()}
        mesh.facet_sets = {
            k: remap[v][(remap[v] >= 0).all(axis=1)] for k, v in mesh.facet_sets.items()
        }
        mesh.notes.append(f"{name}: removed {n_unused} nodes not used by any tet")
    mesh.points = np.ascontiguousarray(pts, dtype=np.float64)
    mesh.tets = np.ascontiguousarray(tets, dtype=np.int64)
    if hasattr(mesh, "_boundary"):
        del mesh._boundary
    return mesh


def _longest_edges(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Longest edge length of each tet."""
    x = points[tets]
    l2 = [((x[:, a] - x[:, b]) ** 2).sum(axis=1) for a, b in _EDGES]
    return np.sqrt(np.max(l2, axis=0))


_EDGES = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))


def _row_keys(rows: np.ndarray) -> np.ndarray:
    """One sortable key per row of small non-negative ints (fast ``np.unique``)."""
    n = int(rows.max(initial=0)) + 1
    if n ** rows.shape[1] < 2**63:
        key = np.zeros(len(rows), dtype=np.int64)
        for c in range(rows.shape[1]):
            key = key * n + rows[:, c]
        return key
    return np.unique(rows, axis=0, return_inverse=True)[1].ravel()


def _topology_notes(tets: np.ndarray, name: str) -> list[str]:
    """Face-sharing topology: raise for non-manifold facets, note parts and bad nodes.

    * A triangle shared by three or more tets, or by two tets on the same side of it,
      means overlapping tets: :class:`MeshError` naming the triangle and the tets.
    * Parts: tets connected through shared triangles. More than one is legal (several
      bodies), so it is a note naming the parts' sizes and a tet of each.
    * Non-manifold nodes: at a node, the tets around it fall into more than one group
      connected through triangles at that node (parts touching at a node or an edge, a
      "bow tie"). Legal, but such a hinge is rarely meant: a note naming the nodes.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    m = len(tets)
    local = _FACES  # (4, 3) local node indices of the faces
    faces = tets[:, local].reshape(-1, 3)  # face f of tet t at row 4 t + f
    order = np.argsort(faces, axis=1, kind="stable")
    key = np.take_along_axis(faces, order, axis=1)
    _, inverse, counts = np.unique(_row_keys(key), return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    shared = counts[inverse]
    if (shared > 2).any():
        rows = np.flatnonzero(shared > 2)
        first = key[rows[0]]
        n_bad = int((counts > 2).sum())
        raise MeshError(
            f"{name}: non-manifold facets: triangle {first.tolist()} is shared by "
            f"{int(shared[rows[0]])} tets ({_ids(rows[inverse[rows] == inverse[rows[0]]] // 4)})"
            f"; {n_bad} non-manifold triangle{'s' if n_bad > 1 else ''} in all (overlapping tets)"
        )
    rows = np.flatnonzero(shared == 2)
    rows = rows[np.argsort(inverse[rows], kind="stable")]
    a, b = rows[0::2], rows[1::2]  # the two sides of each interior triangle
    # outward faces of two neighbours run in opposite directions: the permutations that
    # sort them have opposite parity; equal parity means both tets lie on the same side
    even = (order[:, 1] - order[:, 0]) % 3 == 1
    folded = np.flatnonzero(even[a] == even[b])
    if folded.size:
        f = folded[0]
        raise MeshError(
            f"{name}: folded mesh: tets {a[f] // 4} and {b[f] // 4} lie on the same side of "
            f"their shared triangle {key[a[f]].tolist()}; {folded.size} such "
            f"triangle{'s' if folded.size > 1 else ''} in all (overlapping tets)"
        )
    notes = []
    graph = coo_matrix((np.ones(a.size), (a // 4, b // 4)), shape=(m, m))
    n_parts, part = connected_components(graph, directed=False)
    if n_parts > 1:
        sizes = np.bincount(part)
        firsts = [int(np.flatnonzero(part == k)[0]) for k in range(min(n_parts, 8))]
        notes.append(
            f"{name}: {n_parts} disconnected parts (no shared triangle between them) of "
            f"{_ids(sizes)} tets, containing tets {_ids(np.array(firsts))}; each part needs "
            "its own boundary conditions"
        )
    # corners of a tet: item 4 t + j is node tets[t, j]; an interior triangle joins, at each
    # of its three nodes, the corner items of its two tets
    ia = (a // 4)[:, None] * 4 + local[a % 4][np.arange(a.size)[:, None], order[a]]
    ib = (b // 4)[:, None] * 4 + local[b % 4][np.arange(b.size)[:, None], order[b]]
    corners = coo_matrix((np.ones(ia.size), (ia.ravel(), ib.ravel())), shape=(4 * m, 4 * m))
    _, group = connected_components(corners, directed=False)
    node = tets.ravel()
    pairs = np.unique(node * np.int64(4 * m) + group)  # distinct (node, group) pairs
    n_groups = np.bincount(pairs // (4 * m))
    bad = np.flatnonzero(n_groups > 1)
    if bad.size:
        notes.append(
            f"{name}: {bad.size} non-manifold node{'s' if bad.size > 1 else ''} (parts touch "
            f"only at a node or an edge there): {_ids(bad)}"
        )
    return notes


def _ids(idx: np.ndarray, limit: int = 8) -> str:
    idx = np.asarray(idx).ravel()
    shown = ", ".join(str(int(i)) for i in idx[:limit])
    return shown + (f" … ({idx.size} in all)" if idx.size > limit else "")


_TET_TYPES = {"tetra": 4, "tetra10": 10}
_TRI_TYPES = {"triangle": 3, "triangle6": 6}


def read_mesh(path: str | os.PathLike, scale: float = 1.0) -> TetMesh:
    """Read a tetrahedral mesh with meshio, scale its coordinates and validate it.

    Tets (``tetra``, or ``tetra10`` reduced to its corners) are kept; lower-dimensional
    cells (vertices, lines, triangles, quads) are dropped with a note, except triangles,
    which become named boundary facet sets when a gmsh physical group or cell set names
    them. Other volume cells (hexahedra, wedges, pyramids …) are dropped too, and the note
    says so and that the body lost that part (split them into tets in the meshing tool to
    keep it). Node sets (``point_sets``) and tet cell sets
    become named regions; per-tet cell data (e.g. ``fiber``) is kept.

    Raises
    ------
    MeshError
        If the file can't be read or holds no usable tets.
    """
    import meshio

    path = os.fspath(path)
    if not os.path.isfile(path):
        raise MeshError(f"mesh file {path} does not exist")
    import contextlib
    import io

    chatter = io.StringIO()
    try:
        # meshio prints to stderr and may call sys.exit on unreadable files
        with contextlib.redirect_stderr(chatter), contextlib.redirect_stdout(chatter):
            m = meshio.read(path)
    except (Exception, SystemExit) as exc:  # meshio raises many types; report one line
        text = str(exc).strip() if not isinstance(exc, SystemExit) else chatter.getvalue()
        text = " ".join(text.split()) or type(exc).__name__
        text = text if len(text) <= 200 else text[:199] + "…"
        raise MeshError(f"mesh file {path} could not be read: {text}") from None
    return mesh_from_meshio(m, path, scale=scale)


#: meshio cell types that fill a volume (besides tets): dropped with a warning note.
_VOLUME_TYPES = ("hexahedron", "wedge", "pyramid", "hexahedron20", "hexahedron27", "wedge15")
_VOLUME_TYPES += ("pyramid13", "pyramid14", "wedge18", "hexahedron24", "polyhedron", "VTK_LAGRANGE")


def mesh_from_meshio(m, name: str = "mesh", scale: float = 1.0) -> TetMesh:
    """Build a validated :class:`TetMesh` from a ``meshio.Mesh`` (see :func:`read_mesh`)."""
    try:
        pts = np.asarray(m.points, dtype=np.float64) * scale
    except (TypeError, ValueError) as exc:
        raise MeshError(f"{name}: node coordinates are not numbers ({exc})") from None
    if pts.ndim != 2 or pts.shape[0] == 0:
        raise MeshError(f"{name}: contains no nodes")
    if pts.shape[1] == 2:
        raise MeshError(f"{name}: is two-dimensional; a tetrahedral mesh is needed")
    pts = pts[:, :3]
    tet_blocks, tri_blocks, dropped = [], [], {}
    volume = {}
    for block in m.cells:
        if block.type.startswith(_VOLUME_TYPES):
            volume[block.type] = volume.get(block.type, 0) + len(block.data)
    for b, block in enumerate(m.cells):
        if block.type in _TET_TYPES:
            tet_blocks.append((b, np.asarray(block.data)[:, :4]))
            if block.type == "tetra10":
                dropped["tetra10 mid-edge nodes"] = dropped.get("tetra10 mid-edge nodes", 0) + 1
        elif block.type in _TRI_TYPES:
            tri_blocks.append((b, np.asarray(block.data)[:, :3]))
        else:
            dropped[block.type] = dropped.get(block.type, 0) + len(block.data)
    if not tet_blocks:
        kinds = ", ".join(sorted({c.type for c in m.cells})) or "none"
        raise MeshError(f"{name}: contains no tetrahedra (cell types: {kinds})")
    tets = np.concatenate([t for _, t in tet_blocks]).astype(np.int64)
    offsets = np.cumsum([0] + [len(t) for _, t in tet_blocks])
    block_offset = {b: int(o) for (b, _), o in zip(tet_blocks, offsets)}
    cell_sets: dict[str, np.ndarray] = {}
    facet_sets: dict[str, np.ndarray] = {}
    for set_name, per_block in getattr(m, "cell_sets", {}).items():
        tet_ids, tris = [], []
        for b, ids in enumerate(per_block):
            if ids is None or len(ids) == 0:
                continue
            ids = np.asarray(ids, dtype=np.int64)
            if b in block_offset:
                tet_ids.append(ids + block_offset[b])
            else:
                for bb, data in tri_blocks:
                    if bb == b:
                        tris.append(data[ids])
        if tet_ids:
            cell_sets[set_name] = np.concatenate(tet_ids)
        if tris:
            facet_sets[set_name] = np.concatenate(tris).astype(np.int64)
    # gmsh physical tags without names: expose as "tag:<n>"
    phys = m.cell_data.get("gmsh:physical")
    if phys is not None:
        names_by_tag = {}
        for nm, (tag, _dim) in getattr(m, "field_data", {}).items():
            names_by_tag[int(tag)] = nm
        for b, tags in enumerate(phys):
            tags = np.asarray(tags).astype(np.int64)
            for tag in np.unique(tags):
                nm = names_by_tag.get(int(tag), f"tag:{int(tag)}")
                ids = np.flatnonzero(tags == tag)
                if b in block_offset:
                    cell_sets.setdefault(nm, ids + block_offset[b])
                else:
                    for bb, data in tri_blocks:
                        if bb == b:
                            facet_sets.setdefault(nm, data[ids].astype(np.int64))
    cell_data: dict[str, np.ndarray] = {}
    for key, per_block in m.cell_data.items():
        if key.startswith("gmsh:") or key.startswith("medit:"):
            continue
        arrays = [np.asarray(per_block[b]) for b, _ in tet_blocks]
        try:
            cell_data[key] = np.concatenate(arrays).astype(np.float64)
        except (ValueError, TypeError):
            continue
    node_sets = {k: np.asarray(v, dtype=np.int64) for k, v in getattr(m, "point_sets", {}).items()}
    mesh = TetMesh(
        points=pts,
        tets=tets,
        node_sets=node_sets,
        cell_sets=cell_sets,
        facet_sets=facet_sets,
        cell_data=cell_data,
        source=name,
    )
    if dropped:
        what = ", ".join(f"{n} {k}" for k, n in sorted(dropped.items()))
        warn = (
            "; the dropped volume cells are missing from the body (split them into tets in "
            "the meshing tool to keep them)"
            if volume
            else ""
        )
        mesh.notes.append(f"{name}: kept {len(tets)} tets, dropped {what}{warn}")
    return validate_mesh(mesh, name)


def write_vtu(
    path: str | os.PathLike,
    mesh: TetMesh,
    point_data: dict[str, np.ndarray] | None = None,
    cell_data: dict[str, np.ndarray] | None = None,
) -> None:
    """Write the mesh with point and cell data as VTU, atomically (temp file + rename)."""
    import meshio

    path = os.fspath(path)
    out = meshio.Mesh(
        mesh.points,
        [("tetra", mesh.tets)],
        point_data={k: np.asarray(v) for k, v in (point_data or {}).items()},
        cell_data={k: [np.asarray(v)] for k, v in (cell_data or {}).items()},
    )
    tmp = f"{path}.tmp-{os.getpid()}.vtu"
    meshio.write(tmp, out, file_format="vtu")
    os.replace(tmp, path)
