"""Cases of the ablation study: variants, settings, the scenes and one solve per case."""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from springfem.errors import SpringFemError
from springfem.scene import Scene

from .. import models
from ..metrics import median_time, relative_l2_error
from ..scenes import COMPARISON_SCENES, StudyScene, case_scene, comparison_scenes


def _variant(name: str, label: str, **changes: Any) -> tuple[str, models.Model]:
    return name, models.spring_variant(name, label, **changes)


#: Variants in order of the parts they switch on: name -> model.
VARIANTS: dict[str, models.Model] = dict(
    [
        _variant("spring-axial", "axial springs only", torsion="off", volume=False),
        _variant("spring-axial+volume", "+ volume springs", torsion="off", volume=True),
        _variant("spring-axial+cosine", "+ cosine torsion", torsion="cosine", volume=False),
        _variant("spring-axial+energy", "+ energy torsion", torsion="energy", volume=False),
        _variant(
            "spring-axial+cosine+volume", "cosine torsion + volume", torsion="cosine", volume=True
        ),
        _variant(
            "spring-axial+energy+volume", "energy torsion + volume", torsion="energy", volume=True
        ),
        _variant(
            "spring-axial+energy+volume+lms-abs",
            "+ sign-consistent LMS (dynamic relaxation)",
            torsion="energy",
            volume=True,
            lms="abs",
        ),
        _variant(
            "spring-axial+energy+volume+nnls",
            "+ least-squares calibration",
            torsion="energy",
            volume=True,
            calibration="nnls",
        ),
    ]
)
#: The exact spring element: axis-volume + energy torsion + the closed-form calibration,
#: without and with the Poisson-coupling springs (which anisotropic materials need).
EXACT_VARIANTS: dict[str, models.Model] = dict(
    [
        _variant("spring-exact-no-coupling", "exact element without coupling", **models.EXACT),
        _variant(
            "spring-exact+coupling", "exact element + coupling", coupling=True, **models.EXACT
        ),  # fmt: skip
    ]
)
#: Every variant, the specification's parts first (the order breaks ties towards fewer).
ALL_VARIANTS: dict[str, models.Model] = {**VARIANTS, **EXACT_VARIANTS}
#: Bundled scenes.
SCENE_NAMES = tuple(COMPARISON_SCENES)
#: A variant is adequate when its model error is at most (1 + TOLERANCE) x the best one's.
TOLERANCE = 0.10
#: Solve times within this fraction of the fastest count as a tie (timer noise).
TIME_TIE = 0.25
#: The absolute model-error budget of the second winner column.
MAX_ERROR = 0.10
#: Newton settings shared by every static solve.
NEWTON = {"tol": 1e-8, "max_iter": 25, "max_cutbacks": 4}
#: Dynamic relaxation (LMS variant): residual tolerance and step budget.
DR_TOL = 1e-6
VERSION = 2


@dataclass(frozen=True)
class Settings:
    """Meshes and step budget of the ablation study.

    Parameters
    ----------
    divisions
        Scene name -> box divisions (``None``: the bundled scene's mesh).
    dr_steps
        Dynamic-relaxation step budget of the LMS variant.
    max_error
        The tolerance: the winners table names the cheapest variant whose model error is
        at most this (``study ablation --tolerance``).
    """

    divisions: dict[str, tuple[int, int, int] | None] = field(
        default_factory=lambda: dict.fromkeys(SCENE_NAMES)
    )
    dr_steps: int = 8000
    max_error: float = MAX_ERROR
    extra: dict[str, tuple[int, int, int]] = field(
        default_factory=lambda: {
            "cantilever-unstructured": (40, 4, 4),
            "cantilever-elongated": (20, 4, 4),
        }
    )

    @classmethod
    def full(cls) -> Settings:
        """The bundled meshes, 8000 relaxation steps."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """Coarse meshes, 4000 relaxation steps."""
        coarse = {
            "cantilever": (20, 2, 2),
            "stretch-fiber": (3, 3, 3),
            "stretch-cross": (3, 3, 3),
            "sag": (8, 4, 2),
        }
        extra = {"cantilever-unstructured": (20, 2, 2), "cantilever-elongated": (10, 2, 2)}
        return cls(divisions=coarse, dr_steps=4000, extra=extra)


def bundled_scenes(settings: Settings) -> list[StudyScene]:
    """The bundled scenes on the settings' meshes, then the cantilever's other meshes."""
    return comparison_scenes(settings.divisions, settings.extra)


# ------------------------------------------------------------------------------ cases


def _timed(fn, repeat_below: float = 0.5, repeats: int = 3) -> tuple[Any, float]:
    """Result and wall time of ``fn()``; the median of ``repeats`` runs if it is fast."""
    t0 = time.perf_counter()
    out = fn()
    dt = time.perf_counter() - t0
    if dt < repeat_below:
        times = [dt]
        for _ in range(repeats - 1):
            t0 = time.perf_counter()
            out = fn()
            times.append(time.perf_counter() - t0)
        dt = float(np.median(times))
    return out, dt


def reference_model(scene: Scene) -> models.Model:
    """The same-mesh FEM reference: P1 with the scene's law (``P1-NH`` for neo-Hookean)."""
    return models.P1_NH if scene.material.law == "neo-hookean" else models.P1


def fem_case(case: dict[str, Any]) -> dict[str, Any]:
    """The same-mesh FEM reference of a scene: vertex displacements and wall time."""
    scene = case_scene(case)
    got = models.run(scene, reference_model(scene), lambda m, s: _timed(lambda: m.solve(s)))
    if not got.ok:
        return {"status": "fails", "message": got.message[:200]}
    sol, wall = got.solution
    return {"status": "ok", "u": sol.u.tolist(), "time": wall, "law": sol.result.law}


def spring_case(case: dict[str, Any]) -> dict[str, Any]:
    """One spring variant on one scene: solution and cost.

    ``case``: the scene's case keys, ``variant`` (a model name of :data:`ALL_VARIANTS`) and
    ``dr_steps`` (dynamic-relaxation budget of the LMS variant). Returns ``status``
    (``ok``/``fails``), ``message``, ``u`` (vertex displacements, nested lists; also the
    last state of a non-converged dynamic relaxation), ``solve_time``, ``build_time``,
    ``kernel_rate`` (elements per second), ``method``, ``iterations`` and, for LMS, the
    median stiffness ratio ``k_ratio_median`` and the share at the upper clamp.
    """
    from springfem.mechanics import explicit_static, static
    from springmodel.model import SpringModel

    scene = case_scene(case)
    opts = ALL_VARIANTS[case["variant"]].spring_options(scene)
    t0 = time.perf_counter()
    try:
        model = SpringModel(scene, opts, parallel=False)
    except SpringFemError as exc:  # a calibration that refuses the material
        return {"status": "fails", "message": str(exc)[:200], "tets": scene.mesh.n_tets}
    build = time.perf_counter() - t0
    x0 = model.x0.copy()
    rate = scene.mesh.n_tets / median_time(lambda: model.kernel.forces(x0), repeats=15)
    out: dict[str, Any] = {"build_time": build, "kernel_rate": rate, "tets": scene.mesh.n_tets}

    def solve():
        if opts.lms is None:
            return static(model, **NEWTON, fallback=False)
        fresh = SpringModel(scene, opts, parallel=False)  # LMS state starts at k_s0
        info = explicit_static(
            fresh,
            tol=DR_TOL,
            max_steps=case["dr_steps"],
            dt_safety=0.5 / np.sqrt(opts.lms.k_max),
            raise_on_failure=False,
        )
        info.k_ratio = fresh.elements.k_volume / fresh.elements.k_volume0
        return info

    def timed(m, s):
        # a singular tangent (axial springs only) makes the Krylov fallback divide by zero
        # before the solver reports the failure: silence numpy's warnings, keep the error
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            return _timed(solve, repeat_below=0.5 if opts.lms is None else 0.0)

    got = models.run(scene, case["variant"], solve=timed)
    if not got.ok:
        return {**out, "status": "fails", "message": got.message[:200]}
    info, wall = got.solution
    out.update(
        status="ok" if info.converged else "fails",
        message="" if info.converged else (info.message or "not converged")[:200],
        u=(info.x - x0).tolist(),
        solve_time=wall,
        method=info.method,
        iterations=int(info.iterations),
        residual=float(info.residual),
    )
    if hasattr(info, "k_ratio"):
        out["k_ratio_median"] = float(np.median(info.k_ratio))
        out["k_ratio_at_max"] = float(np.mean(info.k_ratio >= opts.lms.k_max * (1 - 1e-12)))
    return out


def model_error(case: dict[str, Any], result: dict[str, Any], u_ref: Any) -> tuple[float, float]:
    """Relative L2 error of the vertex displacements and the largest relative probe error
    of a :func:`spring_case` result against ``u_ref`` (NaN when there is no solution)."""
    if "u" not in result:
        return float("nan"), float("nan")
    u, u_ref = np.asarray(result["u"]), np.asarray(u_ref)
    scene = case_scene(case)
    return relative_l2_error(u, u_ref), _probe_error(scene, u, u_ref)


def _probe_error(scene: Scene, u: np.ndarray, u_ref: np.ndarray) -> float:
    """Largest relative probe error (displacement vector) against the reference."""
    a, b = scene.probe_displacements(u), scene.probe_displacements(u_ref)
    errs = [np.linalg.norm(np.subtract(a[k], b[k])) / np.linalg.norm(b[k]) for k in a]
    return float(max(errs)) if errs else float("nan")
