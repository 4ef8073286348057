"""Newton with line search and the shared load-stepping rule: quadratic convergence on a
neo-Hookean FEM problem (agreeing with the FEM reference's own Newton), a cut-back on a
failed step, and the rule itself (halve, grow back to the nominal increment, give up)."""

from __future__ import annotations

import numpy as np
import pytest

from reference_fem import solve
from reference_fem.explicit import ExplicitFem
from springfem.mechanics import static
from springfem.mechanics.newton import LoadStepping
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
    """With 2 iterations allowed the full load step fails; halved steps converge, and the
    answer is the one-step equilibrium (both at tolerance 1e-11, FD-tangent floor 1e-9)."""
    _, system = fem
    ref = static(system, tol=1e-11)
    cut = static(system, tol=1e-11, max_iter=2, fallback=False)
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
