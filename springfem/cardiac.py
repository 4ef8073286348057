"""Cardiac outputs: the cavity volume enclosed by the ``endo`` surface and the base plane.

By the divergence theorem the volume enclosed by a closed, outward-oriented surface ``S`` is
``V = 1/3 int_S (x - c) . n dA`` for any point ``c``. The cavity's surface is the
endocardium closed by a cap over its rim (the boundary loop of the ``endo`` facets, on the
base plane at rest). Taking for the cap the cone from ``c`` (the centroid of the rim's
vertices) to the rim, ``x - c`` is tangent to the cap, so the cap contributes nothing and the
integral over the endocardial facets alone is the volume: exact for any planar rim with ``c``
in its plane (the cone is then the flat base-plane cap), and a cone-cap closure of a rim the
deformation has bent.

- **Flat facets** (the vertex positions only, a P1 field): the integral over a triangle is
  ``det(x1 - c, x2 - c, x3 - c) / 6``.
- **Quadratic facets** (a P2 field, or the displacement block of the mixed P2/P1 one): each
  facet is the 6-node triangle ``x(xi, eta) = sum_k N_k x_k`` through its three vertices and
  its three edge (midside) nodes, so the volume is the one the field itself encloses. The
  integrand ``(x - c) . (x_xi x x_eta)`` is a polynomial of degree 2 + 1 + 1 = 4 in the
  reference coordinates; :func:`triangle_rule` (scikit-fem's 7-point rule, exact to degree 5)
  integrates it exactly. The rest mesh's midside nodes are the edge midpoints (the gmsh
  ventricle is a linear mesh: its P2 geometry is straight-sided), so at rest both methods
  give the same volume.

Each facet is oriented by the tet it bounds (its normal away from the tet points into the
cavity), so the facets' vertex order does not matter.

Examples
--------
>>> from springfem.ellipsoid import cavity_volume as exact, ellipsoid_mesh
>>> m = ellipsoid_mesh(size=3.0)
>>> v = cavity_volume(m, m.points)
>>> bool(abs(v / exact() - 1) < 0.05), round(cavity_volume(m, 1.1 * m.points) / v, 12)
(True, 1.331)
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .errors import InputError
from .files import atomic_write_text
from .mesh import TetMesh
from .quadratic_facets import quadratic_facet_integral, straight_facet_nodes

#: The tet's faces as (its three vertices, the opposite vertex), local indices.
_FACES = ((1, 2, 3, 0), (0, 2, 3, 1), (0, 1, 3, 2), (0, 1, 2, 3))


def _keys(tris: np.ndarray, n: int) -> np.ndarray:
    """One integer per triangle, independent of its vertex order."""
    t = np.sort(np.asarray(tris, dtype=np.int64), axis=1)
    return (t[:, 0] * n + t[:, 1]) * n + t[:, 2]


def oriented_facets(mesh: TetMesh, name: str = "endo") -> tuple[np.ndarray, np.ndarray]:
    """The facets of the set ``name`` oriented away from the tet each bounds, and the rim.

    Parameters
    ----------
    mesh
        The mesh at rest.
    name
        A facet-set name.

    Returns
    -------
    tris, rim
        ``(k, 3)`` node indices (normal ``(x2 - x1) x (x3 - x1)`` out of the mesh at rest)
        and the sorted nodes of the set's boundary edges.

    Raises
    ------
    InputError
        No such facet set, or a facet that bounds no tet.
    """
    if name not in mesh.facet_sets:
        have = ", ".join(sorted(mesh.facet_sets)) or "none"
        raise InputError(f"cavity volume needs facet region {name!r} (mesh has: {have})")
    tris = np.asarray(mesh.facet_sets[name], dtype=np.int64).reshape(-1, 3)
    n = mesh.n_points
    faces = np.concatenate([mesh.tets[:, list(f[:3])] for f in _FACES])
    opposite = np.concatenate([mesh.tets[:, f[3]] for f in _FACES])
    fkeys = _keys(faces, n)
    order = np.argsort(fkeys)
    pos = np.searchsorted(fkeys[order], _keys(tris, n))
    pos = np.minimum(pos, len(order) - 1)
    hit = order[pos]
    if not np.array_equal(fkeys[hit], _keys(tris, n)):
        raise InputError(f"facet region {name!r} has facets that bound no tet")
    x = mesh.points
    a, b, c = (x[tris[:, i]] for i in range(3))
    normal = np.cross(b - a, c - a)
    inward = np.einsum("ij,ij->i", normal, x[opposite[hit]] - a) > 0
    tris = tris.copy()
    tris[inward] = tris[inward][:, [0, 2, 1]]
    edges = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
    uniq, count = np.unique(edges, axis=0, return_counts=True)
    return tris, np.unique(uniq[count == 1])


#: Method names reported beside the cavity volume.
FLAT, QUADRATIC = "flat facets (vertices)", "quadratic facets (P2 nodes, 7-point rule)"


def cavity_volume(
    mesh: TetMesh, x: np.ndarray, name: str = "endo", facet_nodes: np.ndarray | None = None
) -> float:
    """Volume enclosed by the facet set ``name`` and the cone cap over its rim.

    Parameters
    ----------
    mesh
        The mesh at rest (facet orientation and rim).
    x
        ``(n, 3)`` vertex positions, rest or deformed.
    name
        The endocardial facet set.
    facet_nodes
        ``(k, 6, 3)`` positions of the 6 nodes of each facet of ``oriented_facets(mesh,
        name)`` (a P2 field: vertices, then the midside nodes of edges (0,1), (1,2), (2,0)),
        for the quadratic facets' volume; ``None``: flat facets through the vertices.

    Returns
    -------
    float
        The enclosed volume, positive at rest (the endocardium's cavity, or the volume
        inside the epicardium).
    """
    tris, rim = oriented_facets(mesh, name)
    x = np.asarray(x, dtype=float).reshape(-1, 3)
    c = _apex(x, tris, rim)
    if facet_nodes is None:
        total = float(np.linalg.det(x[tris] - c).sum() / 6.0)
    else:
        facet_nodes = np.asarray(facet_nodes, dtype=float)
        if facet_nodes.shape != (len(tris), 6, 3):
            raise InputError(
                f"cavity volume: facet_nodes must be ({len(tris)}, 6, 3), got {facet_nodes.shape}"
            )
        total = quadratic_facet_integral(facet_nodes, c)
    # the facets' normals point out of the wall: into an endocardial cavity, out of the
    # volume an epicardium encloses; the sign at rest says which
    rest = mesh.points[tris] - _apex(mesh.points, tris, rim)
    return total if np.linalg.det(rest).sum() > 0 else -total


def _apex(x: np.ndarray, tris: np.ndarray, rim: np.ndarray) -> np.ndarray:
    """The closure's cone apex: the centroid of the rim's vertices (of all, without a rim)."""
    return x[rim].mean(axis=0) if rim.size else x[tris].reshape(-1, 3).mean(axis=0)


def is_ventricle(mesh: TetMesh) -> bool:
    """Whether the mesh has the ventricle's ``endo`` facet set (cardiac outputs apply).

    Parameters
    ----------
    mesh
        The mesh.

    Returns
    -------
    bool
    """
    return "endo" in mesh.facet_sets and "base" in mesh.facet_sets


class PressureVolume:
    """Records the cavity volume at each converged load step (a pressure–volume curve).

    Parameters
    ----------
    mesh
        The ventricle mesh at rest.
    pressure
        The endocardial pressure at load factor 1.
    to_vertices
        Maps a model's state vector to ``(n, 3)`` vertex displacements.
    to_facet_nodes
        Optional ``(state, tris) -> (k, 6, 3)``: the deformed positions of the 6 nodes of
        each facet ``tris`` (``oriented_facets``' order; vertices, then the midside nodes of
        edges (0,1), (1,2), (2,0)) of a P2 field; with it the volumes are the quadratic
        facets'.
    """

    def __init__(self, mesh: TetMesh, pressure: float, to_vertices, to_facet_nodes=None):
        self.mesh, self.pressure, self.to_vertices = mesh, float(pressure), to_vertices
        self.to_facet_nodes = to_facet_nodes
        self.tris = oriented_facets(mesh)[0]
        self.rows: list[tuple[float, float, float]] = [(0.0, 0.0, self._rest())]

    def _rest(self) -> float:
        nodes = None if self.to_facet_nodes is None else straight_facet_nodes(
            self.mesh.points, self.tris)  # fmt: skip
        return cavity_volume(self.mesh, self.mesh.points, facet_nodes=nodes)

    def volume(self, state: np.ndarray) -> float:
        """The cavity volume of a model state (quadratic facets when the model gives them)."""
        u = np.asarray(self.to_vertices(state)).reshape(-1, 3)
        nodes = None if self.to_facet_nodes is None else self.to_facet_nodes(state, self.tris)
        return cavity_volume(self.mesh, self.mesh.points + u, facet_nodes=nodes)

    def __call__(self, load: float, state: np.ndarray) -> None:
        """Record the state converged at load factor ``load``."""
        self.rows.append((float(load), float(load) * self.pressure, self.volume(state)))

    def summary(self, u: np.ndarray, state: np.ndarray | None = None) -> dict:
        """``initial``, ``final``, ``relative_change``, ``method`` and the curve's rows.

        Parameters
        ----------
        u
            ``(n, 3)`` final vertex displacement.
        state
            The final model state; with ``to_facet_nodes`` the volumes are the quadratic
            facets' (``final_flat`` is then the flat-facet volume through the vertices).

        Returns
        -------
        dict
        """
        out = cavity_summary(self.mesh, u)
        if state is not None and self.to_facet_nodes is not None:
            v0, v1 = self.rows[0][2], self.volume(state)  # rows[0]: the rest volume
            out = {"initial": v0, "final": v1, "relative_change": (v1 - v0) / v0,
                   "method": QUADRATIC, "final_flat": out["final"]}  # fmt: skip
        out["pressure_volume"] = [list(r) for r in self.rows]
        return out


def cavity_summary(mesh: TetMesh, u: np.ndarray) -> dict:
    """Cavity volume at rest and deformed by ``u`` (flat facets through the vertices).

    Parameters
    ----------
    mesh
        The ventricle mesh.
    u
        ``(n, 3)`` or flat vertex displacement.

    Returns
    -------
    dict
        ``initial``, ``final``, ``relative_change`` and ``method``.
    """
    v0 = cavity_volume(mesh, mesh.points)
    v1 = cavity_volume(mesh, mesh.points + np.asarray(u).reshape(-1, 3))
    return {"initial": v0, "final": v1, "relative_change": (v1 - v0) / v0, "method": FLAT}


def pressure_volume(scene, to_vertices, to_facet_nodes=None) -> PressureVolume | None:
    """A :class:`PressureVolume` recorder for a ventricle scene loaded on ``endo``, else None.

    Parameters
    ----------
    scene
        A :class:`~springfem.scene.Scene`.
    to_vertices
        Maps a model's state vector to vertex displacements.
    to_facet_nodes
        See :class:`PressureVolume` (a P2 model's facet nodes), or ``None``.

    Returns
    -------
    PressureVolume or None
    """
    p = endo_pressure(scene)
    return None if p is None else PressureVolume(scene.mesh, p, to_vertices, to_facet_nodes)


def endo_pressure(scene) -> float | None:
    """The total pressure of the scene's loads on the ``endo`` facets, or ``None``.

    Parameters
    ----------
    scene
        A :class:`~springfem.scene.Scene`.

    Returns
    -------
    float or None
    """
    if not is_ventricle(scene.mesh):
        return None
    ps = [
        float(ld.value[0])
        for ld in scene.loads
        if ld.type == "pressure" and ld.region is not None and ld.region.name == "endo"
    ]
    return sum(ps) if ps else None


def write_pressure_volume(stem, rows, title: str = "") -> tuple[Path, Path]:
    """Write a pressure-volume curve as ``<stem>.csv`` and ``<stem>.png`` (both atomically).

    Parameters
    ----------
    stem
        Path without the extension.
    rows
        ``(load_factor, pressure, cavity_volume)`` per converged load step.
    title
        Figure title (the scene's name).

    Returns
    -------
    tuple of pathlib.Path
        The CSV and the PNG file.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    stem = Path(stem)
    csv, png = stem.with_suffix(".csv"), stem.with_suffix(".png")
    lines = ["load_factor,pressure,cavity_volume"]
    lines += [f"{lf!r},{p!r},{v!r}" for lf, p, v in rows]
    atomic_write_text(csv, "\n".join(lines) + "\n")
    r = np.asarray(rows, dtype=float).reshape(-1, 3)
    fig, ax = plt.subplots(figsize=(4.5, 3.2))
    ax.plot(r[:, 2], r[:, 1], "o-", lw=1, ms=3)
    ax.set_xlabel("cavity volume")
    ax.set_ylabel("endocardial pressure")
    ax.set_title(title, fontsize=9)
    ax.grid(True, alpha=0.3)
    tmp = png.with_name(f".{png.stem}.{os.getpid()}.tmp.png")
    fig.savefig(tmp, dpi=110, bbox_inches="tight")
    plt.close(fig)
    os.replace(tmp, png)
    return csv, png
