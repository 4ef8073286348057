"""Refinement levels of a scene: level ``r`` is the scene's own mesh refined by the factor ``r``.

A generated box whose grid points are all its vertices (split ``six``, ``five`` and their
mirrored forms) takes any integer factor: its divisions times ``r``. Any other mesh (a mesh
file, an ellipsoid, a jittered Delaunay box) is refined uniformly, each tet into 8
(:func:`springfem.mesh.refine_uniform`), so it takes powers of two only (``r = 2^n``: ``n``
refinements). Either way level ``r`` has ``r³`` times the tets of level 1 and contains the
level-1 vertices, where the studies compare fields across levels; its mesh size is
``h = h₁ / r``, with ``h₁`` the mean edge length of the scene's own mesh (for a box split
the same way on every level, ``h`` is proportional to the grid spacing).

Examples
--------
>>> from studies.scenes import bundled_table
>>> bar = bundled_table("cantilever", {"mesh.divisions": [10, 1, 1]})
>>> level_label(bar, 3), refined_scene(bar, None, 2).mesh.n_tets
('30x3x3', 480)
>>> level_label({"mesh": {"file": "heart.msh"}}, 4)
'x4'
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from springfem.mesh import TetMesh, refine_uniform
from springfem.scene import Scene, scene_from_dict

from ..overrides import scene_with_overrides

#: Box splits whose vertices are exactly the grid points (nested under any integer factor).
GRID_SPLITS = ("six", "five", "six-mirrored", "five-mirrored")


def grid_box(table: Mapping) -> bool:
    """Whether the scene's mesh is a box grid, refined by multiplying its divisions."""
    mesh = table.get("mesh", {})
    return (
        isinstance(mesh, Mapping)
        and mesh.get("generator") == "box"
        and mesh.get("split", "six") in GRID_SPLITS
    )


def _doublings(factor: int) -> int | None:
    """``n`` with ``2^n = factor``, or ``None``."""
    n = int(factor).bit_length() - 1
    return n if factor >= 1 and 2**n == factor else None


def level_label(table: Mapping, factor: int) -> str:
    """A level's name in tables and headline keys: a box's divisions (``20x2x2``), else
    ``x<factor>``.
    """
    if grid_box(table):
        return "x".join(str(int(d) * factor) for d in table["mesh"]["divisions"])
    return f"x{factor}"


def refined_scene(table: Mapping, path: str | None, factor: int) -> Scene:
    """The scene of ``table`` (``path`` anchors a relative mesh path) with its mesh refined by
    ``factor`` (any for a box grid, else a power of two: a :class:`ValueError` otherwise).
    """
    if grid_box(table):
        divisions = [int(d) * factor for d in table["mesh"]["divisions"]]
        return scene_with_overrides(table, [("mesh.divisions", divisions)], path)
    n = _doublings(factor)
    if n is None:
        raise ValueError(f"a mesh that is not a box grid refines by powers of two, not {factor}")
    scene = scene_with_overrides(table, (), path)
    mesh: TetMesh = scene.mesh
    for _ in range(n):
        mesh = refine_uniform(mesh)
    return scene_from_dict({**table, "mesh": mesh}, path=path) if n else scene


def case_level(case: Mapping) -> Scene:
    """The refined scene of a :meth:`~studies.scenes.StudyScene.case` with a ``factor``."""
    return refined_scene(case["table"], case.get("path"), int(case["factor"]))


def mean_edge(mesh: TetMesh) -> float:
    """Mean length of the tets' six edges (each edge counted once per tet)."""
    p, t = mesh.points, mesh.tets
    pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    return float(np.mean([np.linalg.norm(p[t[:, a]] - p[t[:, b]], axis=1) for a, b in pairs]))


def coarse_index(case: Mapping, mesh: TetMesh) -> np.ndarray:
    """Indices into ``mesh.points`` (a refined level's) of the level-1 vertices of a case's
    scene; an :class:`AssertionError` if one is not a vertex of ``mesh``.
    """
    from scipy.spatial import cKDTree

    coarse = refined_scene(case["table"], case.get("path"), 1).mesh.points
    dist, idx = cKDTree(mesh.points).query(coarse)
    if dist.max() > 1e-9 * float(np.ptp(coarse, axis=0).max()):
        raise AssertionError("level-1 vertices are not vertices of the refined mesh")
    return idx


def select_levels(
    table: Mapping, n_tets: int, wanted: Sequence[int], max_tets: int
) -> tuple[list[int], list[str]]:
    """The levels of ``wanted`` a scene runs (ascending), and what was left out and why.

    A scene runs the levels it can be refined by; level ``r`` has ``n_tets r³`` tets and
    levels beyond ``max_tets`` are left out, but the two coarsest possible levels always run
    (a rate needs two).

    Examples
    --------
    >>> select_levels({"mesh": {"file": "m.msh"}}, 200, (1, 2, 3, 4, 6, 8), 40_000)
    ([1, 2, 4], ['levels 3, 6 left out (not powers of two)', 'levels 8 left out (over 40000 tets)'])
    """
    grid = grid_box(table)
    possible = sorted(k for k in set(wanted) if k >= 1 and (grid or _doublings(k) is not None))
    kept = [k for i, k in enumerate(possible) if i < 2 or n_tets * k**3 <= max_tets]
    notes = []
    for left, why in ((set(wanted) - set(possible), "not powers of two"),
                      (set(possible) - set(kept), f"over {max_tets} tets")):  # fmt: skip
        if left:
            notes.append(f"levels {', '.join(map(str, sorted(left)))} left out ({why})")
    return kept, notes
