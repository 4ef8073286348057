"""The manual's Python API example runs, and the manual shows that very file."""

from __future__ import annotations

import os
import runpy
from pathlib import Path

import meshio
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "python_api.py"


def test_the_manual_shows_the_example_file():
    # docs/usage.rst#python-api includes the file itself, so what it shows is what runs
    usage = (ROOT / "docs" / "usage.rst").read_text(encoding="utf-8")
    assert ".. literalinclude:: ../examples/python_api.py\n" in usage


def test_python_api_example_runs(capsys):
    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        ns = runpy.run_path(str(EXAMPLE), run_name="__main__")
    finally:
        os.chdir(cwd)
    assert "model error" in capsys.readouterr().out
    # VTU round trip: the file holds the displacement that was solved (meshio reads it back)
    back = meshio.read(ns["vtu_path"])
    np.testing.assert_allclose(back.point_data["displacement"], ns["spring_energy"].u, rtol=1e-12)
    # the specification's spring element's documented model error on this mesh
    # (docs/theory.rst#model-error-and-discretisation-error: +7.7% softer
    # than P1 at the tip); 10% is the accuracy goal the spring model was built to
    tip_fem, tip_spring = ns["fem"].result.probes["tip"][2], ns["spring"].result.probes["tip"][2]
    assert 0.0 < tip_spring / tip_fem - 1.0 < 0.10


def test_the_example_plugin_passes_the_conformance_check(monkeypatch, capsys):
    """The out-of-tree example model's own test runs check_model (docs/plugins.rst#plugin-check
    shows that file and what it prints)."""
    plugins = (ROOT / "docs" / "plugins.rst").read_text(encoding="utf-8")
    assert ".. literalinclude:: ../examples/plugin_model/test_example_model.py\n" in plugins
    monkeypatch.syspath_prepend(str(ROOT / "examples" / "plugin_model"))
    ns = runpy.run_path(str(ROOT / "examples" / "plugin_model" / "test_example_model.py"))
    ns["test_the_model_conforms"]()
    out = capsys.readouterr().out
    assert "model example-p1 on scene jittered-box:" in out
    assert out.count(": passed:") == 6 and out.count(": skipped:") == 1
