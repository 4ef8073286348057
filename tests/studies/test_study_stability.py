"""Stability study case functions on tiny meshes, against the linear stability bound."""

import pytest

from studies.study_stability import critical_step_case, load_case, locking_case


@pytest.mark.parametrize("method", ["spring-energy", "fem-linear", "spring-exact"])
def test_measured_critical_step_matches_prediction(method):
    """Symplectic Euler on a (nearly) linear system is stable iff omega_max dt < 2: the
    bisection must land within its resolution (1.5/2^4 ≈ 0.09) plus a margin for the
    finite run length (a marginally unstable mode needs many steps to grow)."""
    r = critical_step_case({"method": method, "nx": 6, "ny": 1, "steps": 600, "bisections": 4})
    assert 0.85 <= r["ratio"] <= 1.15


def test_linear_fem_load_response_is_linear_and_flags_nothing_at_small_load():
    """Linear FEM: the tip deflection is proportional to the load (an invariant of the
    linear solve), and a small load leaves every element positively oriented."""
    small = load_case({"method": "fem-linear", "factor": 1, "nx": 10, "ny": 1})
    big = load_case({"method": "fem-linear", "factor": 1000, "nx": 10, "ny": 1})
    assert small["status"] == "ok"
    assert big["tip"] == pytest.approx(1000 * small["tip"], rel=1e-8)


def test_p1_locks_and_p2_does_not():
    p1 = locking_case({"method": "fem-p1", "nu": 0.499, "nx": 10, "ny": 1})
    p2 = locking_case({"method": "fem-p2", "nu": 0.499, "nx": 10, "ny": 1})
    # a 10x1x1 P1 bar at nu = 0.499 keeps a small fraction of the beam-theory deflection
    assert p1["tip_ratio"] < 0.5 * p2["tip_ratio"]
    assert p2["tip_ratio"] > 0.7


def test_exact_spring_element_locks_like_p1():
    """The exact element's small-strain stiffness is the P1 element's on any tet (DESIGN
    §4b), so near incompressibility it locks exactly as P1 does: tip ratios equal to the
    finite-strain kinematics (relative O(w/L), here far below 1e-2 on the locked bar)."""
    p1 = locking_case({"method": "fem-p1", "nu": 0.499, "nx": 10, "ny": 1})
    ex = locking_case({"method": "spring-exact", "nu": 0.499, "nx": 10, "ny": 1})
    assert ex["tip_ratio"] == pytest.approx(p1["tip_ratio"], rel=1e-2)
