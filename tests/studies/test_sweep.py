"""Sweeps: the file format, the table, the case files, and Dask (a real LocalCluster).

The solves run on coarse cantilevers (60-480 tets); the Dask tests use FEM models only
(no numba compilation in the fresh worker processes).
"""

import json
import os
import signal
import subprocess
import sys
import threading
import time
from functools import partial
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from springfem.errors import InputError, SolverError
from studies.cli import main
from studies.sweep import run_sweep
from studies.sweep_case import run_case
from studies.sweep_file import load_sweep, parse_sweep

ROOT = Path(__file__).resolve().parents[2]


def tiny(models=("P1", "P2"), **grid):
    grid = grid or {"mesh.divisions": [[4, 1, 1], [8, 1, 1]], "material.nu": [0.3, 0.45]}
    return {"scene": "cantilever", "models": list(models), "grid": grid}


def case_files(out: Path) -> dict[str, float]:
    return {p.name: p.stat().st_mtime_ns for p in (out / "cases").glob("*.json")}


# ------------------------------------------------------------------------------ the file


def test_grid_is_every_combination_and_cases_a_list(tmp_path):
    torsions = ["cosine", "energy"]
    spec = parse_sweep(tiny(**{"material.nu": [0.3, 0.4, 0.45], "spring.torsion": torsions}))
    assert len(spec.cases) == 6 and spec.keys == ("material.nu", "spring.torsion")
    assert {(c["material.nu"], c["spring.torsion"]) for c in spec.cases} == {
        (nu, t) for nu in (0.3, 0.4, 0.45) for t in torsions
    }
    f = tmp_path / "list.toml"
    f.write_text(
        'scene = "cantilever"\nmodels = ["spring", "P1"]\n'
        '[[cases]]\nmaterial.nu = 0.3\n[[cases]]\n"mesh.divisions" = [4, 1, 1]\n'
    )
    spec = load_sweep(f)
    assert spec.cases == [{"material.nu": 0.3}, {"mesh.divisions": [4, 1, 1]}]
    assert spec.keys == ("material.nu", "mesh.divisions")
    assert spec.reference == "P1" and spec.name == "list"


@pytest.mark.parametrize(
    "models, reference, expected",
    [
        (["spring", "P1", "P2"], None, "P2"),
        (["P1", "P2", "P2-NH"], None, "P2-NH"),
        (["spring"], "P1", "P1"),  # a reference not listed is added
    ],
)
def test_reference_is_the_finest_fem(models, reference, expected):
    data = {"scene": "cantilever", "models": models}
    if reference:
        data["reference"] = reference
    spec = parse_sweep(data)
    assert spec.reference == expected and expected in spec.models


def test_a_sweep_without_models_adds_the_locking_free_ones_where_a_case_needs_them():
    """Cook's neo-Hookean membrane at nu = 0.49 (nearly incompressible) gets the
    locking-free methods and the P2/P1 mixed reference; at nu = 0.3 only, none."""
    cases = {"mesh.divisions": [[2, 2, 1]]}
    spec = parse_sweep({"scene": "cook-membrane", "grid": {**cases, "material.nu": [0.3, 0.49]}})
    assert spec.models[:3] == ("spring", "P1", "P2")
    assert {"fem-P1-nodal-strain", "fem-P1-nodal-volume", "fem-MINI", "spring-stabilised",
            "fem-P2-mixed"} <= set(spec.models)  # fmt: skip
    assert "spring-tissue-stabilised" not in spec.models  # a tissue law's element
    assert spec.reference == "fem-P2-mixed"
    spec = parse_sweep({"scene": "cook-membrane", "grid": {**cases, "material.nu": [0.3]}})
    assert spec.models == ("spring", "P1", "P2") and spec.reference == "P2"
    listed = parse_sweep({"scene": "cook-membrane", "models": ["spring", "P1"], "grid": cases})
    assert listed.models == ("spring", "P1")  # models listed: only those


def test_scene_path_is_relative_to_the_sweep_file(tmp_path):
    (tmp_path / "sub").mkdir()
    text = (ROOT / "studies" / "scenes" / "cantilever.toml").read_text()
    (tmp_path / "sub" / "beam.toml").write_text(text.replace('"cantilever"', '"beam"'))
    f = tmp_path / "s.toml"
    f.write_text('scene = "sub/beam.toml"\nmodels = ["P1"]\n')
    assert load_sweep(f).scene_path == tmp_path / "sub" / "beam.toml"


@pytest.mark.parametrize(
    "data, needle",
    [
        ({"models": ["P1"]}, "scene: missing"),
        ({"scene": "nope"}, "no bundled scene"),
        ({"scene": "cantilever", "models": ["fem-p3"]}, "unknown model 'fem-p3'"),
        ({"scene": "cantilever", "models": ["spring"]}, "no FEM model listed"),
        ({"scene": "cantilever", "grid": {"material.nu": 0.3}}, "must be a non-empty list"),
        ({"scene": "cantilever", "grid": {}, "cases": []}, "not both"),
        ({"scene": "cantilever", "gird": {}}, "gird: unknown key"),
        (tiny(**{"material.nuu": [0.3]}), "material.nuu: unknown key"),
        (tiny(**{"spring.torsion": ["twist"]}), "spring.torsion"),
    ],
)
def test_bad_sweep_files_are_one_line_input_errors(data, needle):
    with pytest.raises(InputError) as info:
        parse_sweep(data)
    assert needle in str(info.value) and "\n" not in str(info.value)


# ----------------------------------------------------------------------------- the table


def test_table_rows_columns_and_resume(tmp_path):
    out = tmp_path / "out"
    spec = parse_sweep(tiny(models=("spring", "P1", "P2")))
    run = run_sweep(spec, out, progress=False)
    t = pd.read_parquet(out / "results.parquet")
    csv = pd.read_csv(out / "results.csv", dtype={"message": str}).fillna(
        {"message": ""}
    )  # CSV: empty text is NaN
    pd.testing.assert_frame_equal(t, csv, check_dtype=False)
    assert len(t) == 4 * 3 and run.computed == 4 and run.cached == 0
    for col in ("mesh.divisions", "material.nu", "model", "status", "message", "rel_l2",
                "rel_max", "probe_error:tip", "probe:tip:uz", "volume_change", "iterations",
                "wall_time"):  # fmt: skip
        assert col in t.columns
    assert set(t["status"]) == {"ok"}
    ref = t[t["model"] == "P2"]
    assert (ref["rel_l2"] == 0).all() and (ref["probe_error:tip"] == 0).all()  # vs itself
    # the grid columns are the case's values: the 8x1x1 mesh has 6 * 8 tets
    assert set(t.loc[t["mesh.divisions"] == "[8, 1, 1]", "tets"]) == {48}
    # relative probe error recomputed from the table's own probe columns (independent path)
    for _, d in t.groupby("case"):
        r = d[d["model"] == "P2"][["probe:tip:ux", "probe:tip:uy", "probe:tip:uz"]].to_numpy()
        u = d[d["model"] == "P1"][["probe:tip:ux", "probe:tip:uy", "probe:tip:uz"]].to_numpy()
        e = d.loc[d["model"] == "P1", "probe_error:tip"].item()
        assert e == pytest.approx(np.linalg.norm(u - r) / np.linalg.norm(r), rel=1e-12)
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert pngs == ["error_vs_material.nu.png", "error_vs_mesh.divisions.png",
                    "error_vs_wall_time.png"]  # fmt: skip
    before = case_files(out)
    assert len(before) == 4
    again = run_sweep(spec, out, progress=False, figures=False)
    assert (again.computed, again.cached) == (0, 4) and case_files(out) == before
    pd.testing.assert_frame_equal(again.table, run.table)


def test_failures_are_rows_not_crashes(tmp_path, monkeypatch):
    from studies import models as Model  # the registry: its solve_model is run's solve

    real = Model.solve_model

    def flaky(self, scene, verbose=False):
        if self.name == "P2" and scene.material.nu > 0.4:
            raise SolverError("P2 diverged (test)")
        return real(self, scene, verbose)

    monkeypatch.setattr(Model, "solve_model", flaky)
    run = run_sweep(parse_sweep(tiny()), tmp_path, progress=False, figures=False)
    t = run.table
    bad = t[t["material.nu"] == 0.45]
    assert set(bad.loc[bad["model"] == "P2", "status"]) == {"failed"}
    assert set(bad.loc[bad["model"] == "P2", "message"]) == {"P2 diverged (test)"}
    p1 = bad[bad["model"] == "P1"]
    assert set(p1["status"]) == {"reference failed"} and p1["rel_l2"].isna().all()
    assert p1["probe:tip:uz"].notna().all()  # its own solution is kept
    assert set(t.loc[t["material.nu"] == 0.3, "status"]) == {"ok"}


def test_cli_sweep_exit_codes(tmp_path, capsys):
    f = tmp_path / "s.toml"
    f.write_text('scene = "cantilever"\nmodels = ["P1"]\n[grid]\n"mesh.divisions" = [[4, 1, 1]]\n')
    assert main(["sweep", str(f), "--out", str(tmp_path / "o"), "--set", "material.E=2e4"]) == 0
    assert "1 cases x 1 models (1 computed, 0 cached)" in capsys.readouterr().out
    row = json.loads((next((tmp_path / "o" / "cases").glob("*.json"))).read_text())
    assert row["case"]["scene"]["material"]["E"] == 2e4  # --set under every case
    f.write_text('scene = "cantilever"\nmodels = ["P1"]\n[grid]\n"mesh.nope" = [1]\n')
    assert main(["sweep", str(f)]) == 2
    err = capsys.readouterr().err.strip()
    assert "mesh.nope: unknown key" in err and "\n" not in err


# ----------------------------------------------------------------------------------- Dask


def _marked_case(marker: str, victim: list, task):
    """run_case, logging each call; the victim case first waits to be killed."""
    d = Path(marker)
    with open(d / "calls.log", "a") as fh:
        fh.write(json.dumps(task["values"], sort_keys=True) + "\n")
    if task["values"]["mesh.divisions"] == victim and not (d / "killed").exists():
        (d / "victim.pid").write_text(str(os.getpid()))
        time.sleep(120)  # SIGKILLed here by the test
    return run_case(task)


def _kill_victim(marker: Path, stop: threading.Event) -> None:
    pid_file = marker / "victim.pid"
    while not stop.is_set():
        if pid_file.exists():
            time.sleep(0.5)  # let the client collect results already finished elsewhere
            (marker / "killed").write_text("")
            os.kill(int(pid_file.read_text()), signal.SIGKILL)  # a worker this test started
            return
        time.sleep(0.05)


@pytest.mark.slow
def test_local_cluster_survives_a_killed_worker_and_resumes(tmp_path):
    import cloudpickle

    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    marker = tmp_path / "marker"
    marker.mkdir()
    out = tmp_path / "out"
    # the cheapest cases that still show it: one model, the other worker finishing two cases
    # while the victim waits to be killed
    divs = [[4, 1, 1], [5, 1, 1], [6, 1, 1]]
    spec = parse_sweep(tiny(models=("P1",), **{"mesh.divisions": divs}))
    work = partial(_marked_case, str(marker), [5, 1, 1])
    stop = threading.Event()
    killer = threading.Thread(target=_kill_victim, args=(marker, stop), daemon=True)
    killer.start()
    try:
        run = run_sweep(spec, out, workers=2, progress=False, figures=False, work=work)
    finally:
        stop.set()
    assert (marker / "killed").exists(), "the victim case never ran"
    assert run.errors == {} and run.computed == 3
    calls = [json.loads(line)["mesh.divisions"] for line in (marker / "calls.log").open()]
    # the killed case ran twice (killed, then rescheduled by dask); every other case once
    assert sorted(map(tuple, calls)) == sorted(map(tuple, divs + [[5, 1, 1]]))
    assert set(run.table["status"]) == {"ok"} and len(case_files(out)) == 3
    # the same numbers as in-process (deterministic solves)
    local = run_sweep(spec, tmp_path / "local", progress=False, figures=False)
    np.testing.assert_allclose(run.table["probe:tip:uz"], local.table["probe:tip:uz"], rtol=1e-12)
    before = case_files(out)  # a rerun computes nothing
    again = run_sweep(spec, out, workers=2, progress=False, figures=False, work=work)
    assert (again.computed, again.cached) == (0, 3) and case_files(out) == before
    assert len((marker / "calls.log").read_text().splitlines()) == 4


def test_joins_an_existing_scheduler(tmp_path):
    from distributed import LocalCluster

    spec = parse_sweep(tiny(**{"mesh.divisions": [[4, 1, 1], [5, 1, 1]]}))
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp",
                      dashboard_address=None) as c:  # fmt: skip
        assert c.scheduler_address.startswith("tcp://")
        run = run_sweep(spec, tmp_path, scheduler=c.scheduler_address, progress=False,
                        figures=False)  # fmt: skip
    assert run.computed == 2 and set(run.table["status"]) == {"ok"}
    # one worker process: at most each model's first solve there is cold, the later one warm
    assert (run.table.groupby("model")["warm"].sum() >= 1).all()


@pytest.mark.slow
def test_killed_client_loses_no_finished_case(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text(
        'scene = "cantilever"\nmodels = ["P1", "P2"]\n[grid]\n'
        '"mesh.divisions" = [[20, 2, 2], [24, 2, 2], [28, 3, 3], [32, 3, 3], [36, 4, 4], '
        "[40, 4, 4]]\n"
    )
    out = tmp_path / "out"
    cmd = [
        sys.executable,
        "-m",
        "studies.cli",
        "sweep",
        str(f),
        "--out",
        str(out),
        "--workers",
        "2",
    ]
    proc = subprocess.Popen(cmd, cwd=ROOT, start_new_session=True, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)  # fmt: skip
    try:
        deadline = time.monotonic() + 120
        while not case_files(out) if (out / "cases").exists() else True:
            assert time.monotonic() < deadline and proc.poll() is None
            time.sleep(0.02)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # the client and the workers it started
        proc.wait()
    done = case_files(out)
    assert 1 <= len(done) < 6
    run = run_sweep(load_sweep(f), out, progress=False, figures=False)
    assert run.cached == len(done) and run.computed == 6 - len(done)
    after = case_files(out)
    assert len(after) == 6 and all(after[k] == v for k, v in done.items())


# ------------------------------------------------------------------ same computations


def _calibrations(**extra):
    grid = {"mesh.divisions": [[4, 1, 1]],
            "spring.calibration": ["analytic", "exact", "analytic-lsq"], **extra}  # fmt: skip
    return parse_sweep({"scene": "cantilever", "models": ["spring", "P1"], "grid": grid})


def test_cases_that_resolve_to_the_same_element_are_solved_once(tmp_path, monkeypatch):
    """Independent check: with the grouping switched off, the two cases solved apart give
    bit-identical rows (the isotropic cantilever's exact and analytic constants agree for
    the specification's parts); with it on, one of them is solved and the note says why."""
    import studies.sweep as sweep_module

    monkeypatch.setattr(sweep_module, "duplicates", lambda tasks: {})
    apart = run_sweep(_calibrations(), tmp_path / "apart", progress=False, figures=False)
    monkeypatch.undo()
    cols = ["probe:tip:ux", "probe:tip:uy", "probe:tip:uz", "rel_l2", "volume_change"]
    t = apart.table
    by = {c: t[(t["spring.calibration"] == c) & (t["model"] == "spring")][cols] for c in
          ("analytic", "exact", "analytic-lsq")}  # fmt: skip
    assert (by["analytic"].to_numpy() == by["exact"].to_numpy()).all()
    assert not (by["analytic"].to_numpy() == by["analytic-lsq"].to_numpy()).all()
    run = run_sweep(_calibrations(), tmp_path / "once", progress=False, figures=False)
    assert (run.computed, run.cached) == (2, 0)
    assert run.notes == [
        "case 1 is the same computation as case 0 "
        "(spring.calibration = exact vs analytic): solved once"
    ]
    same = run.table[run.table["spring.calibration"] == "exact"]
    assert set(same["same_as"]) == {0}
    pd.testing.assert_frame_equal(
        same[cols].reset_index(drop=True),
        apart.table[apart.table["spring.calibration"] == "exact"][cols].reset_index(drop=True),
    )
    again = run_sweep(_calibrations(), tmp_path / "once", progress=False, figures=False)
    assert (again.computed, again.cached) == (0, 3)  # the copy is a case file too
