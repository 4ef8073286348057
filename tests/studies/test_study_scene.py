"""``springfem study NAME --scene FILE``: studies on a user's own scene.

The scenes are tiny gmsh boxes written to ``tmp_path`` with the gmsh Python API, so each
study runs in seconds.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from support.meshes import gmsh_box

from studies.cli import main

SCENE = """
name = "gbox"
[mesh]
file = "{mesh}"
[material]
law = "linear"
E = 1.0e4
nu = 0.3
[axes]
fiber = [1.0, 0.0, 0.0]
sheet = [0.0, 1.0, 0.0]
[[boundary]]
region = "x_min"
fix = ["x", "y", "z"]
[[load]]
type = "traction"
region = "x_max"
value = [0.0, 0.0, -0.1]
[[probe]]
name = "tip"
point = [0.1, 0.01, 0.01]
"""


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory):
    d = tmp_path_factory.mktemp("gscene")
    gmsh_box(d / "box.msh", 0.02)
    (d / "scene.toml").write_text(SCENE.format(mesh="box.msh"))
    return d / "scene.toml"


@pytest.fixture(scope="module")
def accuracy_out(scene_file, tmp_path_factory):
    """``springfem study accuracy --scene`` on the gmsh box as written (nu = 0.3): its exit
    code and output folder, shared by the tests that read that run."""
    out = tmp_path_factory.mktemp("accuracy")
    code = main(["study", "accuracy", "--scene", str(scene_file), "--out", str(out)])
    return code, out


def test_accuracy_on_a_gmsh_scene(accuracy_out):
    """On an unstructured gmsh mesh a scene with no ``[spring]`` section gets the exact
    element, which matches P1 neo-Hookean to higher order in the strain (below the max
    Green-Lagrange strain; docs/theory.rst#the-exact-element-is-the-p1-element: its
    small-strain element is P1's), and the findings say that it is the exact element."""
    code, out = accuracy_out
    assert code == 0
    e = pd.read_csv(out / "accuracy" / "accuracy_errors.csv").set_index("scene")
    assert list(e.index) == ["gbox"]
    strain = e.at["gbox", "max strain (ref)"]
    assert e.at["gbox", "exact model nh err L2"] < strain
    assert e.at["gbox", "model nh err L2"] == pytest.approx(e.at["gbox", "exact model nh err L2"])
    findings = " ".join(json.loads((out / "accuracy" / "output.json").read_text())["findings"])
    assert "is the exact element" in findings and "drops from" not in findings
    assert (out / "accuracy" / "error_field_gbox.png").read_bytes()[:4] == b"\x89PNG"


def test_set_changes_the_scene(scene_file, accuracy_out, tmp_path):
    """``--set material.nu=0.45`` reaches the solve: P1's volume change (1 - 2 nu) falls
    below that of the scene as written (nu = 0.3, the shared run)."""
    args = ["study", "accuracy", "--scene", str(scene_file), "--out", str(tmp_path)]
    assert main([*args, "--set", "material.nu=0.45"]) == 0
    runs = {0.45: tmp_path, 0.3: accuracy_out[1]}
    v = {nu: abs(pd.read_csv(out / "accuracy" / "accuracy_errors.csv").at[0, "ref volume change"])
         for nu, out in runs.items()}  # fmt: skip
    assert v[0.45] < v[0.3]


def test_convergence_by_refinement_of_a_file_mesh(scene_file, tmp_path):
    """Uniform refinement of the gmsh mesh (each tet into 8): the level-2 mesh has 8x the
    tets, P1's error against the finest P2 falls, P2 beats P1 on the same mesh, and the exact
    element's error equals P1's to O(rotation) (its small-strain element is P1's)."""
    from studies import study_convergence
    from studies.cache import CaseCache
    from studies.registry import StudyContext
    from studies.scenes import StudyScene

    out = tmp_path / "out" / "convergence"
    ctx = StudyContext("convergence", out, True, CaseCache(tmp_path, "c"), False)
    scenes = [StudyScene.from_file(scene_file)]
    study_convergence.run(ctx, scenes, study_convergence.Settings.quick())
    df = pd.read_csv(out / "convergence_levels.csv")
    d = df.set_index(["model", "factor"])
    assert d.at[("P1", 2), "tets"] == 8 * d.at[("P1", 1), "tets"]
    err = "L2 err (level-1 vertices)"
    assert d.at[("P1", 2), err] < d.at[("P1", 1), err]
    assert d.at[("P2", 1), err] < d.at[("P1", 1), err]
    # the tip rotation of this beam is ~0.03 rad: the finite-strain spring model's field
    # differs from the linear P1 field by that relative amount at most
    for k in (1, 2):
        assert d.at[("spring-exact", k), err] == pytest.approx(d.at[("P1", k), err], abs=0.03)
    assert np.isfinite(d[err]).all()


@pytest.mark.parametrize(
    "name, why", [("scaling", "generated box meshes"), ("tissue", "its own bundled tissue scenes")]
)
def test_a_study_that_cannot_run_on_a_scene_says_why(scene_file, tmp_path, capsys, name, why):
    code = main(["study", name, "--scene", str(scene_file), "--out", str(tmp_path)])
    assert code == 2
    err = capsys.readouterr().err
    assert f"study {name} cannot run on --scene" in err
    assert why in err
    assert err.count("\n") == 1  # one line, no traceback


@pytest.mark.slow
def test_ablation_on_a_gmsh_scene(scene_file, tmp_path):
    """Every variant on the user's mesh against its own P1: the exact element is within
    O(tip rotation ~ 0.03) of P1 (its small-strain element is P1's,
    docs/theory.rst#the-exact-element-is-the-p1-element) and becomes
    the most accurate variant; the specification-only winner columns are kept beside it."""
    out = tmp_path / "out"
    args = ["study", "ablation", "--quick", "--scene", str(scene_file), "--out", str(out),
            "--tolerance", "0.05"]  # fmt: skip
    assert main(args) == 0
    w = pd.read_csv(out / "ablation" / "winners.csv").set_index("scene")
    assert list(w.index) == ["gbox"]
    # the tolerance's pick, read back against the per-variant table: the fastest variant
    # whose model error is at most 0.05 (the exact element qualifies, so not "none")
    rows = pd.read_csv(out / "ablation" / "ablation.csv")
    ok = rows[(rows.status == "ok") & (rows.error <= 0.05)]
    pick = w.at["gbox", "cheapest with error <= 0.05 (with exact)"]
    assert pick != "none" and pick in set(ok.variant)
    from studies.study_ablation import TIME_TIE  # ties towards fewer parts

    assert ok.set_index("variant").at[pick, "solve_time"] <= (1 + TIME_TIE) * ok.solve_time.min()
    assert w.at["gbox", "best (with exact)"] in (
        "spring-exact-no-coupling",
        "spring-exact+coupling",
    )
    assert w.at["gbox", "best error (with exact)"] < 0.03
    assert w.at["gbox", "best error"] > w.at["gbox", "best error (with exact)"]


def test_set_without_scene_is_an_input_error(tmp_path, capsys):
    assert main(["study", "accuracy", "--set", "material.nu=0.4", "--out", str(tmp_path)]) == 2
    assert "--set needs --scene" in capsys.readouterr().err


def test_executor_cache_writes_each_case_and_resumes(tmp_path):
    """The study cache on a 1-process LocalCluster: results in case order, one file per case,
    and a rerun computes nothing (its work would raise)."""
    import os

    from studies.cache import CaseCache
    from studies.executor import WORKER_ENV

    before = {k: os.environ.get(k) for k in WORKER_ENV}
    cache = CaseCache(tmp_path, "t", "fp", workers=1)
    cases = [{"a": 1}, {"a": 2}, {"a": 3}]
    assert cache.run(cases, dict, progress=False) == cases
    # the workers' one-thread environment does not outlive the cluster in this process
    # (numba raises at the next compile if NUMBA_NUM_THREADS changed after its threads ran)
    assert {k: os.environ.get(k) for k in WORKER_ENV} == before
    assert len(list((tmp_path / "t").glob("*.json"))) == 3

    def boom(case):
        raise AssertionError("recomputed a cached case")

    assert CaseCache(tmp_path, "t", "fp", workers=1).run(cases, boom, False) == cases
