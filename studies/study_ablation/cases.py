"""Cases of the ablation study: variants, settings, the scenes and one solve per case."""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from springfem.errors import SolverError, SpringFemError
from springfem.scene import Scene, scene_from_dict
from springmodel.options import LMSOptions, SpringOptions

from ..compare import bundled_scene
from ..metrics import median_time, relative_l2_error

#: Variants in order of the parts they switch on: label -> changes to ``[spring]``.
VARIANTS: dict[str, dict[str, Any]] = {
    "axial": {"torsion": "off", "volume": False},
    "axial+volume": {"torsion": "off", "volume": True},
    "axial+cosine": {"torsion": "cosine", "volume": False},
    "axial+energy": {"torsion": "energy", "volume": False},
    "axial+cosine+volume": {"torsion": "cosine", "volume": True},
    "axial+energy+volume": {"torsion": "energy", "volume": True},
    "+LMS (abs)": {"torsion": "energy", "volume": True, "lms": "abs"},
    "+volume (nnls cal.)": {"torsion": "energy", "volume": True, "calibration": "nnls"},
}
#: The exact spring element of issue 10 (DESIGN §4b): axis-volume + energy torsion + the
#: closed-form calibration, and with the Poisson-coupling springs (anisotropic materials).
EXACT_VARIANTS: dict[str, dict[str, Any]] = {
    "exact": {"torsion": "energy", "volume": "axes", "calibration": "exact"},
    "exact+coupling": {
        "torsion": "energy",
        "volume": "axes",
        "calibration": "exact",
        "coupling": True,
    },
}
#: Every variant, the seed model's parts first (the order breaks ties towards fewer parts).
ALL_VARIANTS: dict[str, dict[str, Any]] = {**VARIANTS, **EXACT_VARIANTS}
#: Bundled scenes.
SCENE_NAMES = ("cantilever", "stretch-fiber", "stretch-cross", "sag")
#: The cantilever on other meshes: a jittered Delaunay mesh and elongated (2:1:1) cells.
EXTRA_SCENES = ("cantilever-unstructured", "cantilever-elongated")
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


@dataclass(frozen=True)
class Settings:
    """Meshes and step budget of the ablation study.

    Parameters
    ----------
    divisions
        Scene name -> box divisions (``None``: the bundled scene's mesh).
    dr_steps
        Dynamic-relaxation step budget of the LMS variant.
    """

    divisions: dict[str, tuple[int, int, int] | None] = field(
        default_factory=lambda: dict.fromkeys(SCENE_NAMES)
    )
    dr_steps: int = 8000
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

    scene: dict | None = None
    scene_path: str | None = None

    def scenes(self) -> dict[str, tuple[int, int, int] | None]:
        """Scene name -> divisions, the bundled scenes first, then :data:`EXTRA_SCENES`."""
        if self.scene is not None:
            return {self.scene_label(): None}
        return {**self.divisions, **self.extra}

    def scene_label(self) -> str:
        """The user scene's name (its ``name``, else the file's stem)."""
        from pathlib import Path

        return str(self.scene.get("name") or Path(self.scene_path or "scene").stem)

    def scene_fields(self) -> dict[str, Any]:
        """What a case of the user scene carries: its table, file and mesh digest."""
        if self.scene is None:
            return {}
        from ..registry import mesh_digest

        return {
            "table": self.scene,
            "path": self.scene_path,
            "mesh_digest": mesh_digest(self.scene, self.scene_path),
        }

    @classmethod
    def for_scene(cls, table: dict, path: str | None = None, quick: bool = False) -> Settings:
        """Every variant on one user scene (``study ablation --scene FILE``).

        Parameters
        ----------
        table
            The scene table.
        path
            The scene file.
        quick
            4000 instead of 8000 relaxation steps for the LMS variant.

        Returns
        -------
        Settings
        """
        return cls(divisions={}, extra={}, dr_steps=4000 if quick else 8000, scene=table,
                   scene_path=path)  # fmt: skip


# ------------------------------------------------------------------------------ scene


def ablation_scene(name: str, divisions: tuple[int, int, int] | None = None) -> Scene:
    """A bundled scene, optionally on a different box mesh.

    Parameters
    ----------
    name
        A bundled scene.
    divisions
        Box divisions (``None``: the bundled mesh).

    Returns
    -------
    Scene
        ``cantilever-unstructured``: the cantilever on a jittered Delaunay mesh with the
        grid ``divisions``; ``cantilever-elongated``: the cantilever on ``divisions``.
    """
    if name in EXTRA_SCENES:
        from ..study_accuracy.variants import jittered_box

        data = bundled_scene("cantilever", divisions)
        data["name"] = name
        if name == "cantilever-unstructured":
            data["mesh"] = jittered_box(tuple(data["mesh"]["size"]), tuple(divisions), seed=0)
        return scene_from_dict(data)
    return scene_from_dict(bundled_scene(name, divisions))


def variant_options(scene: Scene, variant: str) -> SpringOptions:
    """The scene's spring options with a variant's parts (see :data:`VARIANTS`)."""
    changes = dict(ALL_VARIANTS[variant])
    rule = changes.pop("lms", None)
    if rule is not None:
        changes["lms"] = LMSOptions(rule=rule)
    return replace(SpringOptions.of(scene), **changes)


def case_scene(case: dict[str, Any]) -> Scene:
    """The scene of a case: a user scene's ``table`` (``study ablation --scene``), else
    :func:`ablation_scene` of its name and divisions."""
    if "table" in case:
        return scene_from_dict(case["table"], path=case.get("path"))
    return ablation_scene(case["scene"], case["divisions"])


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


def fem_case(case: dict[str, Any]) -> dict[str, Any]:
    """FEM P1 reference of a scene: vertex displacements and wall time."""
    import reference_fem

    scene = case_scene(case)
    try:
        sol, wall = _timed(lambda: reference_fem.solve(scene, order=1))
    except SolverError as exc:
        return {"status": "fails", "message": str(exc)[:200]}
    return {"status": "ok", "u": sol.u_vertices.tolist(), "time": wall, "law": sol.result.law}


def spring_case(case: dict[str, Any]) -> dict[str, Any]:
    """One spring variant on one scene: solution and cost.

    ``case``: ``scene``, ``divisions`` (``None`` = bundled mesh), ``variant`` and
    ``dr_steps`` (dynamic-relaxation budget of the LMS variant). Returns ``status``
    (``ok``/``fails``), ``message``, ``u`` (vertex displacements, nested lists; also the
    last state of a non-converged dynamic relaxation), ``solve_time``, ``build_time``,
    ``kernel_rate`` (elements per second), ``method``, ``iterations`` and, for LMS, the
    median stiffness ratio ``k_ratio_median`` and the share at the upper clamp.
    """
    from springfem.mechanics import explicit_static, static
    from springmodel.model import SpringModel

    scene = case_scene(case)
    opts = variant_options(scene, case["variant"])
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

    try:
        # a singular tangent (axial springs only) makes the Krylov fallback divide by zero
        # before the solver reports the failure: silence numpy's warnings, keep the error
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            info, wall = _timed(solve, repeat_below=0.5 if opts.lms is None else 0.0)
    except SolverError as exc:
        return {**out, "status": "fails", "message": str(exc)[:200]}
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
