"""The one Newton with line search and the shared load-stepping rule: quadratic convergence
on a neo-Hookean FEM problem (agreeing with the FEM reference), for both models on a bent
cantilever, backtracking of rejected states, FEM residual locations, a cut-back on a failed
step, and the rule itself (halve, grow back to the nominal increment, give up)."""

from __future__ import annotations

import numpy as np
import pytest

from reference_fem import solve
from reference_fem.explicit import ExplicitFem
from reference_fem.newton import FemStep
from springfem.mechanics import static
from springfem.mechanics.newton import LoadStepping, NewtonSettings, RejectedState, newton
from springfem.scene import parse_scene

#: A clamped-slide cube stretched ~25 % by a traction: clearly nonlinear, 2x2x2 boxes.
STRETCH = """
name = "stretch-neo"
[mesh]
generator = "box"
size = [1.0, 1.0, 1.0]
divisions = [2, 2, 2]
[material]
law = "neo-hookean"
E = 1000.0
nu = 0.3
density = 1000.0
[[boundary]]
region = "x_min"
fix = ["x"]
[[boundary]]
region = { point = [0.0, 0.0, 0.0] }
fix = ["y", "z"]
[[boundary]]
region = { point = [0.0, 1.0, 0.0] }
fix = ["z"]
[[load]]
type = "traction"
region = "x_max"
value = [250.0, 0.0, 0.0]
"""


@pytest.fixture(scope="module")
def fem():
    scene = parse_scene(STRETCH)
    return scene, ExplicitFem(scene)


def test_newton_converges_quadratically_on_neo_hookean(fem):
    """Core Newton on the P1 neo-Hookean system (coloured FD tangent: central differences,
    ~1e-9 relative error, so quadratic convergence shows until r ~ 1e-8). Its equilibrium
    equals the FEM reference's Newton (independent assembly) to both tolerances."""
    scene, system = fem
    info = static(system, tol=1e-11)
    h = info.residual_history
    assert info.converged and info.load_steps == [1.0] and info.cutbacks == 0
    pairs = [(a, b) for a, b in zip(h, h[1:], strict=False) if 1e-8 < a < 1e-1]
    assert len(pairs) >= 2, h
    for a, b in pairs:  # r_k+1 <= C r_k^2; a linear rate 0.1 would give b / a^2 >= 10
        assert b <= 1.0 * a**2, h
    u = info.x - system.x0
    ref = solve(scene, order=1, law="neo-hookean/coupled").u_vertices
    assert np.abs(u).max() > 0.2  # really nonlinear
    assert np.linalg.norm(u - ref) <= 1e-8 * np.linalg.norm(ref)


def test_failed_step_is_cut_back_and_reaches_the_same_equilibrium(fem):
    """With 3 iterations allowed the full load step (4 iterations) fails; halved steps
    converge, and the answer is the one-step equilibrium (both at tolerance 1e-11, FD-tangent
    floor 1e-9). (2 iterations also work but need ~260 cut-backs: 1.7 s instead of 0.1 s.)"""
    _, system = fem
    ref = static(system, tol=1e-11)
    cut = static(system, tol=1e-11, max_iter=3, fallback=False)
    assert cut.converged and cut.cutbacks >= 1 and len(cut.load_steps) >= 2
    assert cut.load_steps[-1] == 1.0 and all(np.diff(cut.load_steps) > 0)
    u = ref.x - system.x0
    assert np.linalg.norm(cut.x - ref.x) <= 1e-8 * np.linalg.norm(u)


def test_load_stepping_rule_halves_and_grows_back():
    """Steps larger than 0.3 fail: the rule halves after each failure and grows (x2) after
    an easy step, never beyond the nominal increment."""
    tried: list[tuple[float, float, bool]] = []

    def try_step(a, b):
        ok = b - a <= 0.3 + 1e-12
        tried.append((a, b, ok))
        return ok, 2, "" if ok else "too big"

    path = LoadStepping(load_steps=1).run(try_step)
    assert path.converged and path.load == 1.0 and path.steps[-1] == 1.0
    assert all(b - a <= 0.3 + 1e-12 for a, b, ok in tried if ok)
    assert path.cutbacks == sum(not ok for *_, ok in tried) >= 2
    for (a0, b0, ok0), (a1, b1, _) in zip(tried, tried[1:], strict=False):
        if not ok0:  # the retry starts from the same state with half the increment
            assert a1 == a0 and b1 - a1 == pytest.approx(0.5 * (b0 - a0))


def test_load_stepping_honours_nominal_steps_and_gives_up():
    path = LoadStepping(load_steps=3).run(lambda a, b: (True, 1, ""))
    assert path.steps == pytest.approx([1 / 3, 2 / 3, 1.0]) and path.cutbacks == 0
    failed = LoadStepping(load_steps=1, max_cutbacks=3).run(lambda a, b: (False, 5, "no"))
    assert not failed.converged and failed.steps == [] and failed.reason == "no"
    # halvings in a row: 1, 1/2, 1/4, 1/8 tried; the fourth cut exceeds max_cutbacks
    assert failed.cutbacks == 4 and failed.failed_at == pytest.approx(1 / 8)


#: A cantilever bent by a tip shear to ~25 % of its length (clearly nonlinear): the spring
#: model (energy-consistent torsion, analytic Hessian) and the P1 neo-Hookean FEM.
BEND = {
    "name": "bend",
    "mesh": {"generator": "box", "size": [0.1, 0.02, 0.02], "divisions": [6, 2, 2]},
    "material": {"law": "neo-hookean", "E": 1.0e4, "nu": 0.3},
    "axes": {"fiber": [1.0, 0.0, 0.0], "sheet": [0.0, 1.0, 0.0]},
    "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
    "load": [{"type": "traction", "region": "x_max", "value": [0.0, 0.0, -60.0]}],
    "spring": {"torsion": "energy", "tol": 1e-12},
    "fem": {"tol": 1e-12},
}


def assert_quadratic(history: list[float]) -> None:
    """``r_k+1 <= 100 r_k^2`` on the pairs with ``r_k < 0.05`` (the quadratic phase) and
    ``r_k+1`` above roundoff (1e-12 relative), at least one of them with ``r_k <= 1e-3``: a
    linear rate rho there gives ``r_k+1 / r_k^2 = rho / r_k >= 1000 rho``, so any rate above
    0.1 fails (Newton's constant in these relative units is O(1) to O(10) here)."""
    pairs = [(a, b) for a, b in zip(history, history[1:], strict=False) if a < 0.05 and b > 1e-12]
    assert len(pairs) >= 2 and min(a for a, _ in pairs) <= 1e-3, history
    assert all(b <= 100.0 * a * a for a, b in pairs), history


def test_one_newton_converges_quadratically_for_both_models():
    """Both models run :func:`springfem.mechanics.newton.newton` (the spring static solve
    and the FEM's load steps): quadratic on a bending problem, one load step each."""
    from springfem.scene import scene_from_dict
    from springmodel.model import solve_spring

    scene = scene_from_dict(BEND)
    spring = solve_spring(scene, parallel=False)
    assert spring.result.converged and spring.info.load_steps == [1.0]
    assert np.abs(spring.u).max() > 0.02
    assert_quadratic(spring.info.residual_history)
    fem = solve(scene, order=1)
    steps = fem.result.info["newton"]
    assert len(steps) == 1 and np.abs(fem.u_vertices).max() > 0.02
    assert_quadratic(steps[0]["residuals"])


class Quartic:
    """``E(u) = u^4/4 - u`` (root ``u = 1``); states with ``|u| > 10`` are rejected."""

    def residual(self, u):
        if abs(u[0]) > 10.0:
            raise RejectedState(f"|u| = {abs(u[0]):.3g} > 10")
        R = u**3 - 1.0
        return R, float(abs(R[0]))

    def correction(self, u, R):
        def resolve(b):
            return -b / (3.0 * u**2)

        return resolve(R), resolve

    def trial(self, u, alpha, d):
        return u + alpha * d

    def energy(self, u):
        return float(u[0] ** 4 / 4 - u[0])

    def constrained(self, u):
        return True

    def locate(self, R):
        return ""


def test_rejected_trials_are_backtracked_and_a_rejected_start_fails():
    """From u = 0.1 the full Newton step lands at u ~ 33 (rejected): the line search halves
    it until accepted and Newton still reaches the root; a rejected start fails the step
    with the problem's reason."""
    alphas = []
    out = newton(
        Quartic(), np.array([0.1]), NewtonSettings(tol=1e-14, max_iter=50),
        lambda it, u, r, alpha: alphas.append(alpha),
    )  # fmt: skip
    assert out.converged and out.state[0] == pytest.approx(1.0, abs=1e-13)
    assert alphas[1] <= 0.25  # 0.1 + alpha * 33.3 <= 10 needs alpha <= 0.3
    failed = newton(Quartic(), np.array([20.0]), NewtonSettings())
    assert not failed.converged and failed.reason == "|u| = 20 > 10"


def test_fem_step_locates_the_largest_free_residual():
    """The failure message names the FE node and component of the largest free residual
    (DOF ``3 node + component``), or the first non-finite one."""

    class Stub:
        free = np.array([False, True, True, True, False, True, True, True, True])
        fixed_dofs = np.array([0, 4])
        fixed_values = np.zeros(2)

    step = FemStep(Stub(), 1.0)
    R = np.array([9.0, 0.1, 0.2, 0.3, 9.0, -5.0, 0.1, 0.0, 0.4])  # fixed DOFs ignored
    assert step.locate(R) == "; largest residual at FE node 1, component z"
    R[7] = np.nan
    assert step.locate(R) == " at FE node 2"
