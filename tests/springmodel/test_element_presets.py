"""``[spring] element``: a named element, and a new scene's default from its law.

The independent check is the FEM package: with no ``[spring]`` section a scene gets the
exact element, whose small-strain solve is scikit-fem's linear P1 solve on the same mesh
(docs/theory.rst#the-exact-element-is-the-p1-element), on a jittered Delaunay block, for an
isotropic and a transversely isotropic law. The same scene with ``element = "seed"`` is
percent-level off, so the check can fail.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import meshio
import numpy as np
import pytest

import reference_fem
from springfem.errors import SceneError
from springfem.scene import load_scene, scene_from_dict
from springmodel.model import solve_spring
from springmodel.options import GREEN_AXIAL_COEFFICIENTS, SpringOptions

from .test_exact_scenes import jittered_delaunay_box

SCENES = Path(__file__).resolve().parents[2] / "studies" / "scenes"
LINEAR = {"law": "linear", "E": 1.0e4, "nu": 0.3}
TRANSVERSE = {
    "law": "transverse-linear",
    "E_fiber": 3.0e4, "E_cross": 1.0e4, "nu_fiber_cross": 0.3, "nu_cross": 0.35,
    "G_fiber": 4.0e3,
}  # fmt: skip
GUCCIONE = {"law": "guccione", "C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0, "kappa": 100.0}


def _box(material: dict, spring: dict | None = None) -> dict:
    d = {
        "mesh": {"generator": "box", "size": [1.0, 1.0, 1.0], "divisions": [1, 1, 1]},
        "material": dict(material),
        "axes": {"type": "uniform", "fiber": [1.0, 1.0, 0.0]},
    }
    if spring is not None:
        d["spring"] = spring
    return d


def _options(material: dict, spring: dict | None = None) -> SpringOptions:
    return SpringOptions.of(scene_from_dict(_box(material, spring)))


@pytest.mark.parametrize(
    ("material", "expected"),
    [(LINEAR, "exact"), ({**LINEAR, "law": "neo-hookean"}, "exact"), (GUCCIONE, "tissue")],
)
def test_the_default_element_follows_the_law(material, expected):
    o = _options(material)
    assert o.element == expected and o.volume == "axes" and o.calibration == "exact"
    if expected == "exact":
        assert (o.torsion, o.coupling, o.stiffening) == ("energy", False, "off")
    else:  # the tissue element, with the coupling springs of an anisotropic law
        assert (o.torsion, o.stiffening, o.coupling) == ("green", "law", True)
        assert (o.axial, o.axial_coefficients) == ("cubic", GREEN_AXIAL_COEFFICIENTS)


def test_solver_keys_alone_keep_the_default_element():
    o = _options(LINEAR, {"solver": "explicit", "dt_safety": 0.4})
    assert (o.element, o.volume, o.solver) == ("exact", "axes", "explicit")


def test_parts_alone_build_on_the_specifications_element():
    o = _options(LINEAR, {"torsion": "energy"})
    assert o.element == "seed" and o.volume is True and o.calibration == "analytic"
    assert o == SpringOptions(torsion="energy")


def test_a_named_element_keeps_its_other_parts_when_one_is_overridden():
    o = _options(GUCCIONE, {"element": "tissue", "volume_average": "nodal"})
    assert (o.torsion, o.stiffening, o.volume_average) == ("green", "law", "nodal")
    o = _options(LINEAR, {"element": "exact", "calibration": "nnls"})
    assert (o.volume, o.torsion, o.calibration) == ("axes", "energy", "nnls")
    # an own axial law drops the element's Green coefficients
    o = _options(LINEAR, {"element": "stiffened", "stiffening_modulus": 1e3, "axial": "linear"})
    assert (o.axial, o.axial_coefficients, o.torsion) == ("linear", (0.0, 0.0), "shear")


def test_seed_is_one_key_away():
    assert _options(LINEAR, {"element": "seed"}) == SpringOptions()
    assert _options(GUCCIONE, {"element": "seed"}) == SpringOptions()  # no coupling either


@pytest.mark.parametrize(
    ("material", "spring", "words"),
    [
        (LINEAR, {"element": "tissue"}, 'spring.element: "tissue" needs a tissue law'),
        (LINEAR, {"element": "stiffened"}, 'spring.element: "stiffened" needs stiffening_mod'),
        (LINEAR, {"element": "exakt"}, "spring.element"),
        (LINEAR, {"element": "exact", "volume_average": "nodal", "volume": True}, "volume_aver"),
    ],
)
def test_errors_name_the_key(material, spring, words):
    with pytest.raises(SceneError) as err:
        _options(material, spring)
    assert words in str(err.value) and "\n" not in str(err.value)


def test_misspelt_element_gets_a_suggestion():
    with pytest.raises(SceneError, match="exact"):
        _options(LINEAR, {"element": "exakt"})


@pytest.mark.parametrize("material", [LINEAR, TRANSVERSE])
def test_a_scene_without_spring_section_is_linear_p1(tmp_path, material):
    P, T = jittered_delaunay_box((0.1, 0.02, 0.02), (10, 3, 3), seed=3)
    path = tmp_path / "delaunay.vtu"
    meshio.write(path, meshio.Mesh(P, [("tetra", T)]))
    d = {
        "mesh": {"file": str(path)},
        "material": material,
        "axes": {"type": "uniform", "fiber": [1.0, 0.3, 0.2]},
        "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
        "load": [{"type": "traction", "region": "x_max", "value": [0.0, 0.0, -1.0]}],
        "spring": {"solver": "linear"},
    }
    scene = scene_from_dict(d)
    u_p1 = reference_fem.solve(scene, order=1, law=material["law"]).u_vertices

    def error(scene) -> float:
        return float(np.linalg.norm(solve_spring(scene).u - u_p1) / np.linalg.norm(u_p1))

    assert error(scene) < 1e-8
    assert error(scene_from_dict({**d, "spring": {"solver": "linear", "element": "seed"}})) > 0.02


def test_the_bundled_tissue_scenes_take_the_default_element():
    # Land's beam and ventricles: the tissue element with the locking-free switch
    # (incompressible Guccione), the ventricles with their larger volume stabilisation
    for name, beta in [("land-beam", None), ("land-ventricle", 3e-3),
                       ("land-ventricle-fibres", 3e-3)]:  # fmt: skip
        o = SpringOptions.of(load_scene(SCENES / f"{name}.toml"))
        assert (o.element, o.stiffening, o.torsion) == ("tissue", "law", "green")
        assert (o.volume_average, o.strain_average, o.volume_stabilisation) == (
            "nodal", "nodal", beta
        )  # fmt: skip


@pytest.mark.parametrize("name", ["cantilever", "cook-membrane", "land-ventricle-active"])
def test_bundled_scenes_measured_with_the_seed_name_it(name):
    # the report measured these with the specification's element: their options are
    # unchanged by the new default
    d = tomllib.loads((SCENES / f"{name}.toml").read_text())
    assert d["spring"] == {"element": "seed"}
    assert SpringOptions.of(load_scene(SCENES / f"{name}.toml")) == SpringOptions()
