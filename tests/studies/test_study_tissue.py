"""Study ``tissue``: the small-strain limit of its stress-stretch cases against the law's
tangent, and the quick preset's outputs."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import studies.study_tissue as st
from springfem.materials.tissue import tissue_tangent
from studies.cache import CaseCache
from studies.registry import StudyContext
from studies.study_tissue import GUCCIONE, HOLZAPFEL_OGDEN, VERSION, cube, stretch_case

# the study's quick run takes tens of seconds: -m slow
pytestmark = pytest.mark.slow


def small_strain_tangent(law):
    p = GUCCIONE if law == "guccione" else HOLZAPFEL_OGDEN
    return tissue_tangent(law, p, kappa=p["kappa"])  # in tension


@pytest.mark.parametrize("law", ["guccione", "holzapfel-ogden"])
@pytest.mark.parametrize("direction", ["along", "across"])
@pytest.mark.parametrize("model", ["fem", "spring-exact"])
def test_small_stretch_gives_the_uniaxial_modulus_of_the_tangent(law, direction, model):
    # uniaxial stress with free lateral faces: P = E eps with E = 1 / S_xx of the law's
    # small-strain tangent (the fibre, or across it the sheet, in tension); at eps = 0.002
    # the finite-strain terms are O(b eps), < 1 %
    S = np.linalg.inv(small_strain_tangent(law))
    E = 1.0 / S[0, 0] if direction == "along" else 1.0 / S[1, 1]  # x is the sheet axis across
    eps = 0.002
    r = stretch_case(cube(direction, 1 + eps, 1, law).case("tissue-test", VERSION, model=model))
    assert r["error"] == ""
    assert r["stress"] == pytest.approx(E * eps, rel=0.01)


@pytest.fixture(scope="module")
def output(tmp_path_factory):
    root = tmp_path_factory.mktemp("tissue")
    ctx = StudyContext("tissue", root / "tissue", True, CaseCache(root, "t"), False)
    settings = st.Settings.quick()
    return ctx, st.run(ctx, st.scenes(settings), settings)


def test_quick_outputs(output):
    ctx, out = output
    assert [t.path.name for t in out.tables] == [
        "stress_stretch.md",
        "beam.md",
        "ventricle.md",
        "beam_levels.md",
        "apex_convergence.md",
        "apex_richardson.md",
    ]
    assert out.figures[0].path.stat().st_size > 0
    every = pd.read_csv(ctx.out / "stress_stretch.csv")
    s = every[every.law == "guccione"]
    fem = s[s.model == "fem"].set_index(["direction", "stretch"]).stress
    # Guccione stiffens along the fibre (b_f = 8 > b_t = 2): stiffer along than across, and
    # more than linearly in the stretch
    for lam in s.stretch.unique():
        assert fem[("along", lam)] > fem[("across", lam)] > 0
    lo, hi = sorted(s.stretch.unique())[:2]
    assert fem[("along", hi)] / fem[("along", lo)] > (hi - 1) / (lo - 1)
    beam = pd.read_csv(ctx.out / "beam.csv").set_index("model")
    # Land problem 1 (published 4.14-4.20 mm); a 10x1x1 P2 mesh is within a few % of it
    assert beam.loc["fem", "tip_z"] == pytest.approx(4.17, rel=0.05)
    lv = pd.read_csv(ctx.out / "ventricle.csv").set_index("model")
    # inflation: the apex moves away from the base and the cavity grows
    assert lv.loc["fem", "endo_apex_z"] < -17.0
    assert lv.loc["fem", "cavity_final"] > lv.loc["fem", "cavity_initial"]
    # the stiffened exact element is the Guccione law under a stretch along a frame axis
    # (springmodel.stiffening; the same penalty U(J)): equal to the P1 FEM's homogeneous
    # solution to the solvers' tolerance, where the quadratic springs are 40-75 % off at 30 %
    spring = s[s.model == "spring-stiffened"].set_index(["direction", "stretch"]).stress
    assert np.allclose(spring, fem[spring.index], rtol=1e-6)
    exact = s[s.model == "spring-exact"].set_index(["direction", "stretch"]).stress
    assert (abs(exact / fem[exact.index] - 1).loc[:, hi] > 0.4).all()
    # Holzapfel-Ogden: one exponent per element, the fibre term's (C = a_f / b_f): along the
    # fibre the stiffened element is that term (the isotropic one aside), far closer than the
    # quadratic element; across, the sheet's b_s is missed and it stays too soft
    ho = every[(every.law == "holzapfel-ogden") & (every.stretch == hi)]
    err = ho.set_index(["direction", "model"]).rel_error
    assert abs(err[("along", "spring-stiffened")]) < 0.1 * abs(err[("along", "spring-exact")])
    assert err[("across", "spring-stiffened")] < 0
    # the ventricle: the stiffened element reaches the full load (the quadratic one stops)
    assert lv.loc["spring-stiffened", "load_factor"] == 1.0
    assert lv.loc["spring-exact", "load_factor"] < 0.5
    assert any("Land beam" in f for f in out.findings)
    assert "stress_error_along_spring-exact" in out.headline


def test_quick_apex_convergence(output):
    ctx, out = output
    conv = pd.read_csv(ctx.out / "apex_convergence.csv")
    # the quick preset's two coarse meshes of problem 3 (passive): both converge, the finer
    # one has more DOFs, and the epicardial apex lies below the endocardial one (the wall
    # stays ~3 mm thick at the apex under inflation: incompressible)
    assert list(conv["size"]) == [6.0, 5.0] and (conv.error.isna() | (conv.error == "")).all()
    assert conv.dofs.iloc[1] > conv.dofs.iloc[0]
    assert (conv.epi_apex_z < conv.endo_apex_z - 1.0).all()
    assert (ctx.out / "apex_convergence.png").stat().st_size > 0
    assert any("Land problem 3 (passive)" in f for f in out.findings)
