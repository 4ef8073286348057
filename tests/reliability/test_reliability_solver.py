"""Reliability: solver failures exit 3 with a diagnosis and keep the last good state.

``springfem solve`` on small scenes that fail on purpose:

* explicit blow-up of the spring model (time step five times the critical one),
* Newton divergence of the neo-Hookean FEM reference (a load no solid can carry),
* a singular system (no Dirichlet condition: rigid-body modes remain), for both models.

Each must end with exit code 3 and one stderr line that says what failed, where and at
which step, and must leave ``last_good_state.json`` + ``.vtu`` in ``--out`` (the initial,
undeformed state when the solve failed before its first step) and no ``result.json``.
Every failing case has a control that differs only in the culprit (a stable time step,
a moderate load, a support) and exits 0, so the tests pin the cause, not just the code.
"""

from __future__ import annotations

import json
import re

import meshio
import numpy as np
import pytest

from studies.cli import main

SCENE = """\
name = "tiny"
[mesh]
generator = "box"
size = [0.04, 0.01, 0.01]
divisions = [4, 1, 1]
[material]
law = "{law}"
E = 1.0e4
nu = 0.3
density = 1000.0
{boundary}
[[load]]
type = "traction"
region = "x_max"
value = [0.0, 0.0, {load}]
[[probe]]
name = "tip"
point = [0.04, 0.005, 0.005]
{extra}"""
FIXED = '[[boundary]]\nregion = "x_min"\nfix = ["x", "y", "z"]'
N_NODES = 5 * 2 * 2


def solve(tmp_path, capsys, model, law="linear", boundary=FIXED, load=-0.1, extra=""):
    """Run ``springfem solve`` in-process; return (exit code, stderr lines, out folder)."""
    scene = tmp_path / f"{model}.toml"
    scene.write_text(SCENE.format(law=law, boundary=boundary, load=load, extra=extra))
    out = tmp_path / f"out-{model}"
    capsys.readouterr()
    code = main(["solve", str(scene), "--model", model, "--out", str(out)])
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return code, err.splitlines(), out


def check_failure(lines, out, state: str) -> str:
    """One failure line naming the state written; the state files exist and are readable."""
    assert len(lines) == 1, lines
    line = lines[0]
    assert line.startswith("springfem: solver failure: ")
    assert not (out / "result.json").exists()
    js = json.loads((out / "last_good_state.json").read_text())
    assert js["converged"] is False and js["element"] == "last-good-state"
    assert js["info"]["state"] == state
    assert js["info"]["error"] in line  # the diagnosis is kept with the state
    assert set(js["probes"]) == {"tip"}
    u = meshio.read(out / "last_good_state.vtu").point_data["displacement"]
    assert u.shape == (N_NODES, 3) and np.isfinite(u).all()
    assert not list(out.glob("*.tmp*")) and not list(out.glob(".*.tmp"))
    return line


def test_explicit_blow_up_names_step_element_and_time_step(tmp_path, capsys):
    # critical dt of this scene at rest is ~2e-3 s (the solver reports it); 1e-2 s is 5x
    extra = '[spring]\nsolver = "explicit"\ndt = 0.01\nsteps = 200\n'
    code, lines, out = solve(tmp_path, capsys, "spring", extra=extra)
    assert code == 3
    line = check_failure(lines, out, "last good")
    assert re.search(r"explicit integration blew up at step \d+ \(t = [\d.e+-]+ s\)", line)
    assert re.search(r"at node \d+ in element \d+", line)  # where
    ratio = float(re.search(r"dt / dt_crit = ([\d.e+-]+)", line).group(1))
    assert ratio > 2  # the diagnosis blames the time step, rightly
    assert line.endswith(f"(last good state written to {out})")


def test_explicit_control_with_a_stable_time_step_finishes(tmp_path, capsys):
    extra = '[spring]\nsolver = "explicit"\ndt = 0.0005\nsteps = 200\n'
    code, lines, out = solve(tmp_path, capsys, "spring", extra=extra)
    assert code == 0, lines
    assert (out / "result.json").exists() and not (out / "last_good_state.json").exists()


def test_newton_divergence_names_the_load_step(tmp_path, capsys):
    # a traction of 1e9 Pa on a material with E = 1e4 Pa: no equilibrium Newton can reach
    code, lines, out = solve(tmp_path, capsys, "fem", law="neo-hookean", load=-1.0e9)
    assert code == 3
    line = check_failure(lines, out, "last good")
    assert "tiny (fem P1, neo-hookean/coupled): Newton failed at load step 1" in line
    assert re.search(r"load factor [\d.e+-]+ -> [\d.e+-]+", line)  # when
    assert "cut-backs" in line and line.endswith(f"(last good state written to {out})")
    # the last converged state is the unloaded one: load factor 0
    js = json.loads((out / "last_good_state.json").read_text())
    assert js["probes"]["tip"] == [0.0, 0.0, 0.0]


def test_newton_control_with_a_moderate_load_converges(tmp_path, capsys):
    code, lines, out = solve(tmp_path, capsys, "fem", law="neo-hookean", load=-0.1)
    assert code == 0, lines
    assert json.loads((out / "result.json").read_text())["converged"] is True


@pytest.mark.parametrize(
    "model, diagnosis",
    [
        (
            "spring",
            "singular stiffness: the scene has no boundary condition that stops rigid motion "
            "(no constrained DOF at all)",
        ),
        (
            "fem",
            "tiny (fem P1, linear): singular stiffness matrix: no displacement is prescribed "
            "(translation x, translation y, translation z, 3 rotations); add boundary conditions",
        ),
    ],
)
def test_singular_system_without_dirichlet_condition(tmp_path, capsys, model, diagnosis):
    code, lines, out = solve(tmp_path, capsys, model, boundary="")
    assert code == 3
    line = check_failure(lines, out, "initial")
    assert line == (
        f"springfem: solver failure: {diagnosis} (initial state (failed before the first "
        f"step) written to {out})"
    )
    u = meshio.read(out / "last_good_state.vtu").point_data["displacement"]
    assert not u.any()  # the initial state: undeformed


@pytest.mark.parametrize("model", ["spring", "fem"])
def test_singular_control_with_a_support_solves(tmp_path, capsys, model):
    code, lines, out = solve(tmp_path, capsys, model)
    assert code == 0, lines
    # independent check that the solve did something: the tip moves down under -z traction
    tip = json.loads((out / "result.json").read_text())["probes"]["tip"]
    assert tip[2] < 0


def test_unwritable_output_folder_is_bad_input(tmp_path, capsys):
    (tmp_path / "file").write_text("not a folder")
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE.format(law="linear", boundary=FIXED, load=-0.1, extra=""))
    code = main(["solve", str(scene), "--model", "fem", "--out", str(tmp_path / "file" / "o")])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith(f"springfem: error: cannot write to {tmp_path / 'file' / 'o'}: ")
    assert err.count("\n") == 1


def test_failure_with_unwritable_output_still_exits_3_and_says_so(tmp_path, capsys):
    (tmp_path / "file").write_text("not a folder")
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE.format(law="linear", boundary="", load=-0.1, extra=""))
    out = tmp_path / "file" / "o"
    code = main(["solve", str(scene), "--model", "fem", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 3 and err.count("\n") == 1
    assert f"(the last good state could not be written to {out}: " in err


@pytest.mark.slow
def test_spring_static_divergence_under_a_huge_load(tmp_path, capsys):
    # ~10 s: Newton with cut-backs, then dynamic relaxation, both give up
    code, lines, out = solve(tmp_path, capsys, "spring", load=-1.0e9)
    assert code == 3
    line = check_failure(lines, out, "last good")
    assert "static solve did not converge" in line and "load factor" in line
