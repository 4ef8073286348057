"""Cases of the ``tissue`` study: the scenes, one measurement each, and the settings.

Examples
--------
>>> s = cube("across", 1.2, 1, "guccione").build()
>>> s.frames[0, 0].tolist(), s.boundaries[-1].value.tolist()
([0.0, 1.0, 0.0], [0.19999999999999996, 0.0, 0.0])
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from springfem.scene import Scene

from .. import models
from ..scenes import StudyScene, case_scene

#: Land's problem-1/3 Guccione constants (kPa) with a volumetric penalty the spring model
#: can carry (kappa = 50 C: nearly incompressible, Poisson's ratio near 0.5 at rest).
GUCCIONE = {"law": "guccione", "C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0, "kappa": 100.0}
#: Holzapfel & Ogden's (2009) fit to myocardium shear data (kPa), with a penalty
#: kappa = 1000 kPa (nearly incompressible against the fibre's small-strain 4 a_f = 74 kPa).
HOLZAPFEL_OGDEN = {"law": "holzapfel-ogden", "a": 0.059, "b": 8.023, "a_f": 18.472,
                   "b_f": 16.026, "a_s": 2.481, "b_s": 11.120, "a_fs": 0.216, "b_fs": 11.436,
                   "kappa": 1000.0}  # fmt: skip
#: The stress-stretch cube's laws by name.
STRETCH_LAWS = {"guccione": GUCCIONE, "holzapfel-ogden": HOLZAPFEL_OGDEN}

#: The spring variants compared: the tissue element (Green axial and torsion springs, each
#: group stiffened as the law's terms: the law itself under any homogeneous deformation),
#: the exact element with the tissue's stiffening (shear torsion, one exponential element
#: energy, the FEM's penalty U(J): what the bundled ventricle scenes use), the exact element
#: with the specification's quadratic springs, and the specification's element.
VARIANTS = ("spring-tissue", "spring-stiffened", "spring-exact", "spring-spec")
#: The FEM models: the scene's own (the P2 reference) and P1 on the spring's mesh and element
#: order (the displacement formulation with the spring's penalty, :mod:`studies.models`).
FEM_MODELS = ("fem", "P1")
VERSION = 3


@dataclass(frozen=True)
class Settings:
    """Sizes of the ``tissue`` study.

    Parameters
    ----------
    n
        Box divisions per side of the unit cube.
    stretches
        Stretches of the stress-stretch curves.
    beam_divisions
        Divisions of the Land beam.
    lv_scene
        The bundled ventricle scene: ``land-ventricle`` (problem 2) or
        ``land-ventricle-fibres`` (problem 3's passive inflation; converges on coarser
        meshes than problem 2, whose mixed FEM fails at sizes 5 and 6 mm).
    lv_size
        Element size (mm) of the ventricle.
    lv_steps
        FEM load steps of the ventricle (points of its pressure-volume curve).
    lv_variants
        The spring variants run on the ventricle (the specification's element fails slowly:
        the quick preset leaves it out).
    conv_scenes, conv_sizes, conv_steps
        The apex mesh-convergence study (P2/P1 mixed FEM): the ventricle scenes, their
        element sizes (mm, coarse to fine) and load steps. Measured here: 2 mm takes
        ~5-8 min per scene on a shared 2-core machine; at 1.75 mm problem 2's Newton fails
        (line search at load factor 0.48, after 28 min), so the full preset stops at 2 mm.
    """

    n: int = 3
    stretches: tuple[float, ...] = (1.05, 1.1, 1.15, 1.2, 1.25, 1.3)
    beam_divisions: tuple[int, int, int] = (30, 3, 3)
    lv_scene: str = "land-ventricle"
    lv_size: float = 4.0
    lv_steps: int = 10
    lv_variants: tuple[str, ...] = VARIANTS
    conv_scenes: tuple[str, ...] = ("land-ventricle", "land-ventricle-fibres")
    conv_sizes: tuple[float, ...] = (4.0, 3.0, 2.5, 2.0)
    conv_steps: int = 10

    @classmethod
    def full(cls) -> Settings:
        """The report's preset."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """A few seconds: a coarse cube, beam and ventricle."""
        return cls(n=1, stretches=(1.1, 1.3), beam_divisions=(10, 1, 1),
                   lv_scene="land-ventricle-fibres", lv_size=6.0, lv_steps=3,
                   lv_variants=VARIANTS[:2], conv_scenes=("land-ventricle-fibres",),
                   conv_sizes=(6.0, 5.0), conv_steps=3)  # fmt: skip


def stretch_data(direction: str, stretch: float, n: int, law: str = "guccione") -> dict:
    """The table of a unit cube (mm) of a :data:`STRETCH_LAWS` material (``law``: ``guccione``
    or ``holzapfel-ogden``) pulled to ``stretch`` along x on ``n³`` boxes, the fibre along x
    (``along``) or y (``across``), the lateral faces free (rigid motions removed only).
    """
    fiber = [1.0, 0.0, 0.0] if direction == "along" else [0.0, 1.0, 0.0]
    sheet = [0.0, 1.0, 0.0] if direction == "along" else [1.0, 0.0, 0.0]
    data = {
        "name": f"tissue-{direction}",
        "units": "mm-kPa",
        "mesh": {"generator": "box", "size": [1.0, 1.0, 1.0], "divisions": [n, n, n]},
        "material": dict(STRETCH_LAWS[law]),
        "axes": {"fiber": fiber, "sheet": sheet},
        "boundary": [
            {"region": "x_min", "fix": ["x"]},
            {"region": {"point": [0.0, 0.0, 0.0]}, "fix": ["y", "z"]},
            {"region": {"point": [0.0, 1.0, 0.0]}, "fix": ["z"]},
            {"region": "x_max", "fix": ["x"], "displacement": [stretch - 1.0, 0.0, 0.0]},
        ],
        "fem": {"order": 1, "load_steps": 3},
    }
    return data


def _solve(scene: Scene, model: str, partial: bool = False):
    """Solve ``scene`` with a registered model: ``(Solution, "")``, or ``(None, message)``
    for a solver failure; with ``partial``, a solve that stopped part way along its load
    gives ``(its partial Solution, message)``."""
    got = models.run(scene, model)
    if got.ok:
        return got.solution, ""
    message = got.message.splitlines()[0][:200]
    return (got.solution if partial and got.status == "partial" else None), message


def stretch_case(case: dict) -> dict:
    """Nominal stress ``P_xx`` (kPa: the x reaction on the unit ``x_max`` face) of a cube's
    case: ``stress`` (NaN on failure), ``wall_time`` and ``error`` (message or "").
    """
    sol, err = _solve(case_scene(case), case["model"])
    if sol is None:
        return {"stress": math.nan, "wall_time": math.nan, "error": err}
    fx = sol.result.reactions["x_max"][0]
    return {"stress": float(fx), "wall_time": sol.result.wall_time, "error": ""}


def beam_case(case: dict) -> dict:
    """The Land beam's deformed tip z (mm) for one model (the bundled ``land-beam``):
    ``tip_z``, ``wall_time`` and ``error``.
    """
    sol, err = _solve(case_scene(case), case["model"])
    if sol is None:
        return {"tip_z": math.nan, "wall_time": math.nan, "error": err}
    return {"tip_z": 1.0 + sol.result.probes["tip"][2], "wall_time": sol.result.wall_time,
            "error": ""}  # fmt: skip


def ventricle_case(case: dict) -> dict:
    """A Land ventricle's apex z and cavity volumes for one model.

    Returns ``endo_apex_z``, ``epi_apex_z`` (the probes at the rest apexes (0, 0, -17) and
    (0, 0, -20), mesh vertices of the gmsh ellipsoid), ``cavity`` (initial/final, FEM: the
    pressure-volume rows), ``wall_time``, ``dofs``, ``tets``, ``load_factor`` (below 1: the
    values at the load a failed solve reached, with its ``error``) and ``error``.
    """

    sol, err = _solve(case_scene(case), case["model"], partial=True)
    if sol is None:
        nan = math.nan
        return {"endo_apex_z": nan, "epi_apex_z": nan, "cavity": {}, "wall_time": nan,
                "dofs": nan, "tets": nan, "load_factor": nan, "error": err}  # fmt: skip
    return {**_ventricle_values(sol), "error": err}


def _ventricle_values(sol) -> dict:
    """Apex z, cavity, wall time and load factor (1, or where a partial solve stopped)."""
    p = sol.result.probes
    return {
        "endo_apex_z": -17.0 + p["endo_apex"][2],
        "epi_apex_z": -20.0 + p["epi_apex"][2],
        "cavity": sol.result.info.get("cavity", {}),
        "wall_time": sol.result.wall_time,
        "load_factor": float(sol.result.info.get("load_factor", 1.0)),
        "dofs": sol.result.counts.get("dofs", math.nan),  # a partial state carries no counts
        "tets": sol.result.counts.get("tets", math.nan),
    }


def cube(direction: str, stretch: float, n: int, law: str) -> StudyScene:
    """The stress-stretch cube of :func:`stretch_data` as a study scene (role ``stretch``)."""
    label = f"{law} cube {direction} {stretch:g}"
    params = {"law": law, "direction": direction, "stretch": stretch}
    return StudyScene(label, stretch_data(direction, stretch, n, law), None, ("stretch",),
                      params=params)  # fmt: skip


def ventricle(name: str, size: float, steps: int, role: str) -> StudyScene:
    """A bundled Land ventricle at element ``size`` (mm) with ``steps`` FEM load steps."""
    sets = {"mesh.size": size, "fem.load_steps": steps}
    s = StudyScene.bundled(name, sets, label=f"{name} {size:g} mm", roles=(role,))
    return replace(s, params={"scene": name, "size": size, "steps": steps})


def scenes(settings: Settings) -> list[StudyScene]:
    """The study's scenes: the stress-stretch cubes (``stretch``), the Land beam (``beam``),
    the ventricle (``ventricle``) and the apex mesh-convergence ventricles (``apex``).
    """
    cubes = [
        cube(d, s, settings.n, law)
        for law in STRETCH_LAWS
        for d in ("along", "across")
        for s in settings.stretches
    ]
    beam = StudyScene.bundled(
        "land-beam", {"mesh.divisions": list(settings.beam_divisions)}, roles=("beam",)
    )
    lv = ventricle(settings.lv_scene, settings.lv_size, settings.lv_steps, "ventricle")
    apex = [
        ventricle(s, h, settings.conv_steps, "apex")
        for s in settings.conv_scenes
        for h in settings.conv_sizes
    ]
    return [*cubes, beam, lv, *apex]
