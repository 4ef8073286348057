"""``compare`` on finite-strain tissue scenes: the FEM models solve the scene's own law.

Independent references: a direct ``reference_fem.solve`` of the same scene (P2, mixed
Taylor–Hood) and of a scene written out by hand with the stated P1 penalty
``kappa = 1000 mu`` (``mu`` the mean shear modulus of the law's small-strain tangent,
computed here from its closed form), and, at a small load, the spring exact element
against same-mesh P1 (docs/theory.rst#the-exact-element-is-the-p1-element: the exact element is P1
with the law's small-strain
tangent, so at small strain the two differ by O(strain)).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import reference_fem
from springfem.errors import InputError, SolverError
from springfem.materials.tissue import tissue_tangent
from springfem.scene import scene_from_dict
from studies import compare_output
from studies import models as Model  # the registry: its solve_model is run's solve
from studies.cli import main
from studies.compare import compare_scene
from studies.scenes import bundled_table

DIVISIONS = (6, 1, 1)  # 36 tets: every model solves in about a second
#: The Land beam's 0.004 kPa at 1e-3: P1 tip deflection ~1.5e-4 mm on a 10 mm beam.
SMALL = 1e-3
EXACT = {"volume": "axes", "torsion": "energy", "calibration": "exact", "coupling": True}
PARAMS = {"C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0}  # land-beam's Guccione constants
#: Newton stops at a relative residual 1e-10 ([fem] tol); two solves of the same problem
#: agree to about that times the condition number of the incompressible beam: 1e-7.
SOLVER_TOL = 1e-7


def beam(load: float = 1.0, spring: dict | None = None) -> dict:
    data = bundled_table("land-beam", {"mesh.divisions": list(DIVISIONS)})
    data["load"][0]["value"] *= load
    if spring is not None:
        data["spring"] = dict(spring)
    return data


@pytest.fixture(scope="module")
def small_beam():
    """The Land beam at 1e-3 of its load, spring exact element: compare's three models."""
    scene = scene_from_dict(beam(SMALL, EXACT))
    return scene, compare_scene(scene)


def test_models_are_the_scenes_law(small_beam):
    """P1 and P2 solve Guccione (the table's law column), P2 is the reference; no
    neo-Hookean model is run or accepted for a tissue law."""
    scene, cmp = small_beam
    t = cmp.table.set_index("model")
    # the incompressible beam: the locking-free methods too (P2 is P2/P1 mixed already)
    assert list(t.index)[:3] == ["spring", "P1", "P2"] and cmp.reference == "P2"
    assert set(t.index[3:]) == {"fem-P1-nodal-strain", "fem-P1-nodal-volume", "fem-MINI",
                                "spring-stabilised", "spring-tissue-stabilised"}  # fmt: skip
    assert t.at["P2", "law"].startswith("guccione") and t.at["P1", "law"].startswith("guccione")
    assert t.at["P2", "element"] == "P2" and t.at["P1", "element"] == "P1"
    assert any("guccione" in n and "1000 μ" in n for n in cmp.notes)
    with pytest.raises(InputError, match="neo-Hookean is not the scene's guccione"):
        compare_scene(scene, models=["P2-NH"])


def test_p2_reference_is_a_direct_solve_of_the_scene(small_beam):
    """The reference equals ``reference_fem.solve`` of the scene as given (order 2, mixed)."""
    scene, cmp = small_beam
    direct = reference_fem.solve(scene_from_dict(beam(SMALL, EXACT)))
    assert direct.result.element == "P2" and "mixed" in direct.result.law
    u = cmp.solutions["P2"].u
    assert np.abs(u - direct.u_vertices).max() <= SOLVER_TOL * np.abs(direct.u_vertices).max()


def test_p1_is_displacement_formulation_with_the_stated_penalty(small_beam):
    """P1 equals a direct P1 solve of the beam written with ``kappa = 1000 mu`` and the
    displacement formulation (mu from the closed-form tangent, not from the code under
    test)."""
    _, cmp = small_beam
    mu = float(np.mean(np.diag(tissue_tangent("guccione", {**PARAMS, "kappa": 0.0}))[3:]))
    data = beam(SMALL)
    data["material"] = {"law": "guccione", **PARAMS, "kappa": 1000.0 * mu}
    data["fem"] = {"order": 1, "formulation": "displacement", "load_steps": 4}
    direct = reference_fem.solve(scene_from_dict(data))
    assert cmp.solutions["P1"].result.law == direct.result.law == "guccione/log"
    u = cmp.solutions["P1"].u
    assert np.abs(u - direct.u_vertices).max() <= SOLVER_TOL * np.abs(direct.u_vertices).max()
    assert any(f"{1000.0 * mu:.4g}" in n for n in cmp.notes)


def test_spring_exact_element_is_p1_of_the_law_at_small_strain(small_beam):
    """docs/theory.rst#the-exact-element-is-the-p1-element: the exact element is P1 with the law's
    small-strain tangent (the same
    penalty). Both models' finite-strain terms are O(strain) relative to their common
    linearisation: tolerance ten times the largest P1 Green–Lagrange strain (about 1e-5
    at this load; at the full load the same comparison gives 0.4%)."""
    _, cmp = small_beam
    assert cmp.strain < 1e-4  # the small-strain regime the claim is about
    e = cmp.errors("spring", "P1")
    assert e["rel_l2"] < 10 * cmp.strain, (e, cmp.strain)


def test_cli_compare_on_a_tissue_scene_exits_0(tmp_path, monkeypatch, capsys):
    """The command from the issue, on the coarse beam: exit 0, the table has the three
    models with the P2 reference."""
    monkeypatch.setattr(compare_output, "render_comparison", lambda cmp, path: path)
    out = tmp_path / "o"
    args = ["compare", "land-beam", "--set", "mesh.divisions=[6, 1, 1]", "--out", str(out)]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "reference: P2" in text and "model error (spring vs P1, same mesh)" in text
    df = pd.read_csv(out / "compare.csv").set_index("model")
    assert bool(df.at["P2", "reference"]) and df["converged"].all()


def test_holzapfel_ogden_with_kappa_keeps_the_scenes_penalty():
    """A compressible Holzapfel–Ogden scene: P1 and P2 both use its kappa, displacement."""
    data = beam(SMALL)
    data["material"] = {
        "law": "holzapfel-ogden",
        **dict(a=0.5, b=5.0, a_f=2.0, b_f=5.0, a_s=1.0, b_s=5.0, a_fs=0.5, b_fs=5.0),
        "kappa": 50.0,
    }
    data["fem"] = {"order": 2, "load_steps": 2}
    cmp = compare_scene(scene_from_dict(data))
    t = cmp.table.set_index("model")
    assert t.at["P1", "law"] == t.at["P2", "law"] == "holzapfel-ogden/log"
    assert any("kappa = 50 = the scene's kappa" in n for n in cmp.notes)
    # kappa = 50 is nearly incompressible (kappa > 10 mu): P2/P1 mixed is the reference
    assert cmp.reference == "fem-P2-mixed" and t["converged"].all()


def test_a_spring_stop_is_a_partial_row_not_ranked(monkeypatch):
    """A spring model stopping at load factor 0.4 is reported partial at that load, with
    no error against the reference; the FEM models are still compared."""
    real = Model.solve_model

    def stopping(self, scene, verbose=False):
        if self.name == "spring":
            u = np.zeros((scene.mesh.n_points, 3))
            raise SolverError("stopped at load factor 0.4 of 1", state=u, load_factor=0.4)
        return real(self, scene, verbose)

    monkeypatch.setattr(Model, "solve_model", stopping)
    cmp = compare_scene(scene_from_dict(beam(SMALL)))
    t = cmp.table.set_index("model")
    assert t.at["spring", "status"] == "partial" and t.at["spring", "load factor"] == 0.4
    assert np.isnan(t.at["spring", "rel L2 err"]) and cmp.reference == "P2"
    assert "spring" not in cmp.solutions and t.at["P1", "status"] == "ok"
    lines = compare_output.summary_lines(cmp)
    assert any(line.startswith("spring: partial, stopped at load factor 0.4 ") for line in lines)
    assert not any("spring vs" in line for line in lines)  # not ranked
