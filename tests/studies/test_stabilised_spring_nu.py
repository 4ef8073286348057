"""The stabilised spring element (exact element, nodal strain + nodal volume at their default
stabilisations: ``spring-stabilised`` of the locking study) holds as nu -> 1/2.

Its volume stabilisation scales as ``alpha mu / kappa`` (docs/volumetric.rst
#stabilised-spring-against-nu); a fixed share of ``kappa`` locked: Land's beam (30x3x3) at
nu = 0.4999 came out 9.7 % short of P2/P1 mixed. The reference is P2/P1 mixed (Taylor–Hood)
on the same mesh, solved here; the scenes are the locking study's (the shear modulus held,
nu setting the bulk modulus: :func:`studies.study_locking.cases.with_nu`).
"""

import pytest

from studies import models
from studies.scenes import StudyScene
from studies.study_locking.cases import METHODS, with_nu

#: The issue's tolerance against P2/P1 mixed.
TOLERANCE = 0.05


def cook(divisions, nu):
    base = StudyScene.bundled("cook-membrane", {"mesh.divisions": list(divisions),
                                                "material.nu": 0.4999})  # fmt: skip
    return with_nu(base, nu).build()


def beam(divisions, nu):
    return with_nu(StudyScene.bundled("land-beam", {"mesh.divisions": list(divisions)}), nu).build()


def deflection(scene, method: str, probe: str, component: int) -> float:
    out = models.run(scene, METHODS[method])
    assert out.solved, out.message
    return out.solution.result.probes[probe][component]


def test_the_spring_does_not_lock_between_nu_0499_and_04999_on_a_coarse_cook_membrane():
    """Cheap: Cook's membrane 8x8x1 (384 tets). From nu = 0.499 to 0.4999 (kappa x 10)
    P2/P1 mixed moves 0.07 % (3.051 -> 3.049 mm); the stabilised spring measured 2.0 %
    (2.472 -> 2.423 mm: the nodal volumes' own coarse-mesh locking, which the FEM's
    nodal-volume P1 shows too, docs/fem.rst#nodal-volume-measurements), and with the former
    fixed share 3e-4 of kappa 10 % (2.500 -> 2.249). Tolerance 3 % on the ratio."""
    ratio = {}
    for method in ("spring-stabilised", "P2-mixed"):
        u = [deflection(cook((8, 8, 1), nu), method, "corner", 1) for nu in (0.499, 0.4999)]
        ratio[method] = u[1] / u[0]
    assert ratio["P2-mixed"] == pytest.approx(1.0, abs=0.005)  # the reference does not lock
    assert ratio["spring-stabilised"] == pytest.approx(ratio["P2-mixed"], abs=0.03)


@pytest.mark.slow
def test_within_five_percent_of_p2p1_on_lands_beam_at_nu_04999():
    """Land's beam 30x3x3 (1,620 tets): measured -3.1 % (3.056 mm against 3.155 mm)."""
    ref = deflection(beam((30, 3, 3), 0.4999), "P2-mixed", "tip", 2)
    got = deflection(beam((30, 3, 3), 0.4999), "spring-stabilised", "tip", 2)
    assert got == pytest.approx(ref, rel=TOLERANCE)


@pytest.mark.slow
def test_within_five_percent_of_p2p1_on_cooks_membrane_32x32_at_nu_04999():
    """Cook's membrane 32x32x2 (12,288 tets): measured in
    docs/volumetric.rst#stabilised-spring-against-nu."""
    ref = deflection(cook((32, 32, 2), 0.4999), "P2-mixed", "corner", 1)
    got = deflection(cook((32, 32, 2), 0.4999), "spring-stabilised", "corner", 1)
    assert got == pytest.approx(ref, rel=TOLERANCE)
