"""``springfem bench tissue`` and the NGSolve peer (no timing asserts).

docs/verification.rst#how-speed-is-measured: timings are never asserted. What is checked:
the bench runs on a tiny beam, prints its table and load average, and its JSON holds every
case with positive medians and phases; bad options exit 2 with one line; with NGSolve
installed, its mesh is ours (volume, outward normals) and its solve of the same mixed
Guccione problem agrees with reference_fem.
"""

from __future__ import annotations

import doctest
import json

import numpy as np
import pytest

from reference_fem.options import FemOptions
from springfem.errors import InputError
from studies import bench_tissue, ngsolve_peer
from studies.cli import main

TINY = ["--divisions", "4,1,1", "--cases", "beam-P1,beam-mixed", "--repeats", "2"]


def test_bench_tissue_json_has_every_case_with_positive_medians(capfd):
    assert main(["bench", "tissue", *TINY, "--json"]) == 0
    res = json.loads(capfd.readouterr().out)
    assert res["benchmark"] == "tissue" and res["rounds"] == 2
    assert res["divisions"] == [4, 1, 1]
    rows = {r["name"]: r for r in res["rows"]}
    assert set(rows) == {"beam-P1", "beam-mixed"}
    for r in rows.values():
        assert r["wall_seconds"] > 0 and r["cpu_seconds"] >= 0
        assert r["dofs"] > 0 and r["iterations"] > 0 and "tip" in r["probes"]
        assert {"assembly", "factorization", "solve", "setup"} <= set(r["phase_seconds"])
        assert all(v >= 0 for v in r["phase_seconds"].values())
    assert rows["beam-P1"]["ratio_to_mixed"] > 0 and rows["beam-mixed"]["ratio_to_mixed"] is None
    assert rows["beam-mixed"]["dofs"] > rows["beam-P1"]["dofs"]  # P2 nodes and a p per vertex
    assert len(res["machine"]["load_average_before"]) == 3
    assert any("not run" in n for n in res["notes"])


def test_bench_tissue_table(capfd):
    assert main(["bench", "tissue", *TINY[:4], "--repeats", "1", "--cases", "beam-P1"]) == 0
    out = capfd.readouterr().out
    for text in ("interleaved rounds", "load average", "P1 displacement", "assembly"):
        assert text in out, text


@pytest.mark.parametrize(
    "args, message",
    [
        (["--tets", "100"], "--tets does not apply"),
        (["--divisions", "4,1"], "three positive integers"),
        (["--cases", "beam-P3"], "unknown case 'beam-P3'; valid: all"),
        (["--size", "0"], "--size must be positive"),
    ],
)
def test_bench_tissue_bad_options_exit_2(capfd, args, message):
    assert main(["bench", "tissue", *args]) == 2
    err = capfd.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


def test_case_selection_and_form_scenes():
    assert bench_tissue.select_cases("all", ngsolve=False) == bench_tissue.all_cases(False)
    assert bench_tissue.select_cases("ventricle-P2,beam-mixed") == ["beam-mixed", "ventricle-P2"]
    with pytest.raises(InputError, match="unknown case"):
        bench_tissue.select_cases("ventricle-P4")
    beam = bench_tissue.land_scenes(divisions=(4, 1, 1))["beam"]
    assert beam.mesh.n_tets == 6 * 4
    p2 = bench_tissue.form_scene(beam, "P2")
    assert not p2.material.incompressible  # the penalty, not the constraint
    fem = FemOptions.of(p2)
    assert (fem.order, fem.formulation) == (2, "displacement")
    assert bench_tissue.form_scene(beam, "mixed") is beam


@pytest.mark.parametrize("module", [bench_tissue, ngsolve_peer], ids=lambda m: m.__name__)
def test_doctests(module):
    assert doctest.testmod(module).failed == 0


def test_agreement_is_relative_to_the_largest_component():
    got = bench_tissue.agreement({"tip": [0.0, 0.0, 2.0]}, {"tip": [1e-6, 0.0, 2.0]})
    assert got["tip"] == pytest.approx(5e-7)


@pytest.fixture(scope="module")
def small_beam():
    """Land's beam on 10 x 1 x 1 boxes (60 tets): the bench's problem, small."""
    return bench_tissue.land_scenes(divisions=(10, 1, 1))["beam"]


def test_ngsolve_mesh_is_ours(small_beam):
    ngsolve = pytest.importorskip("ngsolve", reason="NGSolve peer: optional extra [ngsolve]")
    from studies.ngsolve_peer import ngsolve_mesh

    mesh, labels = ngsolve_mesh(small_beam)
    assert (mesh.ne, mesh.nv) == (small_beam.mesh.n_tets, small_beam.mesh.n_points)
    assert ngsolve.Integrate(1.0, mesh) == pytest.approx(10.0, rel=1e-12)  # 10 x 1 x 1 mm
    n = ngsolve.specialcf.normal(3)
    down = [ngsolve.Integrate(n[i], mesh, definedon=mesh.Boundaries("z_min")) for i in range(3)]
    np.testing.assert_allclose(down, [0.0, 0.0, -10.0], atol=1e-12)  # outward: -z, area 10
    assert labels.names == ["z_min", "x_min", "rest"]


def test_ngsolve_solves_the_same_mixed_problem(small_beam):
    """Same mesh, spaces, fixed DOFs and quadrature points: the two discrete problems are
    the same, so the probes differ by the Newton tolerances only (ours |R| <= 1e-10 |f|,
    NGSolve's energy-norm test 1e-10 of its first value; measured ~3e-11). A degree-4 tet
    rule in NGSolve alone is a different discrete problem and moves the tip by far more:
    the comparison sees quadrature."""
    pytest.importorskip("ngsolve", reason="NGSolve peer: optional extra [ngsolve]")
    import reference_fem
    from studies.ngsolve_peer import solve_mixed

    ours = reference_fem.solve(small_beam).result.probes
    peer = solve_mixed(small_beam)
    assert bench_tissue.agreement(ours, peer.probes)["tip"] < 1e-8
    other = solve_mixed(small_beam, intorder=4)
    assert bench_tissue.agreement(ours, other.probes)["tip"] > 1e-6
    assert peer.info["intorder"] == 2 and peer.info["facet_intorder"] == 4
