"""Cases of the ``tissue`` study: the scenes, one measurement each, and the settings.

Examples
--------
>>> s = stretch_scene("across", 1.2, 1)
>>> s.frames[0, 0].tolist(), s.boundaries[-1].value.tolist()
([0.0, 1.0, 0.0], [0.19999999999999996, 0.0, 0.0])
"""

from __future__ import annotations

import copy
import math
import time
import tomllib
from dataclasses import dataclass
from pathlib import Path

from springfem.errors import SolverError
from springfem.scene import Scene, scene_from_dict

from ..partial import partial_solution

SCENES = Path(__file__).resolve().parents[1] / "scenes"

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

#: The spring variants compared: the exact element with the tissue's stiffening (Green-strain
#: axial springs, shear torsion, exponential element energy: what the bundled ventricle scenes
#: use; the FEM's penalty U(J)), the exact element with the spec's quadratic springs, and the
#: seed's default element.
VARIANTS = {
    "stiffened": {"volume": "axes", "torsion": "shear", "calibration": "exact", "coupling": True,
                  "axial": "green", "stiffening": "exponential", "volumetric": "log"},
    "exact": {"volume": "axes", "torsion": "energy", "calibration": "exact", "coupling": True},
    "seed": {},
}  # fmt: skip
#: The ``[spring]`` keys that choose the element (a variant sets them, or leaves defaults).
ELEMENT_KEYS = ("volume", "torsion", "calibration", "coupling", "axial", "axial_coefficients",
                "stiffening", "stiffening_modulus", "volumetric")  # fmt: skip
#: The FEM on the spring's mesh and element order: P1 in the displacement formulation with the
#: spring's penalty (:func:`studies.compare_models.model_scene`), beside the P2 reference.
FEM_P1 = "fem-p1"


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
        The spring variants run on the ventricle (the seed's fails slowly: the quick preset
        leaves it out).
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
    lv_variants: tuple[str, ...] = tuple(VARIANTS)
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
                   lv_variants=("stiffened", "exact"), conv_scenes=("land-ventricle-fibres",),
                   conv_sizes=(6.0, 5.0), conv_steps=3)  # fmt: skip


def stretch_scene(direction: str, stretch: float, n: int, law: str = "guccione") -> Scene:
    """The scene of :func:`stretch_data` (see there).

    Parameters
    ----------
    direction, stretch, n, law
        See :func:`stretch_data`.

    Returns
    -------
    Scene
    """
    return scene_from_dict(stretch_data(direction, stretch, n, law))


def stretch_data(direction: str, stretch: float, n: int, law: str = "guccione") -> dict:
    """A unit cube (mm) of a :data:`STRETCH_LAWS` material pulled to ``stretch`` along x, the
    fibre along x (``along``) or y (``across``), the lateral faces free (rigid motions
    removed only).

    Parameters
    ----------
    direction
        ``along`` or ``across``.
    stretch
        The prescribed stretch of the x edge.
    n
        Divisions per side.
    law
        ``guccione`` (:data:`GUCCIONE`) or ``holzapfel-ogden`` (:data:`HOLZAPFEL_OGDEN`).

    Returns
    -------
    dict
        The scene table.
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


def _solve(data: dict, path: Path | None, model: str, variant: str | None, partial: bool = False):
    """Build the scene of ``data`` (with the spring ``variant``) and solve it: ``(Solution,
    None)``, or ``(None, message)`` for a solver failure; with ``partial``, a solve that
    stopped part way along its load gives ``(its partial Solution, message)``."""
    from ..solve import solve_scene

    if model == "spring":
        # the variant replaces the scene's element choice (the bundled ventricles ask for the
        # exact element); the scene's other spring settings are kept
        own = {k: v for k, v in data.get("spring", {}).items() if k not in ELEMENT_KEYS}
        data = {**data, "spring": {**own, **VARIANTS[variant or "exact"]}}
    scene = scene_from_dict(data, path)
    if model == FEM_P1:
        from ..compare_models import model_scene

        scene, model = model_scene(scene, "P1"), "fem"
    t0 = time.perf_counter()
    try:
        return solve_scene(scene, model), None
    except SolverError as exc:
        stopped = partial_solution(scene, model, exc, time.perf_counter() - t0) if partial else None
        return stopped, str(exc).splitlines()[0][:200]


def stretch_case(case: dict) -> dict:
    """Nominal stress ``P_xx`` (kPa: the x reaction on the unit ``x_max`` face).

    Parameters
    ----------
    case
        ``direction``, ``stretch``, ``n``, ``model``, ``variant`` (spring only) and ``law``
        (default ``guccione``).

    Returns
    -------
    dict
        ``stress`` (NaN on failure), ``wall_time`` and ``error`` (message or "").
    """
    law = case.get("law", "guccione")
    data = stretch_data(case["direction"], case["stretch"], case["n"], law)
    sol, err = _solve(data, None, case["model"], case.get("variant"))
    if sol is None:
        return {"stress": math.nan, "wall_time": math.nan, "error": err}
    fx = sol.result.reactions["x_max"][0]
    return {"stress": float(fx), "wall_time": sol.result.wall_time, "error": ""}


def _scene_file(name: str, edit) -> tuple[dict, Path]:
    """A bundled scene's table, edited, and its path."""
    path = SCENES / f"{name}.toml"
    data = copy.deepcopy(tomllib.loads(path.read_text(encoding="utf-8")))
    edit(data)
    return data, path


def beam_case(case: dict) -> dict:
    """The Land beam's deformed tip z (mm) for one model (the bundled ``land-beam``).

    Parameters
    ----------
    case
        ``divisions``, ``model`` (``fem``, ``fem-p1`` or ``spring``), ``variant`` (spring
        only).

    Returns
    -------
    dict
        ``tip_z``, ``wall_time`` and ``error``.
    """

    def edit(d):
        d["mesh"]["divisions"] = list(case["divisions"])

    sol, err = _solve(*_scene_file("land-beam", edit), case["model"], case.get("variant"))
    if sol is None:
        return {"tip_z": math.nan, "wall_time": math.nan, "error": err}
    return {"tip_z": 1.0 + sol.result.probes["tip"][2], "wall_time": sol.result.wall_time,
            "error": ""}  # fmt: skip


def ventricle_case(case: dict) -> dict:
    """A Land ventricle's apex z and cavity volumes for one model.

    Parameters
    ----------
    case
        ``scene`` (a bundled ventricle scene), ``size``, ``steps``, ``model``, ``variant``
        (spring only).

    Returns
    -------
    dict
        ``endo_apex_z``, ``epi_apex_z`` (the probes at the rest apexes (0, 0, -17) and
        (0, 0, -20), mesh vertices of the gmsh ellipsoid), ``cavity`` (initial/final, FEM:
        the pressure-volume rows), ``wall_time``, ``dofs``, ``tets``, ``load_factor`` (below
        1: the values at the load a failed solve reached, with its ``error``) and ``error``.
    """

    def edit(d):
        d["mesh"]["size"] = case["size"]
        d["fem"]["load_steps"] = case["steps"]

    data, path = _scene_file(case["scene"], edit)
    sol, err = _solve(data, path, case["model"], case.get("variant"), partial=True)
    if sol is None:
        nan = math.nan
        return {"endo_apex_z": nan, "epi_apex_z": nan, "cavity": {}, "wall_time": nan,
                "dofs": nan, "tets": nan, "load_factor": nan, "error": err}  # fmt: skip
    return {**_ventricle_values(sol), "error": err or ""}


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
