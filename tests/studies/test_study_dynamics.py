"""Tests of the dynamics study: explicit P1 conserves its energy undamped, the tissue spring
element tracks explicit P1 of its law where the exact small-strain element does not, the
run length is the deflection's period, resume, and a user's scene through the same
function."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import studies.study_dynamics as dynamics
from springfem.errors import InputError
from studies.runner import run_study
from studies.scenes import StudyScene
from studies.study_dynamics import (
    Settings,
    beam_table,
    energy_drift,
    period_case,
    probe_errors,
    release_cases,
)
from studies.study_dynamics.work import WORK, release_case

#: A 6x1x1 beam (36 tets) under 4x Land's load, half a period, few timed steps.
TINY = Settings(beam=(6, 1, 1), load=4.0, periods=0.5, samples=60, rounds=1, steps=10,
                models=("spring-tissue", "spring-exact"))  # fmt: skip


@pytest.fixture(scope="module")
def tiny_runs():
    sc = beam_table(TINY.beam, TINY.load)
    period = WORK["period"][0](period_case(sc))["period"]
    cases = release_cases(sc, TINY, TINY.periods * period)
    return period, {c["model"]: release_case(c) for c in cases}


def test_undamped_explicit_p1_conserves_its_energy(tiny_runs):
    # Symplectic Euler at half the critical step: the recorded energy (kinetic with the
    # synchronised velocity + strain) oscillates by O((omega dt)^2) times the share of the
    # energy in the highest modes and does not drift (measured 3e-6 on the 10x2x2 beam). A
    # wrong force sign, a missing mass or a secular drift exceeds 1e-4 within the run.
    _, runs = tiny_runs
    p1 = runs["P1"]
    assert p1["status"] == "ok"
    assert energy_drift(p1) < 1e-4
    # the bound is not vacuous: the strain energy went through the kinetic part
    assert max(p1["kinetic"]) > 0.5 * p1["energy"][0]


def test_tissue_element_tracks_explicit_p1_where_the_exact_element_does_not(tiny_runs):
    # The tissue element's energy is the law's own per element (docs/tissue.rst), so it is
    # explicit P1 of the law up to round-off (measured 3e-14 on the 10x2x2 beam). The exact
    # element is linear springs calibrated to P1's small-strain tangent: at 4x Land's load
    # (tip deflection ~ the beam's height) the Guccione law's stiffening shows.
    _, runs = tiny_runs
    tissue, _ = probe_errors(runs["spring-tissue"], runs["P1"])
    exact, _ = probe_errors(runs["spring-exact"], runs["P1"])
    assert tissue < 1e-9
    assert exact > 1e-3
    # same tangent at rest: the stable steps agree (the solver's eigenvalue tolerance)
    assert runs["spring-exact"]["dt_crit_rest"] == pytest.approx(runs["P1"]["dt_crit_rest"],
                                                                 rel=1e-6)  # fmt: skip


def test_run_length_is_the_period_of_the_released_deflection(tiny_runs):
    # The Rayleigh period of the static deflection (work.rayleigh_period) against the time
    # the probe takes to swing to its far side, a half period: the first minimum of the
    # dominant component. Rayleigh's quotient is exact for the first mode; the deflection
    # is close to it (a few per cent), and a wrong mass or unit would be off by far more.
    period, runs = tiny_runs
    u = np.asarray(runs["P1"]["u"])[:, 2]
    t = np.asarray(runs["P1"]["t"])
    assert u[0] > 0 and u.min() < 0  # released upwards deflection swings through rest
    assert t[np.argmin(u)] == pytest.approx(period / 2, rel=0.1)


def test_a_second_run_redoes_nothing(tmp_path, monkeypatch):
    calls = []
    for kind in ("period", "release", "cost"):
        fn, label = WORK[kind]

        def counted(case, fn=fn, kind=kind):
            calls.append(kind)
            return fn(case)

        monkeypatch.setitem(dynamics.WORK, kind, (counted, label))
    first = run_study("dynamics", tmp_path, settings=TINY, progress=False)
    # two bundled beams: Guccione (P1, two springs, three peers not applicable) and its
    # neo-Hookean twin (P1-NH, the exact element, co-rotational, mass-spring, XPBD)
    n = len(calls)
    assert sorted(set(calls)) == ["cost", "period", "release"] and calls.count("cost") == 2
    second = run_study("dynamics", tmp_path, settings=TINY, progress=False)
    assert len(calls) == n
    assert first.findings == second.findings
    names = {f.path.name for f in second.figures}
    assert names == {"probe_vs_time.png", "energy_vs_time.png"}
    df = pd.read_csv(tmp_path / "dynamics" / "dynamics.csv")
    g = df[df.scene == "land-beam"]
    assert list(g[g.status == "ok"].model) == ["P1", "spring-tissue", "spring-exact"]
    assert set(g[g.status != "ok"].status) == {"not applicable"}
    assert g[g.status != "ok"].message.str.contains("guccione").all()
    nh = df[df.scene == "land-beam-nh"]
    assert {"P1-NH", "spring-exact", "xpbd", "mass-spring"} <= set(nh[nh.status == "ok"].model)
    ok = df[df.status == "ok"]
    assert (ok["step (µs)"] > 0).all()


USER_SCENE = """
name = "ubar"
[mesh]
generator = "box"
size = [4.0, 1.0, 1.0]
divisions = [4, 1, 1]
[material]
law = "guccione"
C = 2.0
b_f = 8.0
b_t = 2.0
b_fs = 4.0
kappa = 50.0
density = 1.0e-6
{extra}
[axes]
fiber = [0.8, 0.6, 0.0]
sheet = [-0.6, 0.8, 0.0]
[[boundary]]
region = "x_min"
fix = ["x", "y", "z"]
[[load]]
type = "traction"
region = "x_max"
value = [0.0, 0.0, -0.05]
"""


def test_user_scene_runs_through_the_same_function(tmp_path):
    # Guccione with a rotated fibre, no [[probe]]: the node farthest from the clamp.
    path = tmp_path / "scene.toml"
    path.write_text(USER_SCENE.format(extra=""))
    user = StudyScene.from_file(path)
    s = Settings(periods=0.3, samples=30, rounds=1, steps=5, models=("spring-exact",))
    out = run_study("dynamics", tmp_path / "out", settings=s, scenes=[user], progress=False)
    df = pd.read_csv(tmp_path / "out" / "dynamics" / "dynamics.csv")
    ok = df[df.status == "ok"]
    assert list(ok.model) == ["P1", "spring-exact"]
    assert set(df[df.status != "ok"].status) == {"not applicable"}  # the isotropic peers
    assert ok["energy drift"].max() < 1e-3
    assert any("ubar" in f for f in out.findings)


def test_an_incompressible_scene_is_refused_in_one_line(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text(USER_SCENE.format(extra="incompressible = true").replace("kappa = 50.0\n", ""))
    with pytest.raises(InputError, match="kappa"):
        run_study("dynamics", tmp_path / "out", settings=TINY, scenes=[StudyScene.from_file(path)],
                  progress=False)  # fmt: skip


@pytest.mark.slow
def test_quick_cli_writes_the_table(tmp_path):
    from studies.cli import main

    assert main(["study", "dynamics", "--quick", "--out", str(tmp_path)]) == 0
    df = pd.read_csv(tmp_path / "dynamics" / "dynamics.csv")
    g = df[(df.scene == "land-beam") & (df.status == "ok")]
    assert set(g.model) == {"P1", "spring-tissue", "spring-stiffened", "spring-exact"}
    tissue = g[g.model == "spring-tissue"].iloc[0]
    assert tissue["L2 error (run)"] < 1e-9
