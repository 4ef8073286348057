"""Cases of the accuracy study: settings, the bundled scenes and the work of one case."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .. import models
from ..compare import Comparison, compare_scene, max_principal_strain
from ..scenes import COMPARISON_SCENES, StudyScene, case_scene, comparison_scenes

SCENES = tuple(COMPARISON_SCENES)

DISCRETISATION_HEADLINE = ("cantilever", "sag")  # P1 is exact on the uniaxial stretches

ERROR_KINDS = ("model", "total", "discretisation")


#: Errors of the exact element and the specification's against the finite-strain P1.
EXACT_KINDS = ("exact_model", "exact_model_nh", "exact_total", "model_nh")

VERSION = 3


@dataclass(frozen=True)
class Settings:
    """Meshes of the accuracy study.

    Parameters
    ----------
    divisions
        Bundled scene name -> box divisions (``None``: the bundled scene's own mesh).
    figure_scenes
        Bundled scenes that get an error-field figure (their vertex fields are kept); a
        user's scene always gets one.
    extra
        The cantilever on other meshes: ``cantilever-unstructured`` (jittered Delaunay tets
        of a grid of these divisions), ``cantilever-elongated`` (these box divisions).
    exact
        Also solve the exact spring element (and the finite-strain P1 it is exact against).
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

    @classmethod
    def full(cls) -> Settings:
        """The bundled scenes' meshes, the unstructured cantilever and 20 x 4 x 4 cells."""
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
            },
            extra={"cantilever-unstructured": (20, 2, 2), "cantilever-elongated": (10, 2, 2)},
        )


def bundled_scenes(settings: Settings) -> list[StudyScene]:
    """The bundled scenes on the settings' meshes, then the cantilever's extra meshes, with
    roles ``compare`` (and ``figure`` for :attr:`Settings.figure_scenes`).

    Examples
    --------
    >>> [s.label for s in bundled_scenes(Settings.quick())][-2:]
    ['cantilever-unstructured', 'cantilever-elongated']
    """

    def roles(name: str) -> tuple[str, ...]:
        return ("compare", "figure") if name in settings.figure_scenes else ("compare",)

    return comparison_scenes(settings.divisions, settings.extra, roles)


def scene_case(scene: StudyScene, settings: Settings) -> dict[str, Any]:
    """The JSON-able cache case of one scene: its table decides the result."""
    return scene.case(
        "accuracy", VERSION, fields=scene.serves("figure"), exact=bool(settings.exact),
        peers=models.plugins(),  # the plug-in models (springfem.model_api) it weighs too
    )  # fmt: skip


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
    for name in peer_names(cmp):  # the plug-in models: against the reference and P1-NH
        errors[f"peer_total:{name}"] = cmp.errors(name)
        if "P1-NH" in cmp.solutions:
            errors[f"peer_model_nh:{name}"] = cmp.errors(name, "P1-NH")
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


def peer_names(cmp: Comparison) -> list[str]:
    """The plug-in models a comparison solved."""
    return [n for n in cmp.solutions if models.get(n).kind == "plugin"]


def work(case: dict[str, Any]) -> dict[str, Any]:
    """Run the comparison of one scene case (the exact element where asked, and the
    case's plug-in models that apply to the scene)."""
    scene = case_scene(case)
    cmp = compare_scene(scene)
    extra = []
    if case.get("exact"):
        extra.append("spring-exact")
    if case.get("exact") or case.get("peers"):
        if "P1-NH" not in cmp.solutions and models.P1_NH.applies(scene) is None:
            extra.append("P1-NH")  # the finite-strain P1: the exact element's model error
    extra += [n for n in case.get("peers", ()) if models.get(n).applies(scene) is None]
    if extra:
        for name in extra:
            got = models.run(scene, name)
            if got.ok:
                cmp.solutions[name] = got.solution
            else:
                cmp.failures[name] = got.message
    return summarize(cmp, fields=case["fields"])


def nan_float(v: Any) -> float:
    return float("nan") if v is None else float(v)
