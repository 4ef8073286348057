"""The exact spring variants on whole scenes: spring vs P1 on the same mesh at small load.

With ``volume = "axes"``, ``torsion = "energy"``, ``calibration = "exact"`` (and
``coupling = true`` for the transversely isotropic scenes) the small-strain spring model *is*
the P1 model (docs/theory.rst#the-exact-element-is-the-p1-element); at 1e-3 of the scene's load only
geometric nonlinearity is left
(relative size ~ 1e-3 x deflection / length, measured 2e-6 on the cantilever and 3e-5 on the
sag, whose P1 neo-Hookean solution is 10x closer), so the relative L2 difference must be
below the issue's 1e-4. (At 1e-4 of the load the static solver cannot reach its relative
tolerance 1e-8: the forces are at round-off.) The specification's element is 8-35% off on the same
scenes, so the bound fails on any calibration error. The reference is the FEM package's P1
(linear or transverse-linear law), an independent code path (scikit-fem assembly).
"""

from __future__ import annotations

import copy
import tomllib
from dataclasses import replace
from pathlib import Path

import meshio
import numpy as np
import pytest
from scipy.spatial import Delaunay

import reference_fem
from springfem.scene import scene_from_dict
from springmodel.model import solve_spring
from springmodel.options import SpringOptions

SCENES = Path(__file__).resolve().parents[2] / "studies" / "scenes"
LOAD = 1e-3


def scaled(d: dict, s: float) -> dict:
    d = copy.deepcopy(d)
    for load in d.get("load", []):
        v = load["value"]
        load["value"] = s * v if isinstance(v, int | float) else [s * x for x in v]
    return d


def jittered_delaunay_box(size, div, seed: int = 0, jitter: float = 0.3):
    """Delaunay tets of a jittered grid; boundary nodes move only within their faces."""
    rng = np.random.default_rng(seed)
    axes = [np.linspace(0.0, s, d + 1) for s, d in zip(size, div, strict=True)]
    P = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    J = jitter * (np.array(size) / np.array(div)) * rng.uniform(-1, 1, P.shape)
    J[np.isclose(P, 0.0) | np.isclose(P, np.array(size))] = 0.0
    P = P + J
    T = Delaunay(P).simplices
    V = np.linalg.det(P[T][:, 1:] - P[T][:, :1]) / 6
    keep = np.abs(V) > 1e-6 * np.abs(V).mean()  # flat hull tets of coplanar face nodes
    T, V = T[keep], V[keep]
    T[V < 0] = T[V < 0][:, [0, 2, 1, 3]]
    return P, T


def exact_scene(d: dict) -> dict:
    d = copy.deepcopy(d)
    transverse = d["material"]["law"] == "transverse-linear"
    spring = {k: v for k, v in d.get("spring", {}).items() if k not in ("volume", "torsion")}
    spring.update(volume="axes", torsion="energy", calibration="exact", coupling=transverse)
    d["spring"] = spring
    return d


def model_error(d: dict) -> float:
    scene = scene_from_dict(scaled(exact_scene(d), LOAD))
    law = "transverse-linear" if scene.material.law == "transverse-linear" else "linear"
    u_p1 = reference_fem.solve(scene, order=1, law=law).u_vertices
    u = solve_spring(scene).u
    return float(np.linalg.norm(u - u_p1) / np.linalg.norm(u_p1))


#: The bundled scenes with a small-strain law (the tissue scenes: test_tissue_... below).
SMALL_STRAIN_LAWS = ("linear", "transverse-linear", "neo-hookean")
SMALL_STRAIN_SCENES = sorted(
    p.stem
    for p in SCENES.glob("*.toml")
    if tomllib.loads(p.read_text())["material"]["law"] in SMALL_STRAIN_LAWS
)


#: Scenes whose static Newton stops on a residual floor (about 4e-8 relative, measured on
#: the 20:1 beam with two elements through its thickness) that leaves ~4e-4 of the tiny
#: displacement: there the small-strain solve (``solver = "linear"``) carries the check.
#: The nearly incompressible organ (nu 0.49, gmsh tets) leaves 2e-4 the same way.
SLENDER = ("cantilever-large-rotation", "organ-settle")


@pytest.mark.parametrize("name", SMALL_STRAIN_SCENES)
def test_bundled_scene_small_load_equals_p1(name):
    d = tomllib.loads((SCENES / f"{name}.toml").read_text())
    if "file" in d["mesh"]:  # a bundled mesh file, relative to the scene
        d["mesh"]["file"] = str(SCENES / d["mesh"]["file"])
    d.get("fem", {}).pop("formulation", None)  # the check is against P1 (not P2/P1 mixed)
    if name in SLENDER:
        d.setdefault("spring", {})["solver"] = "linear"
    assert model_error(d) < 1e-4


def test_unstructured_mesh_small_load_equals_p1(tmp_path):
    d = tomllib.loads((SCENES / "cantilever.toml").read_text())
    P, T = jittered_delaunay_box((0.1, 0.01, 0.01), (20, 3, 3), seed=4)
    path = tmp_path / "delaunay.vtu"
    meshio.write(path, meshio.Mesh(P, [("tetra", T)]))
    d["mesh"] = {"file": str(path)}
    assert model_error(d) < 1e-4


@pytest.mark.parametrize("law", ["guccione", "holzapfel-ogden"])
def test_tissue_scene_small_load_equals_p1_of_the_law(law):
    # The Land beam made compressible (kappa = 50 C, the displacement formulation runs on
    # P1) with fibres along x: at 1e-4 of its load the spring model calibrated from the
    # law's closed-form small-strain tangent (springfem.materials.tissue_matrix) must match
    # the FEM's P1 solve of the same law (springfem.materials.laws, finite strain, an independent
    # implementation of W) to the nonlinearity level: the difference is linear in the load
    # (measured 1.04e-3, 1.04e-4, 1.04e-5 at 1e-2, 1e-3, 1e-4: the exponential laws stiffen
    # at O(b strain)), so 1e-4 of the load leaves a tenth of the bound.
    # Holzapfel-Ogden's fibre and sheet terms act only in tension, and the calibration takes
    # the tension side: pulling the beam (a traction on x_max) keeps the fibres stretched;
    # the sheets contract laterally, so the sheet term is left out (a_s = 0).
    d = tomllib.loads((SCENES / "land-beam.toml").read_text())
    d["mesh"]["divisions"] = [10, 2, 2]
    if law == "holzapfel-ogden":
        d["material"] = dict(law=law, a=1.0, b=2.0, a_f=2.0, b_f=4.0, a_s=0.0, b_s=2.0,
                             a_fs=0.5, b_fs=2.0)  # fmt: skip
        d["load"] = [{"type": "traction", "region": "x_max", "value": [1.0, 0.0, 0.0]}]
    d["material"].pop("incompressible", None)
    d["material"]["kappa"] = 100.0
    d["fem"] = {"order": 1}
    scene = scene_from_dict(scaled(exact_scene(d), LOAD / 10))
    s = scene.with_options(spring=replace(SpringOptions.of(scene), coupling=True))
    u_p1 = reference_fem.solve(s, order=1).u_vertices
    u = solve_spring(s).u
    assert np.linalg.norm(u - u_p1) / np.linalg.norm(u_p1) < 1e-4
