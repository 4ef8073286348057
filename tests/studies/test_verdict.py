"""``springfem verdict`` on a gmsh mesh: the cheapest model within the tolerance is the one
the table measures, and the sentence names it.

The scene is a block in uniaxial stress on an unstructured gmsh mesh: a uniform strain, so
P1 and P2 reproduce it exactly (P1's error is round-off) and the exact spring element
differs from them only by its finite-strain kinematics, O(strain) = 1e-3; the
specification's element misses the Poisson coupling on these tets by far more.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from studies.cli import main

SCENE = """
name = "gblock"
[mesh]
file = "block.msh"
[material]
law = "linear"
E = 1.0e4
nu = 0.3
density = 1000.0
[[boundary]]
region = "x_min"
fix = ["x"]
[[boundary]]
region = {{ point = [0.0, 0.0, 0.0] }}
fix = ["y", "z"]
[[boundary]]
region = {{ point = [0.0, 0.02, 0.0] }}
fix = ["z"]
[[load]]
type = "traction"
region = "x_max"
value = [{sigma}, 0.0, 0.0]
"""


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    gmsh = pytest.importorskip("gmsh")
    d = tmp_path_factory.mktemp("verdict")
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("block")
        gmsh.model.occ.addBox(0, 0, 0, 0.04, 0.02, 0.02)
        gmsh.model.occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.008)
        gmsh.model.addPhysicalGroup(3, [1], name="body")
        gmsh.model.mesh.generate(3)
        gmsh.write(str(d / "block.msh"))
    finally:
        gmsh.finalize()
    (d / "block.toml").write_text(SCENE.format(sigma=10.0))
    return d / "block.toml"


def test_verdict_names_the_measured_cheapest_model(scene, tmp_path, capsys):
    out = tmp_path / "v"
    argv = ["verdict", str(scene), "--json", "--out", str(out),
            "--models", "spring-spec,spring-exact,P1,P2"]  # fmt: skip
    assert main(argv) == 0
    v = json.loads(capsys.readouterr().out)
    t = pd.DataFrame(v["rows"]).set_index("model")
    assert v["reference"] == "P2"
    assert t.at["P1", "rel L2 error"] < 1e-9  # the patch test
    assert t.at["spring-exact", "rel L2 error"] < 3e-3  # O(strain) = 1e-3
    assert t.at["spring-spec", "rel L2 error"] > 10 * t.at["spring-exact", "rel L2 error"]
    ok = t[t["within tolerance"]]  # the reference too: a dearer model is no answer
    static = ok["static time (s)"].idxmin()
    assert static != "P2"  # P1 solves the patch test exactly on the same mesh, and sooner
    dynamic = ok["cost per simulated s"].dropna().idxmin()
    assert v["static"] == static and v["dynamic"] == dynamic
    assert v["sentence"].startswith(f"{static} is the cheapest static solve within 5% of P2: ")
    same = "For explicit dynamics it is too: "
    assert (same if dynamic == static else f"For explicit dynamics {dynamic} is: ") in v["sentence"]
    assert "faster" not in v["sentence"] and len(v["sentence"].split(". ")) == 2
    ratio = t.at[static, "static time (s)"] / t.at["P2", "static time (s)"]
    assert f"in {ratio:.2g}× the reference's time" in v["sentence"]
    assert v["sentence"] in (out / "verdict.md").read_text()
    assert np.isfinite(t.at["spring-exact", "stable step (s)"])
    assert (out / "verdict.csv").is_file()


def test_verdict_with_a_tolerance_nothing_meets(scene, tmp_path, capsys):
    """A tolerance below every error but the reference's picks nothing, and says so."""
    argv = ["verdict", str(scene), "--json", "--out", str(tmp_path / "a"),
            "--models", "spring-exact,P2", "--tolerance", "1e-12"]  # fmt: skip
    assert main(argv) == 0
    v = json.loads(capsys.readouterr().out)
    assert v["static"] == "P2"
    assert v["sentence"].startswith("P2, the reference, is the cheapest static solve within")


def test_a_reference_stopped_by_the_budget_is_replaced_with_a_note(scene, tmp_path, capsys,
                                                                   monkeypatch):  # fmt: skip
    """When the reference's solve is stopped (the budget's cap), the next finest FEM that
    finishes stands in, and a note names the substitution."""
    from springfem.mechanics.limits import SolveStopped
    from studies import models as Model  # the registry: its solve_model is run's solve

    real = Model.solve_model

    def capped(self, s, verbose=False):
        if self.name == "P2":
            raise SolveStopped("stopped after 0.1 s")
        return real(self, s, verbose)

    monkeypatch.setattr(Model, "solve_model", capped)
    argv = ["verdict", str(scene), "--json", "--out", str(tmp_path / "b"),
            "--models", "spring-exact,P1,P2", "--budget", "600"]  # fmt: skip
    assert main(argv) == 0
    v = json.loads(capsys.readouterr().out)
    assert v["reference"] == "P1"
    assert any("the reference P2 did not finish (stopped after 0.1 s); P1 stands in" in n
               for n in v["notes"])  # fmt: skip
