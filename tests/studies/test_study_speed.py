"""The speed studies (speed_accuracy, scaling); ``springfem bench`` is in test_bench.py.

No timing assertions (DESIGN §8): the benchmarks must run and print their rows, the kernels
they time must agree with their references, and the studies' solves must agree with each
other where they solve the same problem.
"""

from __future__ import annotations

import numpy as np
import pytest

from springfem.scene import scene_from_dict
from studies import study_speed_accuracy as sa


def test_pareto_front_matches_sweep():
    """Non-dominated points == a sweep in time order keeping each new best error."""
    rng = np.random.default_rng(0)
    t, e = rng.random(60), rng.random(60)
    order = np.argsort(t)
    sweep = np.zeros(60, dtype=bool)
    best = np.inf
    for i in order:
        if e[i] < best:
            sweep[i], best = True, e[i]
    assert np.array_equal(sa.pareto_front(t, e), sweep)


def test_cantilever_variants():
    scene = scene_from_dict(sa.cantilever_table(6, 1))
    assert scene.mesh.n_tets == 6 * 6
    assert sa.timoshenko_tip(scene) == pytest.approx(4.0306e-4, rel=1e-4)


@pytest.mark.parametrize(
    ("explicit_method", "static_method"),
    [
        ("fem-explicit-p1-neo-hookean", "fem-p1-neo-hookean"),
        ("spring-explicit", "spring-static"),
        ("spring-exact-explicit", "spring-exact-static"),
    ],
)
def test_explicit_points_reach_the_static_answer(explicit_method, static_method):
    """Dynamic relaxation to 1e-6 relative residual lands on the static solution of the
    same model: the tips agree to 1e-3 (the residual tolerance times the conditioning of
    this slender beam)."""
    case = {"scene": sa.cantilever_table(10, 1), "torsion": sa.TORSION}
    a = sa.point_case(
        {**case, "method": explicit_method, "setting": {"tol": 1e-6, "dt_safety": 0.5}}
    )
    b = sa.point_case({**case, "method": static_method, "setting": {}})
    assert a["status"] == b["status"] == "ok"
    ta, tb = np.asarray(a["tip"]), np.asarray(b["tip"])
    assert np.linalg.norm(ta - tb) < 1e-3 * np.linalg.norm(tb)


def test_spring_and_fem_differ_on_the_same_mesh():
    """The study's spring and P1 points are different models: on 10x1x1 the spring tip is
    larger than P1's by more than the solver tolerances (DESIGN §4: ~8-25 % softer)."""
    case = {"scene": sa.cantilever_table(10, 1), "torsion": sa.TORSION, "setting": {}}
    spring = sa.point_case({**case, "method": "spring-static"})
    p1 = sa.point_case({**case, "method": "fem-p1-linear"})
    assert abs(spring["tip"][2]) > 1.05 * abs(p1["tip"][2])


def test_exact_point_is_p1_on_the_same_mesh():
    """The exact element's small-strain stiffness is P1's (DESIGN §4b): on 10x1x1 its tip
    equals P1's up to the finite-strain kinematics, O(tip rotation w/L = 4e-3)."""
    case = {"scene": sa.cantilever_table(10, 1), "torsion": sa.TORSION, "setting": {}}
    exact = sa.point_case({**case, "method": "spring-exact-static"})
    p1 = sa.point_case({**case, "method": "fem-p1-linear"})
    assert exact["tip"][2] == pytest.approx(p1["tip"][2], rel=4e-3)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["speed_accuracy", "scaling"])
def test_quick_study_runs(tmp_path, name):
    from studies.runner import run_study

    res = run_study(name, tmp_path, quick=True, progress=False)
    assert res.findings and res.figures and res.headline
    for fig in res.figures:
        assert fig.path.is_file()
    assert all(np.isfinite(v) for v in res.headline.values())
