"""The model plug-in API (springfem.model_api, docs/plugins.rst): a model registered in
Python or by an entry point of an installed package joins compare, verdict, sweeps and the
studies with no edit of studies/.

The out-of-tree example (examples/plugin_model: small-strain linear P1 in numpy) is made an
installed distribution the way pip does it, a ``.dist-info`` folder with its
``entry_points.txt`` written from the package's own ``pyproject.toml`` on the import path of
a fresh process, so the entry point is found by importlib.metadata as for any installed
package. Its independent check: its static solutions are linear P1's (scikit-fem), so its
errors equal P1's. A slow test installs it with pip for real.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from springfem import model_api
from springfem.errors import InputError
from springfem.scene import scene_from_dict
from studies import models
from studies.compare import compare_scene

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "plugin_model"
SCENE = """
name = "plugbar"
[mesh]
generator = "box"
size = [0.1, 0.01, 0.01]
divisions = [8, 2, 2]
[material]
law = "linear"
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
[[probe]]
name = "tip"
point = [0.1, 0.005, 0.005]
"""


def install_like_pip(site: Path) -> None:
    """Copy the example package into ``site`` with a dist-info of its pyproject's entry
    points (what ``pip install --target site`` writes)."""
    meta = tomllib.loads((EXAMPLE / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    shutil.copytree(EXAMPLE / "springfem_example_model", site / "springfem_example_model")
    info = site / f"{meta['name'].replace('-', '_')}-{meta['version']}.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(
        f"Metadata-Version: 2.1\nName: {meta['name']}\nVersion: {meta['version']}\n"
    )
    lines = []
    for group, eps in meta["entry-points"].items():
        lines.append(f"[{group}]")
        lines += [f"{k} = {v}" for k, v in eps.items()]
    (info / "entry_points.txt").write_text("\n".join(lines) + "\n")


def cli(site: Path, *args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(site), MPLBACKEND="Agg", PYVISTA_OFF_SCREEN="true")
    code = "import sys; from studies.cli import main; sys.exit(main(sys.argv[1:]))"
    return subprocess.run([sys.executable, "-c", code, *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=900)  # fmt: skip


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    d = tmp_path_factory.mktemp("plugin")
    site = d / "site"
    site.mkdir()
    install_like_pip(site)
    (d / "plugbar.toml").write_text(SCENE)
    return site, d


def test_the_entry_point_model_runs_through_verdict(installed):
    """``springfem verdict`` weighs the installed model by default; its error against P2
    is linear P1's (the same discretisation solved by scikit-fem)."""
    site, d = installed
    out = cli(site, "verdict", str(d / "plugbar.toml"), "--json", "--out", str(d / "v"), cwd=d)
    assert out.returncode == 0, out.stderr[-2000:]
    table = pd.DataFrame(json.loads(out.stdout)["rows"]).set_index("model")
    assert "example-p1" in table.index and "corotational" in table.index
    assert table.at["example-p1", "status"] == "ok"
    p1, mine = table.at["P1", "rel L2 error"], table.at["example-p1", "rel L2 error"]
    assert p1 > 0.01 and abs(mine - p1) < 1e-6 * p1
    assert np.isfinite(table.at["example-p1", "step cost (s)"])  # its explicit form


def test_the_entry_point_model_runs_through_study_accuracy(installed):
    """``springfem study accuracy --scene`` gives the installed model its own columns: its
    total error is P1's discretisation error, its tip P1's."""
    site, d = installed
    out = cli(site, "study", "accuracy", "--scene", str(d / "plugbar.toml"), "--out",
              str(d / "acc"), cwd=d)  # fmt: skip
    assert out.returncode == 0, out.stderr[-2000:]
    errors = pd.read_csv(next((d / "acc").rglob("accuracy_errors.csv")))
    row = errors.iloc[0]
    assert row["example-p1 total err L2"] == pytest.approx(row["discretisation err L2"], rel=1e-6)
    assert "corotational total err L2" in errors.columns
    probes = pd.read_csv(next((d / "acc").rglob("accuracy_probes.csv")))
    assert probes.iloc[0]["example-p1 (m)"] == pytest.approx(probes.iloc[0]["P1 (m)"], rel=1e-6)


@pytest.mark.slow
def test_pip_installs_the_example_and_its_entry_point(tmp_path):
    """The example's pyproject really installs (pip, into a target folder) with the entry
    point the core finds."""
    shutil.copytree(EXAMPLE, tmp_path / "src")
    site = tmp_path / "site"
    pip = [sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--target", str(site)]
    done = subprocess.run([*pip, str(tmp_path / "src")], capture_output=True, text=True)
    if done.returncode != 0:
        pytest.skip(f"pip could not build the example here: {done.stderr[-300:]}")
    code = "from springfem.model_api import plugin_models; print(sorted(plugin_models()))"
    env = dict(os.environ, PYTHONPATH=str(site))
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert "example-p1" in out.stdout


# -- in Python -------------------------------------------------------------------------------


def test_a_model_registered_in_python_joins_compare(tmp_path):
    """register_model (the entry points' code path) makes a model known by name to the
    registry and to compare; its solution equals P1's."""
    sys.path.insert(0, str(EXAMPLE))
    try:
        from springfem_example_model import LinearP1
    finally:
        sys.path.remove(str(EXAMPLE))
    mine = model_api.SystemModel("py-p1", "linear P1 registered in Python", LinearP1,
                                 default=False)  # fmt: skip
    model_api.register_model(mine)
    try:
        assert models.get("PY-P1") is mine and mine in models.sync_plugins()
        assert "py-p1" not in models.plugins()  # not a default model
        scene = scene_from_dict(tomllib.loads(SCENE))
        cmp = compare_scene(scene, models=["P1", "P2", "py-p1"])
        np.testing.assert_allclose(cmp.solutions["py-p1"].u, cmp.solutions["P1"].u,
                                   atol=1e-9 * np.abs(cmp.solutions["P1"].u).max())  # fmt: skip
        run = mine.run(scene, steps=50)
        assert run.result.status.startswith("end of run at t = ")
    finally:
        model_api._REGISTERED.pop("py-p1")


def test_bad_plugins_are_one_line_errors():
    with pytest.raises(InputError, match="lacks .*solve"):
        model_api.register_model(object)
    corot = models.get("corotational")
    clone = model_api.SystemModel("Corotational", "a second one", lambda scene: None)
    with pytest.raises(InputError, match="registered twice"):
        model_api.register_model(clone)
    assert model_api.register_model(corot) == [corot]  # the same object again is fine


def test_a_broken_entry_point_is_a_warning(monkeypatch, capsys):
    monkeypatch.setattr(model_api, "_LOADED", [])
    monkeypatch.setattr(model_api, "entry_points", lambda group: {"nope": "no_such_pkg:X"})
    got = model_api.plugin_models()
    assert "warning: model plug-in nope (no_such_pkg:X) not loaded" in capsys.readouterr().err
    assert "corotational" in got  # the others stay


def test_a_sweep_takes_a_plugin_by_name(tmp_path):
    """A sweep file's ``models`` takes the plug-in's name: at the bundled cantilever's small
    load co-rotational P1 is linear P1 (same mesh) to O(strain) in every case."""
    from studies.sweep import run_sweep
    from studies.sweep_file import parse_sweep

    spec = parse_sweep({"scene": "cantilever", "models": ["corotational", "P1", "P2"],
                        "grid": {"mesh.divisions": [[4, 1, 1], [8, 1, 1]]}})  # fmt: skip
    run_sweep(spec, tmp_path / "out", progress=False, figures=False)
    t = pd.read_parquet(tmp_path / "out" / "results.parquet")
    assert set(t["status"]) == {"ok"}
    corot = t[t["model"] == "corotational"].set_index("mesh.divisions")["rel_l2"]
    p1 = t[t["model"] == "P1"].set_index("mesh.divisions")["rel_l2"]
    assert len(corot) == 2
    np.testing.assert_allclose(corot.to_numpy(), p1.to_numpy(), rtol=1e-3)


def test_the_studies_weigh_the_default_plugins_where_they_apply():
    """Speed-accuracy gets static and explicit co-rotational points on a linear scene; the
    dynamics study releases it on a linear scene, not on its bundled Guccione beam (no tissue
    law in co-rotational P1); the verdict's candidates include it."""
    import studies.study_dynamics as dynamics
    from studies.scenes import StudyScene
    from studies.study_speed_accuracy import cases as speed

    sc = StudyScene.bundled("cantilever", {"mesh.divisions": [4, 1, 1]})
    pts = speed.points(sc, sc.build(), [1], speed.Settings.quick())
    methods = {(p["model"], p["solution"]) for p in pts}
    assert {("corotational", "static"), ("corotational", "explicit")} <= methods
    assert ("corotational-warped", "static") not in methods  # not a default model
    settings = dynamics.Settings.quick()
    assert "corotational" in dynamics.spring_models(sc.build(), settings)
    beam = dynamics.bundled_scenes(settings)[0].build()
    assert "corotational" not in dynamics.spring_models(beam, settings)
    assert "corotational" in models.candidates()
