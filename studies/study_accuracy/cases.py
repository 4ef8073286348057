"""Cases of the accuracy study: settings, the scene cases and the work of one case."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from springfem.errors import SolverError
from springfem.scene import Scene, scene_from_dict

from .. import metrics
from ..compare import (
    Comparison,
    bundled_scene,
    compare_scene,
    max_principal_strain,
    solve_model,
)
from ..registry import mesh_digest
from ..solve import Solution
from .variants import exact_options, jittered_box

SCENES = ("cantilever", "stretch-fiber", "stretch-cross", "sag")


DISCRETISATION_HEADLINE = ("cantilever", "sag")  # P1 is exact on the uniaxial stretches


ERROR_KINDS = ("model", "total", "discretisation")


#: The cantilever on other meshes: unstructured (jittered Delaunay) and elongated cells.
EXTRA_SCENES = ("cantilever-unstructured", "cantilever-elongated")


#: Errors of the exact variant and the seed model's against the finite-strain P1.
EXACT_KINDS = ("exact_model", "exact_model_nh", "exact_total", "model_nh")


VERSION = 2


@dataclass(frozen=True)
class Settings:
    """Meshes of the accuracy study.

    Parameters
    ----------
    divisions
        Scene name -> box divisions (``None``: the bundled scene's own mesh).
    figure_scenes
        Scenes that get an error-field figure (their vertex fields are kept).
    """

    divisions: dict[str, tuple[int, int, int] | None] = field(
        default_factory=lambda: dict.fromkeys(SCENES)
    )
    figure_scenes: tuple[str, ...] = ("cantilever", "sag")
    extra: dict[str, tuple[int, int, int]] = field(
        default_factory=lambda: {
            "cantilever-unstructured": (40, 4, 4),
            "cantilever-elongated": (20, 4, 4),
        }
    )
    exact: bool = True
    scene: dict | None = None
    scene_path: str | None = None

    @classmethod
    def full(cls) -> Settings:
        """The bundled scenes' meshes, the unstructured cantilever and 20 x 4 x 4 cells."""
        return cls()

    def scene_label(self) -> str:
        """The user scene's name (its ``name``, else the file's stem)."""
        from pathlib import Path

        return str(self.scene.get("name") or Path(self.scene_path or "scene").stem)

    def scenes(self) -> tuple[str, ...]:
        """The scene names this run compares (one: ``"scene"``, for ``--scene``)."""
        if self.scene is not None:
            return (self.scene_label(),)
        return tuple(self.divisions) + tuple(self.extra)

    @classmethod
    def quick(cls) -> Settings:
        """Coarse meshes (``springfem report --quick``)."""
        return cls(
            divisions={
                "cantilever": (20, 2, 2),
                "stretch-fiber": (3, 3, 3),
                "stretch-cross": (3, 3, 3),
                "sag": (8, 4, 2),
            },
            extra={"cantilever-unstructured": (20, 2, 2), "cantilever-elongated": (10, 2, 2)},
        )

    @classmethod
    def for_scene(cls, table: dict, path: str | None = None, quick: bool = False) -> Settings:
        """Settings that compare the models on one user scene (``study --scene FILE``).

        Parameters
        ----------
        table
            The scene table.
        path
            The scene file.
        quick
            Unused (the user's mesh is the mesh).

        Returns
        -------
        Settings
        """
        made = cls(divisions={}, extra={}, scene=table, scene_path=path)
        return replace(made, figure_scenes=(made.scene_label(),))


def scene_case(name: str, settings: Settings) -> dict[str, Any]:
    """The cache case of one scene: its full TOML text decides the result.

    Parameters
    ----------
    name
        A bundled scene name.
    settings
        The study's settings.

    Returns
    -------
    dict
        The JSON-able case.
    """
    jitter = None
    user = settings.scene is not None
    if user:
        data = dict(settings.scene)
    elif name in settings.extra:
        data = bundled_scene("cantilever", settings.extra[name])
        data["name"] = name
        if name == "cantilever-unstructured":
            jitter = {"divisions": list(settings.extra[name]), "seed": 0}
    else:
        data = bundled_scene(name, settings.divisions[name])
    case = {
        "study": "accuracy",
        "version": VERSION,
        "scene": name,
        "table": data,
        "fields": name in settings.figure_scenes,
    }
    if jitter is not None:
        case["jittered"] = jitter
    if user:
        case["path"] = settings.scene_path
        case["mesh_digest"] = mesh_digest(data, settings.scene_path)
    if settings.exact:
        case["exact"] = True
    return case


def case_scene(case: dict[str, Any]) -> Scene:
    """The scene of a case (the unstructured cantilever gets its jittered Delaunay mesh).

    Parameters
    ----------
    case
        A case of :func:`scene_case`.

    Returns
    -------
    Scene
    """
    data = dict(case["table"])
    if "jittered" in case:
        j = case["jittered"]
        data["mesh"] = jittered_box(
            tuple(data["mesh"]["size"]), tuple(j["divisions"]), seed=j["seed"]
        )
    return scene_from_dict(data, path=case.get("path"))


def summarize(cmp: Comparison, fields: bool = False) -> dict[str, Any]:
    """JSON-able numbers of a comparison (and the vertex fields if ``fields``)."""
    p1 = cmp.same_mesh_p1
    errors = {
        "model": cmp.errors("spring", p1) if p1 else {},
        "total": cmp.errors("spring"),
        "discretisation": cmp.errors(p1) if p1 else {},
    }
    if cmp.reference.endswith("-NH"):  # what a small-strain analysis would have given
        errors["small_strain_p2"] = cmp.errors("P2")
    if "spring-exact" in cmp.solutions:
        errors["exact_model"] = cmp.errors("spring-exact", "P1")
        errors["exact_model_nh"] = cmp.errors("spring-exact", "P1-NH")
        errors["exact_total"] = cmp.errors("spring-exact")
        errors["model_nh"] = cmp.errors("spring", "P1-NH")
    out: dict[str, Any] = {
        "reference": cmp.reference,
        "p1": p1,
        "strain": cmp.strain,
        "strain_ref": max_principal_strain(cmp.scene, cmp.solutions[cmp.reference].u),
        "notes": cmp.notes,
        "failures": cmp.failures,
        "nodes": cmp.scene.mesh.n_points,
        "tets": cmp.scene.mesh.n_tets,
        "errors": errors,
        "probes": {n: s.result.probes for n, s in cmp.solutions.items()},
        "volume": {n: s.result.volume["relative_change"] for n, s in cmp.solutions.items()},
        "wall": {n: s.result.wall_time for n, s in cmp.solutions.items()},
        "laws": {n: s.result.law for n, s in cmp.solutions.items()},
    }
    if fields:
        out["u"] = {n: s.u for n, s in cmp.solutions.items()}
    return out


def work(case: dict[str, Any]) -> dict[str, Any]:
    """Run the comparison of one scene case."""
    scene = case_scene(case)
    cmp = compare_scene(scene)
    if case.get("exact"):
        from springmodel.model import solve_spring

        exact = scene.with_options(spring=exact_options(scene))
        try:
            sol = solve_spring(exact)
            cmp.solutions["spring-exact"] = Solution(sol.result, sol.u, dict(sol.cell_data))
        except SolverError as exc:
            cmp.failures["spring-exact"] = str(exc)
        if "P1-NH" not in cmp.solutions and scene.material.law != "transverse-linear":
            try:  # the finite-strain P1: the exact element's model error proper
                cmp.solutions["P1-NH"] = solve_model(scene, "P1-NH")
            except SolverError as exc:
                cmp.failures["P1-NH"] = str(exc)
    return summarize(cmp, fields=case["fields"])


def analytic_probe(name: str, scene: Scene) -> tuple[str, int, float, str] | None:
    """``(probe, component, value, source)`` of an analytic probe displacement, if any."""
    raw = scene.raw
    lo, hi = scene.mesh.bounding_box()
    size = [float(x) for x in hi - lo]  # also for a mesh passed in (no "size" key)
    load = np.asarray(raw["load"][0]["value"], float)
    mat = scene.material
    if name.startswith("cantilever"):  # also the unstructured and elongated meshes
        force = abs(load[2]) * size[1] * size[2]
        w = metrics.timoshenko_tip_deflection(force, *size, mat.E, mat.nu)
        return "tip", 2, float(np.sign(load[2]) * w), "Timoshenko"
    if name in ("stretch-fiber", "stretch-cross"):
        E = mat.E_fiber if name == "stretch-fiber" else mat.E_cross
        label = "σ/E_fiber" if name == "stretch-fiber" else "σ/E_cross"
        return "corner", 0, float(load[0] / E * size[0]), f"{label} · L"
    return None


def nan_float(v: Any) -> float:
    return float("nan") if v is None else float(v)
