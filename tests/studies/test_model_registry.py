"""One model registry, one solution type, one reference choice.

- Every model the command line knows (the ``valid models`` its unknown-model error lists,
  and every name the studies weigh) is a model of :mod:`springfem.model_api`'s registry,
  from its own package's entry point.
- No study switches on a model's kind: the models declare what they apply to.
- The comparisons take the verdict's reference: on a nearly incompressible neo-Hookean
  organ the accuracy study's comparison is against P2/P1 mixed, not locking P1-NH (which
  would give its own same-mesh P1 a discretisation error of zero).
- The Python API solves any registered model and returns its warnings.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import springfem
from springfem.api import get_model
from springfem.errors import InputError
from springfem.model_api import ModelSolution, plugin_models
from springfem.scene import scene_from_dict
from studies import models
from studies.cli import main
from studies.compare import compare_scene, max_principal_strain

ROOT = Path(__file__).resolve().parents[2]
BOX = {
    "mesh": {"generator": "box", "size": [0.1, 0.02, 0.02], "divisions": [3, 1, 1]},
    "material": {"law": "neo-hookean", "E": 1e4, "nu": 0.3},
    "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
    "load": [{"type": "traction", "region": "x_max", "value": [0, 0, -1.0]}],
}


def test_every_model_the_cli_lists_is_in_the_one_registry(capsys):
    assert main(["compare", "cantilever", "--models", "no-such-model"]) == 2
    err = capsys.readouterr().err
    listed = re.search(r"valid models: (.*)$", err.strip()).group(1).split(", ")
    registry = plugin_models()
    assert set(listed) == set(registry)
    names = set(models.PRIMARY) | set(models.LOCKING_FREE) | {"fem", "spring-tissue"}
    assert names <= set(listed)
    for name in names:  # each from its own package: the spring model's, the FEM's
        package = type(registry[name]).__module__.split(".")[0]
        assert package == ("springmodel" if name.startswith("spring") else "reference_fem")


def test_no_study_switches_on_a_model_kind():
    pattern = re.compile(r"\bkind\s*(==|!=|\bin\b)\s*[\"'(]?(spring|fem|plugin)\b")
    hits = [
        f"{path.relative_to(ROOT)}:{n}"
        for path in sorted((ROOT / "studies").rglob("*.py"))
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
        if pattern.search(line) or re.search(r"\.kind\b.*[\"'](spring|fem|plugin)[\"']", line)
    ]
    assert hits == []


def test_the_python_api_solves_any_model_with_the_cli_warnings():
    scene = scene_from_dict(BOX)
    nh = springfem.solve(scene, "P1-NH")
    p1 = springfem.solve(scene, springfem.get_model("p1"))
    exact = springfem.solve(scene, "spring-exact")
    assert all(isinstance(s, ModelSolution) for s in (nh, p1, exact))
    # a tip rotation of 2e-3: neo-Hookean is the linear law to about that share
    np.testing.assert_allclose(nh.u, p1.u, atol=3e-3 * np.abs(p1.u).max())
    assert exact.warnings == [] and set(springfem.models()) == set(plugin_models())
    crushed = scene_from_dict({**BOX, "load": [{"type": "traction", "region": "x_max",
                                                "value": [-1e6, 0, 0]}]})  # fmt: skip
    lines = springfem.solve(crushed, "P1").warnings  # linear P1 crushed through itself
    assert any("inverted" in w for w in lines), lines
    with pytest.raises(InputError, match="did you mean P1-NH"):
        get_model("P1-HN")


def test_an_fem_model_says_it_has_no_explicit_nodal_strain_form():
    scene = scene_from_dict(BOX)
    with pytest.raises(InputError, match="not nodal-strain"):
        models.system(models.get("fem-P1-nodal-strain"), scene)
    assert models.system(models.get("P1-NH"), scene).x0.shape == (scene.mesh.n_points, 3)


def test_accuracy_takes_the_verdicts_locking_free_reference(tmp_path):
    pytest.importorskip("gmsh")
    from springfem.mesh.organ import organ_scene
    from springfem.scene import load_scene

    scene = load_scene(organ_scene(tmp_path, 700))  # neo-Hookean, nu = 0.49
    cmp = compare_scene(scene, locking_free=False)  # as the accuracy study runs it
    strain = max_principal_strain(scene, cmp.solutions["P1"].u)
    assert cmp.reference == models.reference_model(scene, strain) == "fem-P2-mixed"
    assert cmp.same_mesh_p1 == "P1-NH"
    # P1-NH locks: its discretisation error against the mixed reference is far from zero
    assert cmp.errors("P1-NH")["rel_l2"] > 0.05
