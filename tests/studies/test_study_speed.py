"""The speed studies (speed_accuracy, scaling); ``springfem bench`` is in test_bench.py.

No timing assertions: the benchmarks must run and print their rows, the kernels they time
must agree with their references, and the studies' solves must agree with each other where
they solve the same problem.
"""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import numpy as np
import pandas as pd
import pytest

from studies import study_speed_accuracy as sa
from studies.cache import CaseCache
from studies.registry import StudyContext
from studies.scenes import StudyScene
from studies.study_speed_accuracy.cases import point_case

# the study's quick run takes tens of seconds: -m slow
pytestmark = pytest.mark.slow

BAR = sa.bundled_scenes(sa.Settings.quick())[0]


def point(model: str, solution: str, factor: int = 1, **setting):
    return sa.point_work(point_case(BAR, model, solution, factor, setting))


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


def test_bundled_levels_are_the_cantilever_meshes():
    """Levels 1, 2, 4 and the reference 6 of the [10, 1, 1] bar are the bar's 10x1x1,
    20x2x2, 40x4x4 and 60x6x6 hexahedra (six tets each)."""
    from studies.study_convergence.levels import level_label, refined_scene

    full = sa.Settings.full()
    labels = [level_label(BAR.table, k) for k in (*full.levels, full.reference)]
    assert labels == ["10x1x1", "20x2x2", "40x4x4", "60x6x6"]
    assert refined_scene(BAR.table, None, 2).mesh.n_tets == 6 * 20 * 2 * 2


@pytest.mark.parametrize(
    ("model", "setting"),
    [("P1-NH", {}), ("spring-energy", {"tol": 1e-8}), ("spring-exact", {"tol": 1e-8})],
)
def test_explicit_points_reach_the_static_answer(model, setting):
    """Dynamic relaxation to 1e-6 relative residual lands on the static solution of the same
    model: the tips agree to 1e-3 (the residual tolerance times the conditioning of this
    slender beam)."""
    a = point(model, "explicit", tol=1e-6, dt_safety=0.5)
    b = point(model, "static", **setting)
    assert a["status"] == b["status"] == "ok"
    ta, tb = np.asarray(a["probes"]["tip"]), np.asarray(b["probes"]["tip"])
    assert np.linalg.norm(ta - tb) < 1e-3 * np.linalg.norm(tb)


def test_implicit_point_reaches_the_static_answer():
    """Backward Euler to rest (equilibrium tolerance 1e-6) lands on static Newton's answer."""
    a = point("spring-energy", "implicit", dt_factor=1e4, tol=1e-6)
    b = point("spring-energy", "static", tol=1e-8)
    assert a["status"] == "ok" and a["steps"] > 0
    ta, tb = np.asarray(a["probes"]["tip"]), np.asarray(b["probes"]["tip"])
    assert np.linalg.norm(ta - tb) < 1e-3 * np.linalg.norm(tb)


def test_spring_and_fem_differ_on_the_same_mesh():
    """The study's spring and P1 points are different models: on 10x1x1 the spring tip is
    larger than P1's by more than the solver tolerances (the specification's element is
    ~8-25 % softer in bending)."""
    spring = point("spring-energy", "static", tol=1e-8)
    p1 = point("P1", "static")
    assert abs(spring["probes"]["tip"][2]) > 1.05 * abs(p1["probes"]["tip"][2])


def test_exact_point_is_p1_on_the_same_mesh():
    """The exact element's small-strain stiffness is P1's: on 10x1x1 its tip equals P1's up
    to the finite-strain kinematics, O(tip rotation w/L = 4e-3)."""
    exact = point("spring-exact", "static", tol=1e-8)
    p1 = point("P1", "static")
    assert exact["probes"]["tip"][2] == pytest.approx(p1["probes"]["tip"][2], rel=4e-3)


# ----------------------------------------------------- a user's neo-Hookean gmsh scene

NEO_HOOKEAN = """
name = "nh-bar"
[mesh]
file = "bar.msh"
[material]
law = "neo-hookean"
E = 1.0e4
nu = 0.3
density = 1000.0
[[boundary]]
region = "x_min"
fix = ["x", "y", "z"]
[[load]]
type = "traction"
region = "x_max"
value = [0.0, 0.0, -0.1]
"""


@pytest.fixture(scope="module")
def neo_hookean(tmp_path_factory):
    """The quick study on a neo-Hookean gmsh bar (0.1 x 0.02 x 0.02, ~100 tets, no probe):
    the unconverted study stopped here with ``StopIteration`` (its P2-NH reference was
    computed on the costly levels only and looked up on the finest)."""
    from support.meshes import gmsh_box

    d = tmp_path_factory.mktemp("nh")
    gmsh_box(d / "bar.msh", 0.02)
    (d / "nh.toml").write_text(NEO_HOOKEAN)
    ctx = StudyContext("speed_accuracy", d / "out", True, CaseCache(d, "s"), False)
    out = sa.run(ctx, [StudyScene.from_file(d / "nh.toml")], sa.Settings.quick())
    return out, pd.read_csv(d / "out" / "points.csv")


def test_neo_hookean_scene_runs_against_p2_nh(neo_hookean):
    """The reference is P2-NH on the finest level (level 2: 8x the tets of the mesh file):
    its own point has error 0, P2-NH beats P1-NH on level 1, every point solves."""
    out, df = neo_hookean
    d = df[df["setting"].isna()].set_index(["method", "factor"])  # static points
    err = "L2 err (level-1 vertices)"
    assert d.at[("P2-NH static", 2), err] == 0.0
    assert d.at[("P1-NH static", 2), "tets"] == 8 * d.at[("P1-NH static", 1), "tets"]
    assert d.at[("P2-NH static", 1), err] < d.at[("P1-NH static", 1), err]
    assert d.at[("P1-NH static", 2), err] < d.at[("P1-NH static", 1), err]
    assert (df["status"] == "ok").all()
    assert out.headline["n_failed"] == 0 and "l2_error_P2_static_x2" in out.headline


def test_neo_hookean_explicit_fem_reaches_its_static_answer(neo_hookean):
    """The explicit P1 FEM is P1-NH: relaxed to rest it has P1-NH static's error (1e-3: the
    relaxation tolerance 1e-6 times the conditioning)."""
    _, df = neo_hookean
    d = df[~df["method"].str.endswith("implicit")].set_index(["method", "factor"])
    d = d["L2 err (level-1 vertices)"]
    for k in (1, 2):
        assert d[("P1-NH explicit", k)] == pytest.approx(d[("P1-NH static", k)], abs=1e-3)


@pytest.mark.parametrize("name", ["", *(m.name for m in pkgutil.iter_modules(sa.__path__))])
def test_doctests(name):
    module = importlib.import_module(f"studies.study_speed_accuracy{'.' if name else ''}{name}")
    assert doctest.testmod(module).failed == 0


@pytest.mark.slow
@pytest.mark.parametrize("name", ["speed_accuracy", "scaling"])
def test_quick_study_runs(tmp_path, name):
    from studies.runner import run_study

    res = run_study(name, tmp_path, quick=True, progress=False)
    assert res.findings and res.figures and res.headline
    for fig in res.figures:
        assert fig.path.is_file()
    assert all(np.isfinite(v) for v in res.headline.values())
