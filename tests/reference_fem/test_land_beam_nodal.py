"""Land et al. 2015, problem 1, with locking-free linear tets (nodal-volume P1).

The Taylor–Hood reference on the bundled 30x3x3 mesh gives deformed z = 4.155 mm
(``test_land_beam.py``); plain P1 with the scene's penalty locks at 1.149 mm. Measured here
with ``[fem] formulation = "nodal-volume"`` and the default share: 3.345 mm on 30x3x3 and
3.894 mm on 60x6x6 (docs/fem.rst#nodal-volume-measurements). What remains is P1's bending
error, not locking: it halves and more with each halving of h; ``formulation =
"nodal-strain"`` removes most of it on the bundled mesh.
"""

import tomllib
from pathlib import Path

import pytest

from reference_fem import solve
from springfem.scene import scene_from_dict

SCENE = Path(__file__).resolve().parents[2] / "studies" / "scenes" / "land-beam.toml"
#: Taylor–Hood P2/P1 on the bundled 30x3x3 mesh (test_land_beam.py's table).
REFERENCE = 4.155
#: The issue's target for a locking-free P1 option.
TARGET = 0.03


def deformed_z(divisions, fem) -> float:
    data = tomllib.loads(SCENE.read_text())
    data["mesh"]["divisions"] = list(divisions)
    data["fem"] = {"load_steps": 4, **fem}
    sol = solve(scene_from_dict(data, path=SCENE))
    assert sol.result.converged
    return 1.0 + sol.result.probes["tip"][2]


NODAL = {"order": 1, "formulation": "nodal-volume"}
NODAL_STRAIN = {"order": 1, "formulation": "nodal-strain"}


@pytest.mark.slow
def test_nodal_strain_tip_within_the_target_on_the_bundled_mesh():
    """The default blend: measured 4.035 mm (-2.9 %; docs/fem.rst#nodal-strain-tetrahedra)."""
    assert deformed_z((30, 3, 3), NODAL_STRAIN) == pytest.approx(REFERENCE, rel=TARGET)


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="measured 3.345 mm (-19.5 %): P1's bending error on 3 tets through the depth",
)
def test_nodal_volume_tip_within_the_target_on_the_bundled_mesh():
    assert deformed_z((30, 3, 3), NODAL) == pytest.approx(REFERENCE, rel=TARGET)


@pytest.mark.slow
def test_nodal_volume_converges_to_the_reference():
    """At least first order in h (P1's energy-norm rate); a locked P1 does not converge."""
    z = [deformed_z(d, NODAL) for d in [(30, 3, 3), (60, 6, 6)]]
    err = [REFERENCE - v for v in z]
    assert 0.0 < err[1] <= 0.5 * err[0]
