"""The locking-free switch of the default spring element and its stabilisation at nu -> 1/2.

A nearly incompressible scene (``nu >= 0.45``, ``kappa / mu >= 30`` or ``incompressible =
true``) that names no element gets nodal strain and nodal volume
(:data:`springmodel.options.LOCKING_FREE`, docs/studies.rst#the-default-spring-element); the
volume stabilisation scales as ``alpha mu / kappa``. Checked here: the rule, the overrides,
the eigenvalue count of the tangent on a gmsh organ mesh (Land's ventricle), and the
deflection against P2/P1 mixed (docs/volumetric.rst#stabilised-spring-against-nu).
"""

import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from springfem.errors import SceneError
from springfem.mechanics.modes import zero_modes
from springfem.scene import scene_from_dict
from springmodel.model import SpringModel
from springmodel.options import SpringOptions

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from support.meshes import ventricle_mesh  # noqa: E402

SCENES = Path(__file__).resolve().parents[2] / "studies" / "scenes"
BOX = {"generator": "box", "size": [2.0, 1.0, 1.0], "divisions": [2, 1, 1]}
GUCCIONE = {"law": "guccione", "C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0}


def options(material: dict, spring: dict | None = None) -> SpringOptions:
    data = {"mesh": BOX, "material": material}
    if spring is not None:
        data["spring"] = spring
    return SpringOptions.of(scene_from_dict(data))


def locking_free(o: SpringOptions) -> bool:
    return (o.volume_average, o.strain_average) == ("nodal", "nodal")


@pytest.mark.parametrize(
    ("material", "expected"),
    [
        ({"law": "linear", "E": 1.0, "nu": 0.3}, False),
        ({"law": "linear", "E": 1.0, "nu": 0.449}, False),
        ({"law": "neo-hookean", "E": 1.0, "nu": 0.45}, True),
        ({"law": "neo-hookean", "mu": 1.0, "kappa": 9.6}, False),  # nu = 0.449
        ({"law": "neo-hookean", "mu": 1.0, "kappa": 9.7}, True),  # nu = 0.450
        ({**GUCCIONE, "kappa": 99.0}, False),  # kappa / mu = 29.7 (mu = 10/3)
        ({**GUCCIONE, "kappa": 101.0}, True),  # kappa / mu = 30.3
        ({**GUCCIONE, "incompressible": True}, True),
    ],
)
def test_the_switch_follows_the_material(material, expected):
    """The rule's thresholds, on both sides (Guccione's mean shear modulus here is 10/3:
    the mean of its small-strain tangent's shear diagonal, C (b_fs, b_fs, b_t) / 2)."""
    o = options(material)
    assert locking_free(o) is expected
    assert o.element == ("tissue" if material["law"] == "guccione" else "exact")


def test_keys_override_the_switch():
    nearly = {"law": "neo-hookean", "E": 1.0, "nu": 0.49}
    assert not locking_free(options(nearly, {"locking_free": False}))
    part = options(nearly, {"element": "auto", "strain_average": "element"})
    assert (part.volume_average, part.strain_average) == ("nodal", "element")
    # a named element is the element as defined; the key adds the switch to it
    assert not locking_free(options(nearly, {"element": "exact"}))
    assert locking_free(options({"law": "linear", "E": 1.0, "nu": 0.3},
                                {"element": "exact", "locking_free": True}))  # fmt: skip
    # parts set one by one build on the seed's element, which has no nodal form
    assert options(nearly, {"torsion": "energy"}).element == "seed"
    with pytest.raises(SceneError, match="spring.locking_free"):
        options(nearly, {"element": "seed", "locking_free": True})


def ventricle_scene(material: dict, boundary: bool):
    """Land's ventricle (a gmsh mesh, element size 3 mm: 361 nodes, 1,039 tets) with the
    default spring element of ``material``."""
    data = tomllib.loads((SCENES / "land-ventricle.toml").read_text())
    data["mesh"] = ventricle_mesh(3.0)
    data["material"] = material
    data.pop("spring")
    data.pop("load")
    if not boundary:
        data.pop("boundary")
    return scene_from_dict(data, path=SCENES / "land-ventricle.toml")


ORGAN_LAWS = {
    "neo-hookean nu 0.4999": {"law": "neo-hookean", "E": 3.0, "nu": 0.4999},
    "incompressible Guccione": {**GUCCIONE, "incompressible": True},
}


@pytest.mark.parametrize("law", list(ORGAN_LAWS))
def test_no_spurious_modes_on_a_gmsh_organ_mesh(law):
    """The default (locking-free) element's tangent at rest on the gmsh ventricle: exactly
    six near-zero eigenvalues free (the rigid motions), none clamped at the base, none
    negative. Threshold 1e-10 of the largest: the stiffest mode carries ``kappa`` (5,000 mu
    at nu = 0.4999), the softest physical mode of the clamped shell lies above it, and a
    spurious mode sits at round-off (1e-16)."""
    free_scene = ventricle_scene(ORGAN_LAWS[law], boundary=False)
    model = SpringModel(free_scene)
    assert locking_free(model.options)
    K = model.stiffness(model.x0, scale=0.0).toarray()
    modes = zero_modes(K, rtol=1e-10)
    assert modes.count == 6 and modes.negative == 0
    clamped = SpringModel(ventricle_scene(ORGAN_LAWS[law], boundary=True))
    Kc = clamped.stiffness(clamped.x0, scale=0.0).toarray()
    free = np.setdiff1d(np.arange(Kc.shape[0]), clamped.fixed_dofs)
    modes = zero_modes(Kc[np.ix_(free, free)], rtol=1e-10)
    assert modes.count == 0 and modes.negative == 0
