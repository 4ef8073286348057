"""Stability study case functions on tiny meshes, against the linear stability bound, the
linearity of small-strain FEM and beam theory."""

import pytest

from studies import models
from studies.study_stability.cases import (
    VERSION,
    bar,
    critical_step_case,
    grids,
    load_case,
    locking_case,
    series_methods,
)
from studies.study_stability.cases import Settings as StabilitySettings


def _case(kind: str, **kw) -> dict:
    s = bar(10, 1, ("dt", "load", "lock", "map"))
    if "nu" in kw:
        s = s.with_sets({"material.nu": kw["nu"]})
    return s.case("stability-test", VERSION, kind=kind, **kw)


@pytest.mark.parametrize("method", ["spring-energy", "P1", "spring-exact"])
def test_measured_critical_step_matches_prediction(method):
    """Symplectic Euler on a (nearly) linear system is stable iff omega_max dt < 2: the
    bisection must land within its resolution (1.5/2^4 ≈ 0.09) plus a margin for the
    finite run length (a marginally unstable mode needs many steps to grow)."""
    r = critical_step_case(_case("dt", method=method, steps=600, bisections=4))
    assert 0.85 <= r["ratio"] <= 1.15


def test_linear_fem_load_response_is_linear_and_flags_nothing_at_small_load():
    """Linear FEM: the largest displacement is proportional to the load (an invariant of
    the linear solve), a small load leaves every element positively oriented, and a load
    whose solution leaves small-strain kinematics is flagged ``unphysical``."""
    small = load_case(_case("load", method="P1", factor=1))
    big = load_case(_case("load", method="P1", factor=1000))
    assert small["status"] == "ok"
    assert big["u/size"] == pytest.approx(1000 * small["u/size"], rel=1e-8)
    assert big["status"] == "unphysical"  # 1000 x 4e-3 of the length


def test_p1_locks_and_p2_does_not():
    p1 = locking_case(_case("lock", method="P1", nu=0.499))
    p2 = locking_case(_case("lock", method="P2", nu=0.499))
    # a 10x1x1 P1 bar at nu = 0.499 keeps a small fraction of the beam-theory deflection
    assert p1["tip_ratio"] < 0.5 * p2["tip_ratio"]
    assert p2["tip_ratio"] > 0.7


def test_exact_spring_element_locks_like_p1():
    """The exact element's small-strain stiffness is the P1 element's on any tet, so near
    incompressibility it locks exactly as P1 does: tip ratios equal to the finite-strain
    kinematics (relative O(w/L), here far below 1e-2 on the locked bar)."""
    p1 = locking_case(_case("lock", method="P1", nu=0.499))
    ex = locking_case(_case("lock", method="spring-exact", nu=0.499))
    assert ex["tip_ratio"] == pytest.approx(p1["tip_ratio"], rel=1e-2)


def test_series_follow_the_scene_roles_and_the_law():
    """A bundled bar serves only the series it lists; a user scene (no roles) serves all
    but the locking series, which needs the beam-theory reference; an anisotropic law has no
    explicit FEM, so its explicit series run the spring variants alone."""
    q = StabilitySettings.quick()
    b = bar(10, 1, ("load",))
    g = grids([b], q)
    assert not g["dt"] and not g["lock"] and not g["map"]
    # the series' own methods, the default plug-in models (co-rotational P1) and XPBD's
    # Jacobi variant
    peers = models.plugins(b.build())
    assert "corotational" in peers
    assert len(g["load"]) == (len(series_methods("linear")["load"]) + len(peers) + 1) * len(
        q.load_factors
    )
    user = type(b)("user", b.table)  # no roles, no closed-form reference
    g = grids([user], q)
    assert g["dt"] and g["load"] and g["map"] and not g["lock"]
    assert "P1" not in series_methods("transverse-linear")["dt"]
    assert series_methods("transverse-linear")["load"][-1] == "P1"
