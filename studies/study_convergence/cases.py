"""Cases of the convergence study: settings, levels, one solve per case, extrapolation."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from springfem.mesh import box_mesh
from springfem.scene import scene_from_dict

from ..compare import bundled_scene, solve_model

BASE = (10, 1, 1)


SIZE = (0.1, 0.01, 0.01)


MODELS = ("spring", "spring-exact", "P1", "P2")

#: The exact spring element of issue 10 (DESIGN §4b), solved at the spring levels.
EXACT = {"torsion": "energy", "volume": "axes", "calibration": "exact"}


SPRING_TORSION = "energy"


MIN_EXTRAPOLATION_ORDER = 0.8  # an extrapolation with a lower fitted order is not trusted


VERSION = 1


@dataclass(frozen=True)
class Settings:
    """Refinement levels of the convergence study (level ``k``: ``[10, 1, 1] * k``).

    Parameters
    ----------
    levels
        Levels of the spring model and P1.
    p2_levels
        Levels of P2.
    ref
        Level of the P2 reference solution.
    cosine_check_level
        Level of the extra spring case with cosine torsion.
    scene, scene_path
        A user scene table and its file (``study convergence --scene``; see
        :mod:`studies.study_convergence.scene`).
    scene_levels
        Refinement levels of the user scene (1: its own mesh).
    """

    levels: tuple[int, ...] = (1, 2, 3, 4, 6, 8)
    p2_levels: tuple[int, ...] = (1, 2, 3, 4)
    ref: int = 8
    cosine_check_level: int = 4
    scene: dict | None = None
    scene_path: str | None = None
    scene_levels: tuple[int, ...] = (1, 2, 3)

    @classmethod
    def for_scene(cls, table: dict, path: str | None = None, quick: bool = False) -> Settings:
        """Refinement of a user scene: levels 1-3 (quick: 1-2), each halving the mesh size.

        Parameters
        ----------
        table
            The scene table.
        path
            The scene file.
        quick
            Two levels instead of three (each level has 8x the tets).

        Returns
        -------
        Settings
        """
        return cls(scene=table, scene_path=path, scene_levels=(1, 2) if quick else (1, 2, 3))

    @classmethod
    def full(cls) -> Settings:
        """Levels 1-8, reference P2 at k = 8."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """Levels 1-4, reference P2 at k = 4."""
        return cls(levels=(1, 2, 3, 4), p2_levels=(1, 2, 3), ref=4)


def divisions(k: int) -> list[int]:
    return [b * k for b in BASE]


def coarse_vertices() -> np.ndarray:
    """Vertices of the level-1 mesh: contained in every level's mesh."""
    return box_mesh(SIZE, BASE, "six").points


def case(model: str, k: int, torsion: str | None = None) -> dict[str, Any]:
    """The cache case of one model at level ``k`` (the scene table decides everything).

    ``torsion`` overrides the spring model's torsion law (default :data:`SPRING_TORSION`).
    """
    data = bundled_scene("cantilever", divisions(k))
    if model == "spring":
        data.setdefault("spring", {})["torsion"] = torsion or SPRING_TORSION
    if model == "spring-exact":
        data.setdefault("spring", {}).update(EXACT)
    return {"study": "convergence", "version": VERSION, "model": model, "k": k, "table": data}


def work(c: dict[str, Any]) -> dict[str, Any]:
    """Solve one level with one model: tip displacement and the coarse-vertex field."""
    from scipy.spatial import cKDTree

    scene = scene_from_dict(c["table"])
    sol = solve_model(scene, "spring" if c["model"] == "spring-exact" else c["model"])
    dist, idx = cKDTree(scene.mesh.points).query(coarse_vertices())
    if dist.max() > 1e-9 * max(SIZE):
        raise AssertionError("coarse vertices are not vertices of the refined mesh")
    r = sol.result
    return {
        "h": SIZE[1] / c["k"],
        "tets": scene.mesh.n_tets,
        "dofs": r.counts.get("dofs", 3 * scene.mesh.n_points),
        "tip": r.probes["tip"],
        "u_coarse": sol.u[idx],
        "wall": r.wall_time,
    }


def richardson_limit(h: np.ndarray, w: np.ndarray) -> tuple[float, float]:
    """Limit ``L`` and order ``p`` of ``w(h) = L + C h^p`` through three points.

    Returns ``(nan, nan)`` when there are fewer than three points or the three values are
    not monotone (no such fit).

    Examples
    --------
    >>> h = np.array([0.4, 0.2, 0.1]); L, p = richardson_limit(h, 2.0 + 3.0 * h**1.5)
    >>> round(L, 10), round(p, 10)
    (2.0, 1.5)
    """
    from scipy.optimize import brentq

    if len(h) < 3 or len(w) < 3:
        return float("nan"), float("nan")
    h1, h2, h3 = (float(x) for x in h)
    w1, w2, w3 = (float(x) for x in w)
    if (w1 - w2) * (w2 - w3) <= 0:
        return float("nan"), float("nan")
    ratio = (w1 - w2) / (w2 - w3)

    def g(p: float) -> float:
        return (h1**p - h2**p) / (h2**p - h3**p) - ratio

    try:
        p = brentq(g, 0.05, 12.0)
    except ValueError:
        return float("nan"), float("nan")
    L = w3 - (w2 - w3) * h3**p / (h2**p - h3**p)
    return float(L), float(p)
