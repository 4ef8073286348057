"""Implausible results are flagged, not passed as "ok"; raw numpy warnings are summarised.

Independent references: a block of E = 3 kPa compressed by 3 kPa on three faces (a
hydrostatic-like load of the order of its modulus) loses most of its volume, and the solver's
own volume measure says by how much; a linear cantilever is linear in 1/E, so E = 0.01 Pa
turns the bundled ~1 mm tip into ~100 m, a thousand times the 0.1 m beam.
"""

import numpy as np
import pandas as pd
import pytest

from springfem.scene import scene_from_dict
from studies.cli import main
from studies.compare import compare_scene
from studies.models import run
from studies.sweep import run_sweep
from studies.sweep_file import parse_sweep

SOFT = ["--set", "material.E=0.01"]


def _squeezed_block(E: float = 3.0e3, load: float = 3.0e3):
    faces = (("x_max", [-load, 0, 0]), ("y_max", [0, -load, 0]), ("z_max", [0, 0, -load]))
    return scene_from_dict({
        "name": "squeezed",
        "mesh": {"generator": "box", "size": [1, 1, 1], "divisions": [3, 3, 3],
                 "split": "delaunay"},
        "material": {"law": "neo-hookean", "E": E, "nu": 0.3},
        "boundary": [{"region": "x_min", "fix": ["x"]}, {"region": "y_min", "fix": ["y"]},
                     {"region": "z_min", "fix": ["z"]}],
        "load": [{"type": "traction", "region": r, "value": v} for r, v in faces],
    })  # fmt: skip


def test_a_converged_fem_solve_that_loses_most_of_its_volume_is_implausible():
    got = run(_squeezed_block(), "P1-NH", check=True)
    assert got.status == "implausible" and got.solved and not got.ok
    dV = got.solution.result.volume["relative_change"]  # the solver's own volume measure
    assert dV < -0.5
    assert f"volume changes by {dV:+.1%}" in got.message
    assert run(_squeezed_block(load=30.0), "P1-NH", check=True).status == "ok"  # 1 % load
    assert run(_squeezed_block(), "P1-NH").status == "ok"  # unchecked: as before


def test_compare_rows_of_an_implausible_solution_say_so(tmp_path, capsys):
    out = tmp_path / "cmp"
    assert main(["compare", "cantilever", "--models", "P1,P2", "--out", str(out), *SOFT]) == 0
    captured = capsys.readouterr()
    table = pd.read_csv(out / "compare.csv")
    assert set(table["status"]) == {"implausible"}
    assert "exceeds the body's size" in captured.out + captured.err


def test_compare_of_the_bundled_cantilever_is_plausible(tmp_path):
    from springfem.scene import load_scene

    cmp = compare_scene(load_scene("cantilever"), ["P1", "P2"])
    assert cmp.implausible == {} and set(cmp.table["status"]) == {"ok"}


def test_sweep_rows_of_implausible_cases_are_not_ok(tmp_path):
    grid = {"mesh.divisions": [[4, 1, 1]], "material.E": [1.0e4, 0.01]}
    spec = parse_sweep({"scene": "cantilever", "models": ["P1", "P2"], "grid": grid})
    t = run_sweep(spec, tmp_path, progress=False, figures=False).table
    assert set(t.loc[t["material.E"] == 1.0e4, "status"]) == {"ok"}
    soft = t[t["material.E"] == 0.01]
    assert set(soft["status"]) == {"implausible"}
    assert soft["message"].str.contains("exceeds the body's size").all()
    assert soft["probe:tip:uz"].notna().all()  # the numbers are kept beside the status


def test_raw_floating_point_warnings_become_one_summary_line(monkeypatch, capsys):
    import studies.cli.solve as solve_cli

    def noisy(args):
        with np.errstate(over="warn", invalid="warn"):
            np.exp(np.array([1000.0]))
            np.exp(np.array([2000.0]))
            np.log(np.array([-1.0]))
        return 0

    monkeypatch.setattr(solve_cli, "cmd_solve", noisy)
    assert main(["solve", "cantilever"]) == 0
    err = capsys.readouterr().err
    assert "RuntimeWarning" not in err
    notes = [line for line in err.splitlines() if "floating-point warnings" in line]
    assert notes == [
        "springfem: note: 3 floating-point warnings while solving: overflow encountered in "
        "exp (2), invalid value encountered in log (1)"
    ]


@pytest.mark.parametrize("flag", [[], ["--debug"]])
def test_a_quiet_command_prints_no_warning_summary(flag, tmp_path, capsys):
    assert main([*flag, "solve", "cantilever", "--model", "fem", "--out", str(tmp_path)]) == 0
    assert "floating-point" not in capsys.readouterr().err


def test_cli_sweep_warns_on_implausible_rows_and_exits_0(tmp_path, capsys):
    f = tmp_path / "s.toml"
    f.write_text('scene = "cantilever"\nmodels = ["P1", "P2"]\n[grid]\n'
                 '"mesh.divisions" = [[4, 1, 1]]\n"material.E" = [0.01]\n')  # fmt: skip
    assert main(["sweep", str(f), "--out", str(tmp_path / "o")]) == 0
    err = capsys.readouterr().err
    assert "solver failure" not in err
    assert err.count("warning: case 0 ") == 2 and "implausible" in err
