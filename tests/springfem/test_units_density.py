"""The default density follows the scene's ``units``, so an mm-MPa (or mm-kPa) scene has the
stable time step of the same body in SI units; a body whose size in metres is implausible
is warned about, naming the units and ``mesh.scale``.

The check is an invariance: one body (a 40 × 10 × 10 mm block of E = 3 MPa, ν = 0.3,
1000 kg/m³) written in three unit systems must have one stable step in seconds, and it must
be the order of the element size over the dilatational wave speed ``sqrt((λ + 2μ)/ρ)``.
"""

from __future__ import annotations

import numpy as np
import pytest

from springfem.mechanics import stable_time_step
from springfem.scene import default_density, scene_from_dict
from studies import models
from studies.guards import size_warning

E_PA, NU, SIZE_M = 3.0e6, 0.3, (0.04, 0.01, 0.01)
UNITS = {"SI": (1.0, 1.0), "mm-kPa": (1e3, 1e3), "mm-MPa": (1e3, 1e6)}  # length, stress


def _block(units: str, density: float | None = None) -> dict:
    length, stress = UNITS[units]
    material = {"law": "linear", "E": E_PA / stress, "nu": NU}
    if density is not None:
        material["density"] = density
    return {
        "units": units,
        "mesh": {"generator": "box", "size": [s * length for s in SIZE_M], "divisions": [8, 2, 2]},
        "material": material,
        "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
    }


def _stable_step(units: str, model: str = "P1", density: float | None = None) -> float:
    scene = scene_from_dict(_block(units, density))
    return float(stable_time_step(models.get(model).system(scene))[0])


@pytest.mark.parametrize("model", ["P1", "spring-exact"])
def test_the_stable_step_of_one_body_is_the_same_in_every_unit_system(model):
    si = _stable_step("SI", model)
    for units in ("mm-kPa", "mm-MPa"):
        assert _stable_step(units, model) == pytest.approx(si, rel=1e-9), units
    # and it is a CFL step: the element size over the dilatational wave speed, within the
    # geometry factor of a six-tet split (the shortest altitude is a fraction of the edge)
    lam_2mu = E_PA * (1 - NU) / ((1 + NU) * (1 - 2 * NU))
    h = 0.005  # edge of the 8 x 2 x 2 cells
    assert 0.05 < si / (h / np.sqrt(lam_2mu / 1000.0)) < 1.0


def test_an_mm_mpa_scene_without_a_density_gets_1e_9_tonnes_per_mm3():
    scene = scene_from_dict(_block("mm-MPa"))
    assert scene.material.density == pytest.approx(1000.0 / 1e12)  # t/mm^3
    assert default_density("mm-kPa") == pytest.approx(1e-6)  # kg/mm^3, forces in mN
    # the density left out and 1000 kg/m^3 given in the scene's units are the same scene
    assert _stable_step("mm-MPa") == pytest.approx(_stable_step("mm-MPa", density=1e-9))
    # the SI default in an mm-MPa scene would be 1e12 times too heavy: 1e6 times the step
    heavy = _stable_step("mm-MPa", density=1000.0)
    assert heavy / _stable_step("mm-MPa") == pytest.approx(1e6, rel=1e-9)


def test_a_body_of_implausible_size_is_warned_about_naming_units_and_mesh_scale():
    mm_as_si = scene_from_dict({**_block("mm-MPa"), "units": "SI"})  # 40 m long
    line = size_warning(mm_as_si)
    assert line is not None and "units" in line and "mesh.scale" in line
    assert "42.4 m across" in line  # the diagonal of 40 x 10 x 10: sqrt(1800)
    assert size_warning(scene_from_dict(_block("mm-MPa"))) is None
    tiny = _block("SI")
    tiny["mesh"]["size"] = [4e-5, 1e-5, 1e-5]  # 40 um: a block in mm read as metres / 1000
    assert "outside 0.1 mm" in size_warning(scene_from_dict(tiny))
