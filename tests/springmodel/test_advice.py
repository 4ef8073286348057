"""Warnings for a predicted model error (springmodel.advice) in inspect and solve.

The references are the mismatch values themselves (counted here with numpy) and the option
rules: the specification's barycentric volume and cosine torsion are named, and the
exact
options produce no warning.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np

from springfem.scene import scene_from_dict
from springmodel.advice import MISMATCH_WARN, model_warnings
from springmodel.inspect import inspect_scene
from springmodel.options import SpringOptions

SCENES = Path(__file__).resolve().parents[2] / "studies" / "scenes"


def cantilever(**spring) -> dict:
    d = tomllib.loads((SCENES / "cantilever.toml").read_text())
    d["mesh"]["divisions"] = [8, 2, 2]
    d["spring"] = spring
    return d


def test_seed_cantilever_warns_with_count_and_fix():
    from springmodel.model import SpringModel

    scene = scene_from_dict(cantilever(element="seed"))
    report = inspect_scene(scene)
    n_bad = int(np.sum(SpringModel(scene).elements.mismatch > MISMATCH_WARN))
    assert n_bad == report["tets"]  # every six-split tet: mismatch ~0.58, far above 0.1%
    (line,) = report["warnings"]
    assert f"{n_bad} of {report['tets']} tets" in line and len(line) < 250  # the former ran to 400
    for fix in (
        'element = "exact"',
        'volume = "axes"',
        'torsion = "energy"',
        'calibration = "exact"',
    ):
        assert fix in line
    assert "Frobenius" in report["calibration_mismatch_norm"]


def test_exact_options_do_not_warn():
    d = cantilever(volume="axes", torsion="energy", calibration="exact")
    report = inspect_scene(scene_from_dict(d))
    assert report["calibration_mismatch_max"] < 1e-12
    assert report["warnings"] == []
    default = inspect_scene(scene_from_dict(cantilever()))  # the default element is exact
    assert default["calibration_mismatch_max"] < 1e-12 and default["warnings"] == []


def test_transverse_material_asks_for_coupling():
    mm = np.array([0.0, 0.02, 0.5, np.nan])
    opts = SpringOptions(volume="axes", torsion="energy", calibration="exact")
    (line,) = model_warnings(mm, opts, transverse=True)
    # median and max of the finite values; two of the three above 0.1 %
    assert line.startswith("spring model: calibration mismatch 2.00% (median; max 50.00%; 2 of 4")
    assert "coupling = true" in line
    assert model_warnings(np.full(3, np.nan), opts, transverse=True) == []
