"""Cardiac outputs: the cavity volume enclosed by the ``endo`` surface and the base plane.

By the divergence theorem the volume enclosed by a closed triangulated surface is
``V = sum_T det(x1 - c, x2 - c, x3 - c) / 6`` for any point ``c``, with the triangles
oriented outwards. The cavity's surface is the endocardium closed by a cap over its rim
(the boundary loop of the ``endo`` facets, on the base plane at rest). Taking ``c`` at the
centroid of the rim's vertices, the cap (a fan of triangles from ``c`` to the rim's edges)
contributes nothing, so the sum over the endocardial facets alone is the volume closed by
that fan cap: exact for any planar rim, and a flat-cap closure of a rim the deformation has
bent. Each facet is oriented by the tet it bounds (its normal away from the tet points into
the cavity), so the facets' vertex order does not matter.

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


def cavity_volume(mesh: TetMesh, x: np.ndarray, name: str = "endo") -> float:
    """Volume enclosed by the facet set ``name`` and the flat cap over its rim.

    Parameters
    ----------
    mesh
        The mesh at rest (facet orientation and rim).
    x
        ``(n, 3)`` node positions, rest or deformed.
    name
        The endocardial facet set.

    Returns
    -------
    float
        The enclosed volume, positive at rest (the endocardium's cavity, or the volume
        inside the epicardium).
    """
    tris, rim = oriented_facets(mesh, name)
    x = np.asarray(x, dtype=float).reshape(-1, 3)
    total = _signed_volume(x, tris, rim)
    # the facets' normals point out of the wall: into an endocardial cavity, out of the
    # volume an epicardium encloses; the sign at rest says which
    return total if _signed_volume(mesh.points, tris, rim) > 0 else -total


def _signed_volume(x: np.ndarray, tris: np.ndarray, rim: np.ndarray) -> float:
    """``sum det(x1 - c, x2 - c, x3 - c) / 6`` with ``c`` the rim's centroid."""
    c = x[rim].mean(axis=0) if rim.size else x[tris].reshape(-1, 3).mean(axis=0)
    return float(np.linalg.det(x[tris] - c).sum() / 6.0)


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
    """

    def __init__(self, mesh: TetMesh, pressure: float, to_vertices):
        self.mesh, self.pressure, self.to_vertices = mesh, float(pressure), to_vertices
        self.rows: list[tuple[float, float, float]] = [(0.0, 0.0, cavity_volume(mesh, mesh.points))]

    def __call__(self, load: float, state: np.ndarray) -> None:
        """Record the state converged at load factor ``load``."""
        u = np.asarray(self.to_vertices(state)).reshape(-1, 3)
        v = cavity_volume(self.mesh, self.mesh.points + u)
        self.rows.append((float(load), float(load) * self.pressure, v))

    def summary(self, u: np.ndarray) -> dict:
        """``initial``, ``final``, ``relative_change`` and the curve's rows.

        Parameters
        ----------
        u
            ``(n, 3)`` final vertex displacement.

        Returns
        -------
        dict
        """
        out = cavity_summary(self.mesh, u)
        out["pressure_volume"] = [list(r) for r in self.rows]
        return out


def cavity_summary(mesh: TetMesh, u: np.ndarray) -> dict:
    """Cavity volume at rest and deformed by ``u``.

    Parameters
    ----------
    mesh
        The ventricle mesh.
    u
        ``(n, 3)`` or flat vertex displacement.

    Returns
    -------
    dict
        ``initial``, ``final`` and ``relative_change``.
    """
    v0 = cavity_volume(mesh, mesh.points)
    v1 = cavity_volume(mesh, mesh.points + np.asarray(u).reshape(-1, 3))
    return {"initial": v0, "final": v1, "relative_change": (v1 - v0) / v0}


def pressure_volume(scene, to_vertices) -> PressureVolume | None:
    """A :class:`PressureVolume` recorder for a ventricle scene loaded on ``endo``, else None.

    Parameters
    ----------
    scene
        A :class:`~springfem.scene.Scene`.
    to_vertices
        Maps a model's state vector to vertex displacements.

    Returns
    -------
    PressureVolume or None
    """
    p = endo_pressure(scene)
    return None if p is None else PressureVolume(scene.mesh, p, to_vertices)


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
