"""Cases of the convergence study: settings, the bundled bar, the plan of a scene, one solve.

Every case is a :meth:`~studies.scenes.StudyScene.case` of the scene (its level-1 table)
with ``model`` (a name of :mod:`studies.models`) and ``factor`` (its refinement level,
:mod:`.levels`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import models
from ..scenes import StudyScene
from .levels import case_level, coarse_index, mean_edge, select_levels

VERSION = 2

#: The spring model of the study (energy torsion: analytic Hessian), its cosine check and
#: the exact element.
SPRING, COSINE, EXACT = "spring-energy", "spring-cosine", "spring-exact"
#: An extrapolation with a lower fitted order is not trusted.
MIN_EXTRAPOLATION_ORDER = 0.8


@dataclass(frozen=True)
class Settings:
    """Refinement levels of the convergence study (factors of the scene's own mesh).

    Parameters
    ----------
    levels
        Levels of the spring models and P1.
    p2_levels
        Levels of P2.
    ref
        Level of the P2 reference (a scene that cannot take it: its finest level).
    cosine_check_level
        Level of the cosine-torsion check (or the finest level below it that runs).
    max_tets
        Levels with more tets are left out (the two coarsest always run).
    """

    levels: tuple[int, ...] = (1, 2, 3, 4, 6, 8)
    p2_levels: tuple[int, ...] = (1, 2, 3, 4)
    ref: int = 8
    cosine_check_level: int = 4
    max_tets: int = 40_000

    @classmethod
    def full(cls) -> Settings:
        """Levels 1-8, reference P2 at 8."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """Levels 1-4, reference P2 at 4."""
        return cls(levels=(1, 2, 3, 4), p2_levels=(1, 2, 3), ref=4, max_tets=5_000)


def fem_models(law: str) -> tuple[str, str]:
    """The FEM models ``(P1, P2)`` of a scene: its law (neo-Hookean FEM for a neo-Hookean
    scene, else the small-strain law or a tissue law's own).

    Examples
    --------
    >>> fem_models("neo-hookean"), fem_models("transverse-linear")
    (('P1-NH', 'P2-NH'), ('P1', 'P2'))
    """
    return ("P1-NH", "P2-NH") if law == "neo-hookean" else ("P1", "P2")


def bundled_scenes(settings: Settings) -> list[StudyScene]:
    """The cantilever bar (0.1 × 0.01 × 0.01 m, end shear) on ``[10, 1, 1]`` hexahedra, six
    tets each, with Timoshenko's tip deflection as its closed-form reference.

    Examples
    --------
    >>> [s.build().mesh.n_tets for s in bundled_scenes(Settings())]
    [60]
    """
    return [StudyScene.bundled("cantilever", {"mesh.divisions": [10, 1, 1]}, analytic="timoshenko")]


@dataclass(frozen=True)
class Plan:
    """What runs on one scene: its levels, the reference and the cosine check.

    Attributes
    ----------
    scene
        The scene (level 1).
    fem
        Its P1 and P2 models (:func:`fem_models`).
    levels, p2_levels
        Levels of the spring models and P1, and of P2 (without the reference level).
    ref, cosine
        Levels of the P2 reference and of the cosine-torsion check.
    notes
        Levels of the settings the scene does not run, and why.
    n_tets, h1
        Tets and mean edge length of level 1.
    """

    scene: StudyScene
    fem: tuple[str, str]
    levels: tuple[int, ...]
    p2_levels: tuple[int, ...]
    ref: int
    cosine: int
    notes: tuple[str, ...]
    n_tets: int
    h1: float

    @property
    def models(self) -> tuple[str, ...]:
        """The models of the tables: the spring models, P1 and P2."""
        return (SPRING, EXACT, *self.fem)

    def case(self, model: str, factor: int) -> dict[str, Any]:
        """The cache case of ``model`` on level ``factor``."""
        return self.scene.case("convergence", VERSION, model=model, factor=factor)

    def cases(self) -> list[dict[str, Any]]:
        """Every case of the plan: the reference first (a budget leaves out the last cases,
        never the reference), then levels, P2 levels and the cosine check."""
        p1, p2 = self.fem
        out = [self.case(m, k) for m in (SPRING, p1, EXACT) for k in self.levels]
        out += [self.case(p2, k) for k in self.p2_levels]
        return [self.case(p2, self.ref), *out, self.case(COSINE, self.cosine)]


def plan(s: StudyScene, q: Settings) -> Plan:
    """The levels a scene runs (see :func:`.levels.select_levels`).

    Examples
    --------
    >>> p = plan(bundled_scenes(Settings())[0], Settings())
    >>> p.levels, p.p2_levels, p.ref, p.cosine
    ((1, 2, 3, 4, 6, 8), (1, 2, 3, 4), 8, 4)
    """
    scene = s.build()
    mesh = scene.mesh
    wanted = {*q.levels, *q.p2_levels, q.ref}
    kept, notes = select_levels(s.table, mesh.n_tets, sorted(wanted), q.max_tets)
    levels = tuple(k for k in q.levels if k in kept)
    ref = q.ref if q.ref in kept else max(kept)
    below = [k for k in levels if k <= q.cosine_check_level]
    cosine = max(below) if below else levels[0]
    p2 = tuple(k for k in q.p2_levels if k in kept and k != ref)
    fem = fem_models(scene.material.law)
    return Plan(s, fem, levels, p2, ref, cosine, tuple(notes), mesh.n_tets, mean_edge(mesh))


def work(case: dict[str, Any]) -> dict[str, Any]:
    """Solve one level with one model: its probes and its field at the level-1 vertices."""
    scene = case_level(case)
    got = models.run(scene, case["model"])
    out = {"status": got.status, "tets": scene.mesh.n_tets, "message": got.message[:240]}
    if not got.ok:
        return out
    r = got.solution.result
    return {
        **out,
        "dofs": r.counts.get("dofs", 3 * scene.mesh.n_points),
        "probes": r.probes,
        "u_coarse": np.asarray(got.u)[coarse_index(case, scene.mesh)],
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
