"""Cases of the accuracy study: settings, the scene cases and the work of one case."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from springfem.scene import Scene, parse_scene

from .. import metrics
from ..compare import (
    Comparison,
    bundled_scene_text,
    compare_scene,
    max_principal_strain,
)

SCENES = ("cantilever", "stretch-fiber", "stretch-cross", "sag")


DISCRETISATION_HEADLINE = ("cantilever", "sag")  # P1 is exact on the uniaxial stretches


ERROR_KINDS = ("model", "total", "discretisation")


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

    @classmethod
    def full(cls) -> Settings:
        """The bundled scenes' meshes."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """Coarse meshes (``springfem report --quick``)."""
        return cls(
            divisions={
                "cantilever": (20, 2, 2),
                "stretch-fiber": (3, 3, 3),
                "stretch-cross": (3, 3, 3),
                "sag": (8, 4, 2),
            }
        )


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
    text = bundled_scene_text(name, settings.divisions[name])
    return {
        "study": "accuracy",
        "version": VERSION,
        "scene": name,
        "text": text,
        "fields": name in settings.figure_scenes,
    }


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
    scene = parse_scene(case["text"])
    return summarize(compare_scene(scene), fields=case["fields"])


def analytic_probe(name: str, scene: Scene) -> tuple[str, int, float, str] | None:
    """``(probe, component, value, source)`` of an analytic probe displacement, if any."""
    raw = scene.raw
    size = raw["mesh"]["size"]
    load = np.asarray(raw["load"][0]["value"], float)
    mat = scene.material
    if name == "cantilever":
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
