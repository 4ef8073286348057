"""Tests of the locking study: P1 locks where Taylor–Hood does not, the Poisson-ratio map,
the cheapest-method rule on a hand-made table, resume, and a user's gmsh scene."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from support.meshes import gmsh_box

import studies.study_locking as locking
from studies.runner import run_study
from studies.scenes import StudyScene
from studies.study_locking import answer_frame, cheapest, with_errors
from studies.study_locking.cases import Settings, bundled_scenes, cases, locking_case, with_nu

TINY = Settings(nus=(0.4999,), cook=(2, 2, 1), beam=None, factors=(1,),
                methods=("P1", "P2-mixed"), max_time=60.0, timed=False)  # fmt: skip


def _cook(nu: float, method: str, divisions=(4, 4, 1)) -> float:
    sc = bundled_scenes(Settings(cook=divisions, beam=None))[0]
    s = Settings(nus=(nu,), cook=divisions, beam=None, factors=(1,), methods=(method,),
                 timed=False)  # fmt: skip
    r = locking_case(cases(sc, s)[0])
    assert r["status"] == "ok", r["message"]
    return r["u"][1]  # u_y of the corner


def test_p1_locks_near_incompressibility_where_taylor_hood_does_not():
    # Cook's membrane on 4x4x1 (96 tets). Taylor–Hood is inf-sup stable: its corner u_y
    # barely depends on the bulk modulus (measured 3.43 at nu = 0.3, 2.96 at 0.4999: the
    # material, not the mesh, stiffens with fixed mu). P1 keeps 22 % at nu = 0.4999 against
    # the mesh's own 0.3 share; a locked element keeps well under a third.
    th = {nu: _cook(nu, "P2-mixed") for nu in (0.3, 0.4999)}
    p1 = {nu: _cook(nu, "P1") for nu in (0.3, 0.4999)}
    assert p1[0.4999] < 0.3 * th[0.4999]
    assert p1[0.4999] / th[0.4999] < 0.75 * p1[0.3] / th[0.3]  # worse as nu -> 0.5
    assert th[0.4999] == pytest.approx(th[0.3], rel=0.25)


def test_nu_holds_the_shear_modulus_and_sets_a_tissue_penalty():
    cook = bundled_scenes(Settings.quick())[0]
    mu = cook.build().material.mu
    for nu in (0.3, 0.4999):
        m = with_nu(cook, nu).build().material
        assert (m.mu, m.nu) == (pytest.approx(mu, rel=1e-12), nu)
    assert mu == pytest.approx(80.19, rel=1e-3)  # Cook's shear modulus
    beam = StudyScene.bundled("land-beam")
    mat = with_nu(beam, 0.4999).build().material
    assert not mat.incompressible
    # kappa / mu = 2 (1 + nu) / (3 (1 - 2 nu)) = 2.9998 / 0.0006 at nu = 0.4999
    ratio = mat.parameters["kappa"] / beam.build().material.mu
    assert ratio == pytest.approx(2.9998 / 0.0006, rel=1e-9)
    table = {"material": {"law": "transverse-linear"}}
    with pytest.raises(Exception, match="no single Poisson ratio"):
        with_nu(StudyScene("t", table), 0.4)


def _table(rows) -> pd.DataFrame:
    cols = ["method", "factor", "tets", "status", "uy", "seconds"]
    df = pd.DataFrame(rows, columns=cols).assign(scene="s", nu=0.49, ux=0.0, uz=0.0,
                                                 component=1, load=1.0, message="")  # fmt: skip
    return with_errors(df)[0]


def test_cheapest_method_rule_on_a_hand_made_table():
    df = _table(
        [
            ("P2-mixed", 1, 10, "ok", 9.0, 0.5),
            ("P2-mixed", 2, 80, "ok", 10.0, 5.0),  # the reference: 10
            ("P1", 2, 80, "ok", 3.0, 0.1),  # fast, locked (70 % off)
            ("MINI", 1, 10, "ok", 9.6, 0.4),  # 4 % off, cheapest adequate
            ("MINI", 2, 80, "ok", 9.9, 0.2),  # 1 % off and cheaper still
            ("P2", 2, 80, "partial", np.nan, 1e-3),  # stopped: never a candidate
        ]
    )
    assert df.reference.sum() == 1 and df.error[df.reference].iloc[0] == 0.0
    win = cheapest(df, 0.05)
    assert (win.method, win.factor) == ("MINI", 2)
    assert cheapest(df, 0.005) is None  # only the reference itself is that close
    ans = answer_frame(df, 0.05).iloc[0]
    assert ans["cheapest within tolerance"] == "MINI"
    assert ans["never within tolerance"] == "P1, P2"
    assert answer_frame(df, 0.005).iloc[0]["cheapest within tolerance"] == "none"


def test_a_level_that_cannot_be_the_cheapest_of_its_kind_is_not_run():
    """A finer level is left out where, on a coarser level, a method on the same kind of
    tets was within the tolerance faster than the level's predicted time (DOFs x cost per
    DOF, by hand), or twice as accurate and no slower."""
    from types import SimpleNamespace

    from studies.budget import CostModel
    from studies.study_locking.cases import COSTLIER, case_of, estimate

    s = Settings(nus=(0.4999,), cook=(2, 2, 1), beam=None, factors=(1, 2),
                 methods=("P1", "P2", "P2-mixed"), timed=False, prune=False)  # fmt: skip
    sc = bundled_scenes(s)[0]
    ctx = SimpleNamespace(cache=SimpleNamespace(costs=CostModel(priors={"P1": 1e-3, "P2": 1e-3})))
    p2, p1 = (case_of(sc, s, m, 0.4999, 2) for m in ("P2", "P1"))
    predicted = 1e-3 * estimate(p2)[1]  # seconds: DOFs x the prior
    faster = (0.5 * predicted, "P2-mixed", 24)
    assert COSTLIER in locking._not_run(ctx, s, p2, faster, [])
    assert locking._not_run(ctx, s, p2, (2.0 * predicted, "P2-mixed", 24), []) is None
    # on the coarser level: P2/P1 twice as accurate and no slower, or not
    dominated = [("P2", 0.5, 2.0, 24), ("P2-mixed", 0.25, 2.0, 24)]
    assert COSTLIER in locking._not_run(ctx, s, p2, None, dominated)
    for other in (("P2-mixed", 0.26, 1.0, 24), ("P2-mixed", 0.1, 2.1, 24)):
        assert locking._not_run(ctx, s, p2, None, [dominated[0], other]) is None
    assert locking._not_run(ctx, s, p1, None, [("P1", 0.5, 2.0, 24)]) is None
    off = Settings(**{**s.__dict__, "skip_costlier": False})
    assert locking._not_run(ctx, off, p2, faster, dominated) is None


def test_a_second_run_redoes_nothing(tmp_path, monkeypatch):
    calls = []

    def counted(case):
        calls.append(case["method"])
        return locking_case(case)

    monkeypatch.setattr(locking, "locking_case", counted)
    first = run_study("locking", tmp_path, settings=TINY, progress=False)
    assert sorted(calls) == ["P1", "P2-mixed"]
    second = run_study("locking", tmp_path, settings=TINY, progress=False)
    assert len(calls) == 2
    assert first.findings == second.findings
    assert {f.path.name for f in second.figures} == {"deflection_vs_nu.png", "error_vs_cost.png"}


GMSH_SCENE = """
name = "gbox"
[mesh]
file = "box.msh"
[material]
law = "neo-hookean"
E = 1.0e4
nu = 0.3
[[boundary]]
region = "x_min"
fix = ["x", "y", "z"]
[[load]]
type = "traction"
region = "x_max"
value = [0.0, 0.0, -20.0]
[[probe]]
name = "tip"
point = [0.1, 0.01, 0.01]
"""


@pytest.fixture
def gmsh_scene(tmp_path):
    gmsh_box(tmp_path / "box.msh", 0.02)
    (tmp_path / "scene.toml").write_text(GMSH_SCENE)
    return tmp_path / "scene.toml"


def test_user_gmsh_scene_runs_through_the_same_function(gmsh_scene, tmp_path):
    user = StudyScene.from_file(gmsh_scene)
    s = Settings(nus=(0.3,), factors=(1, 2), methods=("P1", "P2-mixed"), max_time=60.0,
                 timed=False)  # fmt: skip
    out = run_study("locking", tmp_path / "out", settings=s, scenes=[user], progress=False)
    df = pd.read_csv(tmp_path / "out" / "locking" / "locking.csv")
    assert set(df.axis) == {"z"}  # the tip bends down: the dominant component
    assert (df.status == "ok").all()
    # P1 converges towards Taylor-Hood under refinement at nu = 0.3 (no locking)
    p1 = df[df.method == "P1"].sort_values("tets").error.to_numpy()
    assert p1[1] < p1[0]
    assert any("gbox" in f for f in out.findings)


@pytest.mark.slow
def test_quick_cli_on_a_gmsh_scene(gmsh_scene, tmp_path):
    from studies.cli import main

    out = tmp_path / "cli"
    args = ["study", "locking", "--quick", "--scene", str(gmsh_scene), "--out", str(out)]
    assert main(args) == 0
    answers = pd.read_csv(out / "locking" / "cheapest.csv")
    assert list(answers.nu) == list(Settings.quick().nus)


@pytest.mark.slow
def test_locking_free_methods_free_cook_at_nu_0_4999():
    # 8x8x1 (384 tets): nodal-volume P1, MINI and the stabilised spring element recover most
    # of the Taylor-Hood deflection where P1 and the exact element keep about a quarter
    # (measured 0.67 / 2.04 / 2.30 / 2.25 against 3.05).
    th = _cook(0.4999, "P2-mixed", (8, 8, 1))
    for m, share in (("P1-nodal-volume", 0.6), ("MINI", 0.7), ("spring-stabilised", 0.7)):
        assert _cook(0.4999, m, (8, 8, 1)) > share * th, m
    for m in ("P1", "spring-exact"):
        assert _cook(0.4999, m, (8, 8, 1)) < 0.3 * th, m


def test_a_budget_bounds_the_whole_study_and_it_still_writes_its_tables(
    gmsh_scene, tmp_path, capsys
):
    """``--budget`` on a user's scene: a plan line comes before the first solve, the levels
    whose predicted cost does not fit are left out with a note, the cases that do not fit
    are skipped (listed with the reason, not cached), every other case is a row, and the
    tables and figures are written; the run ends near its budget (a generous cap)."""
    import time

    from studies.cli import main

    out = tmp_path / "budget"
    budget = 4.0  # well below the ~15 s the cases take on an idle machine: some must skip
    args = ["study", "locking", "--quick", "--scene", str(gmsh_scene), "--out", str(out),
            "--budget", str(budget), "--max-time", "10"]  # fmt: skip
    t0 = time.monotonic()
    assert main(args) == 0
    elapsed = time.monotonic() - t0
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert lines[0].startswith("plan: ") and "(budget 4 s)" in lines[0]  # before any solve
    folder = out / "locking"
    df = pd.read_csv(folder / "locking.csv")
    skipped = pd.read_csv(folder / "skipped.csv")
    assert len(skipped) >= 1 and skipped.reason.str.contains("budget").all()
    assert set(df[df.status == "skipped"].method) == set(skipped.method)
    # every method at every Poisson ratio on the level that fits is a row: run or skipped
    methods = {m for m in Settings.quick().methods if "tissue" not in m}
    assert set(df.method) == methods and set(df.nu) == set(Settings.quick().nus)
    assert set(df.tets.dropna()) == {df.tets.min()}  # only level x1 fits in 4 s
    assert (folder / "cheapest.csv").is_file() and (folder / "error_vs_cost.png").is_file()
    # no case started once it could not finish: the study ends near its budget
    assert elapsed < budget + 90.0
    # the skipped cases (and any the budget cut short) were not cached: a rerun with more
    # time computes them
    cached = len(list((out / ".cache" / "locking").glob("*.json")))
    assert cached <= int((df.status != "skipped").sum())
