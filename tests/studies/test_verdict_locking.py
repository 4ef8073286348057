"""``springfem verdict`` and ``compare`` on nearly incompressible organ-like gmsh scenes.

- A neo-Hookean sphere at ν = 0.49 with ``[fem] formulation = "mixed"``, ``order = 2``
  (refused before: its P1 rows inherited the P2/P1 formulation) runs through both commands:
  every P1 row solves the nearest locking-free formulation of its law, and a note says so.
- A kidney-shaped neo-Hookean body at ν = 0.49: the verdict weighs the locking-free methods,
  its reference is P2/P1 mixed, and the cheapest model within 5 % it names is a locking-free
  one or P2/P1 mixed itself. Independent of the code's own numbers: displacement P1 locks
  (far off the mixed solution, the known failure of linear tets near ν = 1/2), and every
  locking-free linear tet of the same law is nearer the mixed solution than the locking
  displacement P1 of that law.
"""

from __future__ import annotations

import json

import pandas as pd
import pytest

from studies.cli import main

LOCKING_FREE = ("fem-P1-nodal-strain", "fem-P1-nodal-volume", "fem-MINI", "spring-stabilised")

SPHERE = """
name = "nh-sphere"
[mesh]
file = "sphere.msh"
[material]
law = "neo-hookean"
E = 5000.0
nu = 0.49
[[boundary]]
region = {{ box = [[-1, -1, -1], [1, 1, -0.015]] }}
fix = ["x", "y", "z"]
[[load]]
type = "pressure"
region = {{ box = [[-1, -1, 0.012], [1, 1, 1]] }}
value = 100.0
[[probe]]
name = "side"
point = [0.0141421356, 0.0, 0.0141421356]
{fem}
"""

KIDNEY = """
name = "kidney"
units = "mm-kPa"
[mesh]
file = "kidney.msh"
[material]
law = "neo-hookean"
E = 5.0
nu = 0.49
[[boundary]]
region = { box = [[-60, -40, -30], [-40, 40, 30]] }
fix = ["x", "y", "z"]
[[load]]
type = "pressure"
region = { box = [[-60, -40, 10], [60, 40, 30]] }
value = 0.02
[[probe]]
name = "pole"
point = [55.0, 0.0, 0.0]
"""


def _gmsh(path, build, size: float) -> None:
    gmsh = pytest.importorskip("gmsh")
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("organ")
        build(gmsh.model.occ)
        gmsh.model.occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        volumes = [tag for _, tag in gmsh.model.getEntities(3)]
        gmsh.model.addPhysicalGroup(3, volumes, name="body")
        gmsh.model.mesh.generate(3)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()


def _kidney_shape(occ) -> None:
    """An ellipsoid of 110 x 60 x 44 mm with a notch cut in one long side (the hilum)."""
    body = occ.addSphere(0, 0, 0, 1.0)
    occ.dilate([(3, body)], 0, 0, 0, 55.0, 30.0, 22.0)
    notch = occ.addCylinder(0, 38.0, -30.0, 0, 0, 60.0, 20.0)
    occ.cut([(3, body)], [(3, notch)])


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    d = tmp_path_factory.mktemp("organs")
    _gmsh(d / "sphere.msh", lambda occ: occ.addSphere(0, 0, 0, 0.02), 0.01)
    _gmsh(d / "kidney.msh", _kidney_shape, 12.0)
    (d / "sphere.toml").write_text(SPHERE.format(fem='[fem]\nformulation = "mixed"\norder = 2'))
    (d / "kidney.toml").write_text(KIDNEY)
    return d


def test_a_mixed_neo_hookean_scene_runs_through_verdict(folder, tmp_path, capsys):
    argv = ["verdict", str(folder / "sphere.toml"), "--json", "--out", str(tmp_path / "v"),
            "--models", "P1,P1-NH,P2-NH"]  # fmt: skip
    assert main(argv) == 0
    v = json.loads(capsys.readouterr().out)
    t = pd.DataFrame(v["rows"]).set_index("model")
    assert (t["status"] == "ok").all(), t["message"].to_dict()
    assert v["reference"] == "fem-P2-mixed"  # nearly incompressible neo-Hookean
    assert any('P1 solves "nodal-strain"' in n and 'P1-NH "mini"' in n for n in v["notes"])
    assert any("snapped to the nearest boundary point" in n for n in v["notes"])  # the probe
    assert "fem-P2-mixed" in v["sentence"] and (tmp_path / "v" / "verdict.md").is_file()
    assert v["sentence"] in (tmp_path / "v" / "verdict.md").read_text()


def test_a_mixed_neo_hookean_scene_runs_through_compare(folder, tmp_path, capsys):
    argv = ["compare", str(folder / "sphere.toml"), "--json", "--out", str(tmp_path / "c")]
    assert main(argv) == 0
    c = json.loads(capsys.readouterr().out)
    t = pd.DataFrame(c["rows"]).set_index("model")
    assert t.at["P1", "law"] == "linear/nodal-strain"
    assert t.at["P1-NH", "law"].endswith("mini-P1bP1")
    assert t.at["P2-NH", "law"].endswith("mixed-P2P1")
    assert c["reference"] == "P2-NH"  # the scene's own P2/P1 mixed, which fem-P2-mixed is
    assert any("P2/P1 mixed (P2-NH) is the reference" in n for n in c["notes"])
    # solved once: fem-MINI is P1-NH here, fem-P2-mixed is P2-NH
    assert "fem-P1-nodal-strain" in t.index and "fem-MINI" not in t.index
    assert "fem-P2-mixed" not in t.index


def _kidney_verdict(folder, out, capsys, models: str | None = None) -> tuple[dict, pd.DataFrame]:
    argv = ["verdict", str(folder / "kidney.toml"), "--json", "--out", str(out)]
    assert main(argv + (["--models", models] if models else [])) == 0
    v = json.loads(capsys.readouterr().out)
    return v, pd.DataFrame(v["rows"]).set_index("model")


def _check_kidney(v: dict, t: pd.DataFrame) -> None:
    assert v["reference"] == "fem-P2-mixed"
    assert any("nearly incompressible (nu = 0.49 >= 0.45)" in n for n in v["notes"])
    pick = v["static"]
    assert pick in (*LOCKING_FREE, "fem-P2-mixed"), (pick, t["rel L2 error"].to_dict())
    assert v["sentence"].startswith(pick) and len(v["sentence"].split(". ")) <= 2
    err = t["rel L2 error"]
    assert err["P1"] > 0.05 and err["P1-NH"] > 0.05  # displacement P1 locks
    for m in {"fem-P1-nodal-strain", "fem-P1-nodal-volume", "fem-MINI"} & set(t.index):
        assert err[m] < err["P1-NH"], m  # same law, free of the volume constraints
    # a small-strain model's speed is not compared like for like with the neo-Hookean law
    assert t.at["P1", "law vs reference"] == "small-strain law"


def test_on_a_kidney_at_nu_0_49_the_verdict_picks_a_locking_free_method(folder, tmp_path,
                                                                        capsys):  # fmt: skip
    """The cheaper variant: the default candidates include the locking-free methods (no
    solve), and a verdict over a few of them adds the P2/P1 mixed reference itself."""
    from springfem.scene import load_scene
    from studies.verdict import candidate_models

    assert set(LOCKING_FREE) <= set(candidate_models(load_scene(folder / "kidney.toml")))
    v, t = _kidney_verdict(folder, tmp_path / "k", capsys, "P1,P1-NH,fem-P1-nodal-strain")
    assert "fem-P2-mixed" in t.index
    _check_kidney(v, t)


@pytest.mark.slow
def test_on_a_kidney_every_default_model_is_weighed(folder, tmp_path, capsys):
    """The full default verdict (about 15 s of CPU; minutes of wall time on a busy machine)."""
    v, t = _kidney_verdict(folder, tmp_path / "k", capsys)
    assert set(LOCKING_FREE) <= set(t.index)
    _check_kidney(v, t)
    assert t.at["spring-exact", "law vs reference"] == "small-strain calibration"


@pytest.mark.parametrize("formulation", ["nodal-strain", "nodal-volume", "mini"])
def test_p2_rows_of_a_linear_tet_scene_solve_a_formulation_of_their_order(formulation):
    """A scene of linear-tet formulation (order 1) gives its P2 rows the nearest P2 one:
    P2/P1 mixed for neo-Hookean, the displacement P2 for the small-strain law."""
    from springfem.scene import scene_from_dict
    from studies.models import run

    scene = scene_from_dict({
        "mesh": {"generator": "box", "size": [4.0, 1.0, 1.0], "divisions": [4, 1, 1]},
        "material": {"law": "neo-hookean", "E": 10.0, "nu": 0.49},
        "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
        "load": [{"type": "traction", "region": "x_max", "value": [0.0, 0.0, -0.01]}],
        "fem": {"formulation": formulation},
    })  # fmt: skip
    laws = {m: run(scene, m).solution.result.law for m in ("P1-NH", "P2-NH", "P2")}
    assert laws["P1-NH"].endswith({"mini": "mini-P1bP1"}.get(formulation, formulation))
    assert laws["P2-NH"].endswith("mixed-P2P1") and laws["P2"] == "linear"


def test_a_failed_extra_locking_free_model_is_a_row_not_a_failed_compare(tmp_path, capsys,
                                                                         monkeypatch):  # fmt: skip
    """compare's exit code stays 0 when one of the locking-free models it adds fails (its
    row says FAILED, a note names it); a failure of a model asked for is still exit 3."""
    from springfem.errors import SolverError
    from studies import compare_output
    from studies import models as Model  # the registry: its solve_model is run's solve

    real = Model.solve_model

    def failing(self, scene, verbose=False):
        if self.name == "fem-P1-nodal-volume":
            raise SolverError("singular saddle-point system (made up by the test)")
        return real(self, scene, verbose)

    monkeypatch.setattr(Model, "solve_model", failing)
    monkeypatch.setattr(compare_output, "render_comparison", lambda cmp, path: path)
    scene = tmp_path / "box.toml"
    scene.write_text(
        '[mesh]\ngenerator = "box"\nsize = [4.0, 1.0, 1.0]\ndivisions = [4, 1, 1]\n'
        '[material]\nlaw = "neo-hookean"\nE = 10.0\nnu = 0.49\n'
        '[[boundary]]\nregion = "x_min"\nfix = ["x", "y", "z"]\n'
        '[[load]]\ntype = "traction"\nregion = "x_max"\nvalue = [0.0, 0.0, -0.01]\n'
    )
    assert main(["compare", str(scene), "--out", str(tmp_path / "a")]) == 0
    err = capsys.readouterr().err
    assert "note: fem-P1-nodal-volume (a locking-free method weighed too) failed" in err
    df = pd.read_csv(tmp_path / "a" / "compare.csv").set_index("model")
    assert df.at["fem-P1-nodal-volume", "status"] == "FAILED"
    args = [
        "compare",
        str(scene),
        "--out",
        str(tmp_path / "b"),
        "--models",
        "P1,fem-P1-nodal-volume",
    ]
    assert main(args) == 3  # asked for by name: a failure of the comparison
