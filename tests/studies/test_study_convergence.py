"""Study ``convergence``: the bundled bar on tiny levels, a user's gmsh mesh with a
closed-form solution, refinement levels and Richardson extrapolation.

The bundled run uses levels 1, 2, 3 of the ``[10, 1, 1]`` bar (60 to 1620 tets) with the P2
reference on level 3, so the whole study (cases, tables, figures) runs in seconds.
"""

import doctest
import importlib
import json
import pkgutil

import numpy as np
import pandas as pd
import pytest

from studies import metrics
from studies import study_convergence as sc
from studies.analytic import reference
from studies.cache import CaseCache
from studies.registry import StudyContext
from studies.scenes import StudyScene
from studies.study_convergence.levels import coarse_index, refined_scene, select_levels

TINY = sc.Settings(levels=(1, 2, 3), p2_levels=(1, 2), ref=3, cosine_check_level=2)
L2 = "L2 err (level-1 vertices)"


def run_study(scenes, settings, root):
    ctx = StudyContext("convergence", root / "convergence", True, CaseCache(root, "c"), False)
    return sc.run(ctx, scenes, settings), ctx


@pytest.fixture(scope="module")
def output(tmp_path_factory):
    return run_study(sc.bundled_scenes(TINY), TINY, tmp_path_factory.mktemp("conv"))


def _levels(ctx, suffix=""):
    return pd.read_csv(ctx.out / f"convergence_levels{suffix}.csv")


def test_outputs_exist(output):
    out, _ = output
    for f in out.figures:
        assert f.path.read_bytes()[:4] == b"\x89PNG"
    for t in out.tables:
        assert t.path.is_file() and t.path.with_suffix(".csv").is_file()
    assert len(out.findings) >= 4
    json.dumps(out.headline)  # JSON-able


def test_errors_decrease_with_refinement(output):
    _, ctx = output
    df = _levels(ctx)
    assert (df["status"] == "ok").all()
    for model in ("spring-energy", "P1", "P2"):
        err = df[df["model"] == model].sort_values("factor")[L2].values
        assert np.all(np.diff(err) < 0), model


def test_levels_are_the_bar_refined(output):
    """Level k is the [10, 1, 1] bar on [10, 1, 1]·k hexahedra (6 k³ · 10 tets) and h is
    proportional to 1/k, as the rates need."""
    _, ctx = output
    d = _levels(ctx).set_index(["model", "factor"])
    for k in (1, 2, 3):
        assert d.at[("P1", k), "tets"] == 60 * k**3
        assert d.at[("P1", k), "mesh"] == f"{10 * k}x{k}x{k}"
        assert d.at[("P1", k), "h"] == pytest.approx(d.at[("P1", 1), "h"] / k, rel=1e-12)


def test_p2_rate_exceeds_p1_rate(output):
    """P2 converges faster than P1 (asymptotically 3 vs 2 in L2; on these pre-asymptotic
    bending meshes measured P2 > 2, P1 ~ 0.9): require a clear margin of 1."""
    out, _ = output
    h = out.headline
    assert h["rate_l2_P2"] > h["rate_l2_P1"] + 1.0
    assert h["rate_l2_P1"] > 0.5


def test_spring_p1_gap_closes(output):
    """The spring model is softer than P1 on the same mesh (measured +23 %, +16 %, +11 % at
    k = 1, 2, 3) and the gap shrinks with h."""
    out, ctx = output
    df = _levels(ctx)
    sp = df[df["model"] == "spring-energy"].sort_values("factor")["w"].values
    p1 = df[df["model"] == "P1"].sort_values("factor")["w"].values
    gap = sp / p1 - 1
    assert np.all(gap > 0) and np.all(np.diff(gap) < 0)
    assert out.headline["rate_spring-energy_P1_gap"] > 0.3
    assert out.headline["spring-energy_over_P1_finest"] == pytest.approx(1 + gap[-1], rel=1e-12)


def test_reference_close_to_timoshenko(output):
    """P2 on the 30x3x3 mesh is within 2 % of Timoshenko beam theory, computed here from the
    bar's data (F L³ / 3EI + F L / kGA, k = 10 (1 + nu) / (12 + 11 nu)); beam theory ignores
    the 3D clamping, so they need not agree better than ~1 %."""
    out, _ = output
    L, b, t, E, nu, traction = 0.1, 0.01, 0.01, 1.0e4, 0.3, 0.1
    F, inertia, G = traction * b * t, b * t**3 / 12, E / (2 * (1 + nu))
    w = F * L**3 / (3 * E * inertia) + F * L / (10 * (1 + nu) / (12 + 11 * nu) * G * b * t)
    s = sc.bundled_scenes(TINY)[0]
    assert reference(s, s.build())[2] == pytest.approx(-w, rel=1e-12)
    assert abs(out.headline["ref_over_timoshenko"] - 1) < 0.02


def test_cosine_and_energy_torsion_agree_in_small_strain(output):
    """Cosine (spec) and energy torsion linearise to the same shear stiffness on the bar's
    cubes, so in this small-strain bending their deflections differ only by the geometric
    nonlinearity of the torsion laws (measured 0.03 % at k = 4); require < 1 %."""
    out, _ = output
    assert any("spring-cosine" in f for f in out.findings)
    plan = sc.plan(sc.bundled_scenes(TINY)[0], TINY)
    cosine, energy = (sc.work(plan.case(m, 2)) for m in ("spring-cosine", "spring-energy"))
    assert cosine["probes"]["tip"][2] == pytest.approx(energy["probes"]["tip"][2], rel=0.01)


def test_richardson_limit_of_manufactured_sequences():
    """w = L + C h^p through three points, even and uneven ratios: the limit and the order."""
    for h in (np.array([0.3, 0.2, 0.1]), np.array([0.35, 0.29, 0.21])):
        for L0, C, p0 in ((1.0, -0.5, 2.0), (-26.5, 0.7, 1.3), (0.2, 3.0, 3.3)):
            L, p = sc.richardson_limit(h, L0 + C * h**p0)
            assert L == pytest.approx(L0, abs=1e-10) and p == pytest.approx(p0, abs=1e-8)
    L, p = sc.richardson_limit(np.array([0.3, 0.2, 0.1]), np.array([1.0, 2.0, 1.5]))
    assert np.isnan(L) and np.isnan(p)  # not monotone: no such fit
    assert np.isnan(sc.richardson_limit(np.array([0.2, 0.1]), np.array([1.0, 1.1]))[0])


# --------------------------------------------------------------------- refinement levels


def test_select_levels():
    """A box grid takes any factor, another mesh powers of two; the budget leaves out the
    fine levels but never the two coarsest."""
    box = {"mesh": {"generator": "box", "size": [1, 1, 1], "divisions": [2, 2, 2]}}
    assert select_levels(box, 48, (1, 2, 3, 4), 48 * 27) == ([1, 2, 3], [
        "levels 4 left out (over 1296 tets)"])  # fmt: skip
    jittered = {"mesh": {**box["mesh"], "split": "delaunay"}}
    assert select_levels(jittered, 48, (1, 2, 3, 4), 10**6)[0] == [1, 2, 4]
    assert select_levels(box, 10**6, (1, 2, 3), 10)[0] == [1, 2]


def test_refined_box_contains_the_level_one_vertices():
    bar = StudyScene.bundled("cantilever", {"mesh.divisions": [5, 1, 1]})
    coarse = bar.build().mesh.points
    fine = refined_scene(bar.table, None, 3).mesh
    assert fine.n_tets == 27 * 30
    idx = coarse_index(bar.case("test", 0, factor=3), fine)
    np.testing.assert_allclose(fine.points[idx], coarse, atol=1e-15)


# ---------------------------------------------------------- a user's gmsh mesh, exact solution

COLUMN = """
name = "column"
[mesh]
file = "column.msh"
[material]
law = "linear"
E = 1.0e4
nu = 0.0
density = 1000.0
[[boundary]]
region = "x_min"
fix = ["x", "y", "z"]
[[load]]
type = "gravity"
value = [0.1, 0.0, 0.0]
[[probe]]
name = "end"
point = [0.04, 0.005, 0.005]
"""
LENGTH, BODY_FORCE, E = 0.04, 1000.0 * 0.1, 1.0e4


def exact_column(points):
    """A column clamped at x = 0 under its weight along x, nu = 0: sigma_xx = f (L - x), the
    other stresses zero, so u_x = f / E (L x - x² / 2), u_y = u_z = 0 (every boundary
    condition holds: the clamp, free sides and a free end)."""
    u = np.zeros_like(points)
    x = points[:, 0]
    u[:, 0] = BODY_FORCE / E * (LENGTH * x - x**2 / 2)
    return u


@pytest.fixture(scope="module")
def column(tmp_path_factory):
    """The convergence study (quick) on a gmsh mesh of the column (173 tets, refined
    uniformly: levels 1, 2)."""
    gmsh = pytest.importorskip("gmsh")
    d = tmp_path_factory.mktemp("column")
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("column")
        gmsh.model.occ.addBox(0, 0, 0, LENGTH, 0.01, 0.01)
        gmsh.model.occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMin", 0.006)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.006)
        gmsh.model.addPhysicalGroup(3, [1], name="body")
        gmsh.model.mesh.generate(3)
        gmsh.write(str(d / "column.msh"))
    finally:
        gmsh.finalize()
    (d / "column.toml").write_text(COLUMN)
    s = StudyScene.from_file(d / "column.toml")
    out, ctx = run_study([s], sc.Settings.quick(), d / "out")
    return s, out, ctx


def test_user_mesh_is_refined_uniformly(column):
    s, out, ctx = column
    d = _levels(ctx).set_index(["model", "factor"])
    n1 = s.build().mesh.n_tets
    assert d.at[("P1", 2), "tets"] == 8 * n1 == 8 * d.at[("P1", 1), "tets"]
    assert d.at[("P1", 2), "mesh"] == "x2"
    assert any("levels 3 left out (not powers of two)" in f for f in out.findings)


def test_p2_reproduces_the_quadratic_column(column):
    """The exact field is quadratic, so P2 is exact on every level: the reference's probe is
    f L² / 2E, and P2 on level 1 has no error against it (solver round-off)."""
    _, out, ctx = column
    d = _levels(ctx).set_index(["model", "factor"])
    assert d.at[("P2", 1), L2] < 1e-9
    w_ref = d.at[("P1", 1), "w"] / d.at[("P1", 1), "w / w_ref"]
    assert w_ref == pytest.approx(BODY_FORCE * LENGTH**2 / (2 * E), rel=1e-9)
    assert "ref_over_timoshenko" not in out.headline  # no closed form through the hook


def test_study_errors_are_errors_against_the_exact_field(column):
    """With an exact reference the study's P1 errors are P1's errors against the closed form,
    recomputed here from an independent solve at the level-1 vertices (uniform refinement
    keeps the old vertices first, springfem.mesh.refine_uniform); they fall under
    refinement at a rate between 1 and 2 (P1's best-approximation order in L2)."""
    from studies import models

    s, out, ctx = column
    d = _levels(ctx).set_index(["model", "factor"])
    coarse = s.build().mesh.points
    for k in (1, 2):
        scene = refined_scene(s.table, s.path, k)
        np.testing.assert_array_equal(scene.mesh.points[: len(coarse)], coarse)
        u = models.run(scene, "P1").u[: len(coarse)]
        err = metrics.relative_l2_error(u, exact_column(coarse))
        assert d.at[("P1", k), L2] == pytest.approx(err, rel=1e-6)
    assert 1.0 < out.headline["rate_l2_P1"] < 2.2
    assert d.at[("P1", 2), L2] < d.at[("P1", 1), L2]


@pytest.mark.parametrize("name", ["", *(m.name for m in pkgutil.iter_modules(sc.__path__))])
def test_doctests(name):
    module = importlib.import_module(f"studies.study_convergence{'.' if name else ''}{name}")
    assert doctest.testmod(module).failed == 0


@pytest.mark.slow
def test_neo_hookean_jittered_box_against_the_neo_hookean_fem(tmp_path):
    """On a neo-Hookean scene the FEM models are P1-NH and P2-NH (the scene's law); a
    jittered Delaunay box is refined uniformly (powers of two). The exact element's
    small-strain element is P1's and both are solved at finite strain with the same law's
    tangent, so their errors agree to higher order in the strain (the tip rotation is
    ~4e-3 here: 1e-3)."""
    sets = {"material.law": "neo-hookean", "mesh.split": "delaunay", "mesh.divisions": [8, 2, 2]}
    s = StudyScene.bundled("cantilever", sets, label="jittered")
    q = sc.Settings(levels=(1, 2, 3), p2_levels=(1,), ref=2, cosine_check_level=1)
    p = sc.plan(s, q)
    assert p.fem == ("P1-NH", "P2-NH") and p.levels == (1, 2) and p.ref == 2
    out, ctx = run_study([s], q, tmp_path)
    d = _levels(ctx).set_index(["model", "factor"])
    assert d.at[("P1-NH", 2), "tets"] == 8 * d.at[("P1-NH", 1), "tets"]
    for k in (1, 2):
        exact, p1 = d.at[("spring-exact", k), L2], d.at[("P1-NH", k), L2]
        assert exact == pytest.approx(p1, abs=1e-3)
    assert d.at[("P2-NH", 1), L2] < d.at[("P1-NH", 1), L2]
    assert "rate_l2_P1-NH" in out.headline and "spring-energy_over_P1-NH_finest" in out.headline
