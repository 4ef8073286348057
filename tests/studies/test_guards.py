"""Guard rails: implausible input warns, caps stop a solve (exit 3), -v shows progress,
compare never ranks against a weaker reference, and small points of the command line.

Independent references: the cantilever's tip deflection is linear in 1/E (small-strain
law), so E = 0.01 Pa turns the bundled ~1e-3 m tip into ~1e3 m, ten thousand times the
0.1 m beam; the bundled scene itself (E = 1e4 Pa, tip ~ 2 mm, strain < 1 %) must not warn.
"""

import json
import re

import numpy as np
import pytest

from springfem.errors import SolverError
from studies import compare
from studies.cli import main
from studies.solve import Solution

SOFT = ["--set", "material.E=0.01"]


def _warnings(err: str) -> list[str]:
    return [line for line in err.splitlines() if line.startswith("warning: ")]


def test_bundled_cantilever_does_not_warn(tmp_path, capsys):
    assert main(["solve", "cantilever", "--model", "fem", "--out", str(tmp_path)]) == 0
    assert _warnings(capsys.readouterr().err) == []


def test_wrong_modulus_warns_on_input_and_on_the_solution(tmp_path, capsys):
    assert main(["solve", "cantilever", "--model", "fem", "--out", str(tmp_path), *SOFT]) == 0
    w = _warnings(capsys.readouterr().err)
    # the modulus first, then the solution's checks (springfem.plausibility)
    assert "E = 0.01 Pa is outside 10 Pa" in w[0]
    (big,) = [line for line in w if "exceeds the body's size" in line]
    size = float(re.search(r"size ([0-9.e+-]+):", big).group(1))
    assert size == pytest.approx(np.sqrt(0.1**2 + 2 * 0.01**2), rel=1e-3)  # box diagonal
    (strain,) = [line for line in w if "small-strain" in line]
    assert "neo-hookean" in strain


def test_max_time_stops_a_relaxation_with_exit_3(tmp_path, capsys):
    out = tmp_path / "spring"
    cap = 1.0
    argv = ["solve", "cantilever", "--out", str(out), *SOFT, "--set", "spring.solver=explicit",
            "--max-time", str(cap)]  # fmt: skip
    assert main(argv) == 3
    err = capsys.readouterr().err.strip().splitlines()[-1]
    m = re.search(r"stopped after ([0-9.]+) s / (\d+) steps at relative residual ([0-9.e+-]+)", err)
    assert m, err
    # checked at every force evaluation: the stop comes within one step (~1 ms here) of the
    # cap; 0.5 s of slack for a busy machine
    assert cap <= float(m.group(1)) < cap + 0.5
    assert int(m.group(2)) > 0 and float(m.group(3)) > 0
    assert "last state written to" in err
    state = json.loads((out / "last_good_state.json").read_text())
    assert state["status"].startswith("stopped after")
    assert np.abs(state["probes"]["tip"]).max() > 0  # it moved: not the initial state


def test_max_steps_stops_a_timed_run_after_exactly_n_steps(tmp_path, capsys):
    argv = ["solve", "sag", "--out", str(tmp_path), "--set", "spring.solver=explicit",
            "--set", "spring.steps=100", "--set", "mesh.divisions=[8, 4, 2]",
            "--max-steps", "7"]  # fmt: skip
    assert main(argv) == 3
    err = capsys.readouterr().err
    assert "/ 7 steps at" in err and "the cap of 7 steps" in err


def test_verbose_shows_newton_residuals_of_the_spring_static_solve(tmp_path, capsys):
    assert main(["solve", "cantilever", "--out", str(tmp_path), "-v"]) == 0
    lines = [x for x in capsys.readouterr().err.splitlines() if x.startswith("newton iteration")]
    assert lines
    r = [float(x.rsplit(" ", 1)[1]) for x in lines]
    assert r[-1] <= 1e-8  # the spring options' default tolerance: the last line is converged


def test_verbose_shows_relaxation_residuals(tmp_path, capsys, monkeypatch):
    from springfem.mechanics import relaxation

    monkeypatch.setattr(relaxation, "PROGRESS_EVERY", 0.0)
    argv = ["solve", "cantilever", "--out", str(tmp_path), "-v", "--set",
            "spring.solver=explicit", "--set", "mesh.divisions=[10, 1, 1]"]  # fmt: skip
    assert main(argv) == 0
    lines = [x for x in capsys.readouterr().err.splitlines() if x.startswith("relaxation step")]
    assert len(lines) >= 2
    r = [float(re.search(r"residual ([0-9.e+-]+)", x).group(1)) for x in lines]
    assert r[-1] < r[0]


def test_order_and_law_are_refused_for_the_spring_model(capsys):
    assert main(["solve", "cantilever", "--order", "2"]) == 2
    assert "--order applies to --model fem only" in capsys.readouterr().err


def test_solve_line_names_the_spring_model_once(tmp_path, capsys):
    assert main(["solve", "cantilever", "--out", str(tmp_path), "--set",
                 "mesh.divisions=[10, 1, 1]"]) == 0  # fmt: skip
    line = capsys.readouterr().out.splitlines()[0]
    assert line.startswith("cantilever: spring [axial=") and line.count("spring") == 1


# ------------------------------------------------------------------ compare's reference


@pytest.fixture
def fake_models(monkeypatch):
    """``Model.solve`` with chosen failures: every model solves to a known field."""
    from springfem.result import Result
    from studies import models as Model  # the registry: its solve_model is run's solve

    failing: set[str] = set()

    def solve(self, scene, verbose=False):
        name = self.name
        if name in failing:
            raise SolverError(f"{name} diverged at load factor 0.64")
        u = np.full((scene.mesh.n_points, 3), {"spring": 1.1}.get(name, 1.0))
        r = Result(scene.name, name, name, name, {}, scene.probe_displacements(u), {}, {},
                   0.0, True, 1)  # fmt: skip
        return Solution(r, u)

    monkeypatch.setattr(Model, "solve_model", solve)
    return failing


def _neo_scene():
    from studies.overrides import load_scene_with

    return load_scene_with("studies/scenes/sag.toml", ["mesh.divisions=[2, 1, 1]"])


def test_compare_never_ranks_against_a_small_strain_reference(fake_models):
    fake_models.update({"P1-NH", "P2-NH"})
    scene = _neo_scene()
    models = ["spring", "P1", "P2", "P1-NH", "P2-NH"]
    with pytest.raises(SolverError, match="no finite-strain reference"):
        compare.compare_scene(scene, models=models)
    cmp = compare.compare_scene(scene, models=models, allow_no_reference=True)
    assert cmp.reference == ""
    t = cmp.table.set_index("model")
    assert list(t.loc[["P1-NH", "P2-NH"], "status"]) == ["FAILED", "FAILED"]
    assert np.isnan(t.loc["spring", "rel L2 err"])  # not ranked against linear P2 (10%)


def test_compare_falls_back_to_p1_nh_and_says_so(fake_models):
    fake_models.add("P2-NH")
    cmp = compare.compare_scene(_neo_scene(), models=["spring", "P1", "P2", "P1-NH", "P2-NH"])
    assert cmp.reference == "P1-NH"
    assert any("P2-NH FAILED" in n and "P1-NH" in n for n in cmp.notes)
    assert cmp.table.set_index("model").loc["spring", "rel L2 err"] == pytest.approx(0.1)


def test_study_help_lists_the_registered_studies(capsys):
    from studies.runner import REGISTRY

    with pytest.raises(SystemExit) as exc:
        main(["study", "--help"])
    assert exc.value.code == 0
    text = capsys.readouterr().out
    listed = text.split("studies (* also runs on --scene FILE):", 1)[1]
    assert REGISTRY and all(f"  {n.replace('_', '-')} " in listed for n in REGISTRY)
    rows = {line.split()[0]: line.split()[1] == "*" for line in listed.strip().splitlines()}
    # the mark is the registry's: a study runs on --scene unless it says why not
    assert rows == {n.replace("_", "-"): s.user_scenes is None for n, s in REGISTRY.items()}
    assert not rows["scaling"] and rows["stability"]


def test_p2_result_says_it_is_reduced_to_vertices(tmp_path, capsys):
    argv = ["solve", "cantilever", "--model", "fem", "--order", "2", "--out", str(tmp_path),
            "--set", "mesh.divisions=[4, 1, 1]"]  # fmt: skip
    assert main(argv) == 0
    assert "reduced to the mesh vertices" in capsys.readouterr().out
    res = json.loads((tmp_path / "result.json").read_text())
    assert "vertex_output" in res["info"]


def test_verbose_shows_the_fem_newton_residuals(tmp_path, capsys):
    argv = ["solve", "sag", "--model", "fem", "-v", "--out", str(tmp_path),
            "--set", "mesh.divisions=[4, 2, 1]"]  # fmt: skip
    assert main(argv) == 0
    assert "|R|/|f|" in capsys.readouterr().err


def test_max_time_stops_the_fem_newton_with_exit_3(tmp_path, capsys):
    # the FEM's Newton checks its deadline at every checkpoint (assembly, factorisation,
    # each iteration): a 1 ns cap stops it at the first one, with the last converged state
    # (rest, load factor 0)
    argv = ["solve", "cantilever", "--model", "fem", "--out", str(tmp_path),
            "--set", "material.law=neo-hookean", "--max-time", "1e-9"]  # fmt: skip
    assert main(argv) == 3
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert re.search(r"stopped after [0-9.e+-]+ s / start \(the --max-time cap of 1e-09 s\)", err)
    assert "last converged load factor 0;" in err and "last state written to" in err
    state = json.loads((tmp_path / "last_good_state.json").read_text())
    assert state["status"].startswith("stopped after")


def test_a_locking_formulation_warns_once_and_names_the_fix(tmp_path, capsys):
    """nu = 0.499 (the issue's cantilever case) with the default options: both models'
    formulations lock; the locking-free options silence the FEM's line."""
    argv = ["solve", "cantilever", "--model", "fem", "--out", str(tmp_path / "a"),
            "--set", "material.nu=0.499"]  # fmt: skip
    assert main(argv) == 0
    (line,) = [w for w in _warnings(capsys.readouterr().err) if "locks" in w]
    assert "nu = 0.499" in line and 'formulation = "nodal-strain"' in line
    argv += ["--set", 'fem.formulation="nodal-volume"', "--out", str(tmp_path / "b")]
    assert main(argv) == 0
    assert not [w for w in _warnings(capsys.readouterr().err) if "locks" in w]


def test_locking_lines_name_each_models_fix():
    from studies.guards import locking_warnings
    from studies.overrides import load_scene_with
    from studies.scenes import scene_path

    soft = load_scene_with(scene_path("cantilever"), ["material.nu=0.499"])
    fem, spring = locking_warnings(soft)
    assert "[fem]" in fem and "[spring]" in spring and 'volume_average = "nodal"' in spring
    nodal = load_scene_with(scene_path("cantilever"), ["material.nu=0.499", 'spring.volume="axes"',
                                           'spring.volume_average="nodal"'])  # fmt: skip
    assert locking_warnings(nodal, ("spring",)) == []
