"""``compare_scene`` and ``springfem compare`` on coarse variants of the bundled scenes.

Independent references: the uniaxial-stress solution ``u_x(L) = sigma L / E`` (exact for
P1 and P2, since a uniform strain lies in the P1 space), equilibrium of the reactions with
the applied load, and closed-form strains for the large-strain detector.
"""

import doctest
import json

import numpy as np
import pandas as pd
import pytest

from springfem.errors import InputError, SolverError
from springfem.scene import scene_from_dict
from studies import compare, plots
from studies import models as Model  # the registry: its solve_model is run's solve
from studies.cli import compare as cli_compare
from studies.cli import main
from studies.compare import compare_scene, max_principal_strain
from studies.scenes import bundled_table

COARSE = (3, 3, 3)  # 162 tets: all three models solve in well under a second
SIGMA = {"stretch-fiber": 300.0, "stretch-cross": 100.0}  # traction on x_max (Pa)
E_LOAD = {"stretch-fiber": 3.0e4, "stretch-cross": 1.0e4}  # E_fiber, E_cross (Pa)
L = 0.01  # cube edge (m)

# The spring model's small-strain answer has an independent reference: P1 FEM assembled
# with each element's effective spring matrix D_k
# (docs/theory.rst#the-effective-small-strain-matrix-d-k; ``dk_reference`` in
# conftest.py). At 1e-4 of the scenes' load (strain 1e-6) the spring model's nonlinear
# kinematics differ from that linearisation by O(strain) = 1e-6 relative (measured
# 1.1e-6 / 1.0e-6 over the field on 3x3x3): tolerance 5e-6, five times the strain.
SMALL_LOAD = 1e-4
LINEARISATION_TOL = 5e-6


@pytest.fixture(scope="module", params=["stretch-fiber", "stretch-cross"])
def stretch(request):
    name = request.param
    scene = scene_from_dict(bundled_table(name, {"mesh.divisions": list(COARSE)}))
    return name, compare_scene(scene)


def test_stretch_reference_and_models(stretch):
    name, cmp = stretch
    assert list(cmp.table["model"]) == ["spring", "P1", "P2"]
    assert cmp.reference == "P2" and cmp.same_mesh_p1 == "P1"
    # P1 is exact for the uniform uniaxial strain eps = sigma/E = 1 % (lateral strains are
    # smaller), whose Green-Lagrange strain is eps + eps^2/2: round-off tolerance.
    eps = SIGMA[name] / E_LOAD[name]
    assert cmp.strain == pytest.approx(eps + eps**2 / 2, rel=1e-9)
    assert not cmp.failures
    assert bool(cmp.table["converged"].all())


def test_fem_probe_is_the_uniaxial_stress_solution(stretch):
    """A uniform stress is reproduced exactly by P1 and P2 (round-off tolerance)."""
    name, cmp = stretch
    exact = SIGMA[name] / E_LOAD[name] * L
    for model in ("P1", "P2"):
        for probe in ("corner", "center"):
            ux = cmp.solutions[model].result.probes[probe][0]
            assert ux == pytest.approx(exact, rel=1e-9), (model, probe)


@pytest.fixture(scope="module", params=["stretch-fiber", "stretch-cross"])
def small_stretch(request, dk_reference):
    """``compare_scene`` of a stretch at 1e-4 of its load, and the D_k FEM displacement."""
    dk_p1_displacement, scaled_loads = dk_reference
    name = request.param
    scene = scene_from_dict(
        scaled_loads(bundled_table(name, {"mesh.divisions": list(COARSE)}), SMALL_LOAD)
    )
    return name, compare_scene(scene), dk_p1_displacement(scene)


def test_spring_probe_is_its_dk_linearisation(small_stretch):
    """The spring corner displacement equals the D_k FEM's (not a loose bound around the
    uniaxial answer sigma L / E, which the calibration mismatch misses by 1-5 %)."""
    name, cmp, u_dk = small_stretch
    ux = cmp.solutions["spring"].result.probes["corner"][0]
    ux_dk = cmp.scene.probe_displacements(u_dk)["corner"][0]
    assert ux == pytest.approx(ux_dk, rel=LINEARISATION_TOL)
    assert np.linalg.norm(cmp.solutions["spring"].u - u_dk) <= LINEARISATION_TOL * np.linalg.norm(
        u_dk
    )


def test_spring_vs_p1_same_mesh(small_stretch):
    """The comparison's spring-vs-P1 error is the D_k FEM's distance from P1 (the whole
    model error of the calibration), to the linearisation tolerance."""
    name, cmp, u_dk = small_stretch
    u_p1 = cmp.solutions["P1"].u
    expected = np.linalg.norm(u_dk - u_p1) / np.linalg.norm(u_p1)
    e = cmp.errors("spring", "P1")
    # |e - expected| <= ||u - u_dk|| / ||u_p1|| <= TOL * ||u_dk|| / ||u_p1|| (triangle ineq.)
    assert e["rel_l2"] == pytest.approx(expected, abs=LINEARISATION_TOL * (1 + expected))
    row = cmp.table.set_index("model").loc["spring"]
    assert row["rel L2 err"] == pytest.approx(cmp.errors("spring")["rel_l2"])
    # P1 equals P2 at the vertices for a uniform field (round-off)
    assert cmp.errors("P1")["rel_l2"] < 1e-9


def test_reactions_balance_the_load(stretch):
    """Every model's x_min reaction equals the applied force sigma * area (equilibrium;
    tolerance: the spring model's static solver residual, relative 1e-8)."""
    name, cmp = stretch
    col = "|R| x_min (N)"
    assert np.allclose(cmp.table[col], SIGMA[name] * L * L, rtol=1e-8)


def test_table_columns(stretch):
    _, cmp = stretch
    cols = set(cmp.table.columns)
    for c in (
        "model", "reference", "element", "law", "corner |u| (m)", "corner ux (m)",
        "center ux (m)", "rel L2 err", "rel max err", "volume change", "wall time (s)",
        "converged",
    ):  # fmt: skip
        assert c in cols, c


def test_large_strain_detector_analytic():
    scene = scene_from_dict(bundled_table("stretch-fiber", {"mesh.divisions": list((1, 1, 1))}))
    x = scene.mesh.points
    eps = 0.1
    u = np.zeros_like(x)
    u[:, 0] = eps * x[:, 0]  # uniaxial: Green-Lagrange E_xx = eps + eps^2 / 2
    assert max_principal_strain(scene, u) == pytest.approx(eps + eps**2 / 2, rel=1e-12)
    theta = 0.3  # linearised rotation about z: E = theta^2 / 2 in the x-y plane
    u = theta * np.stack([-x[:, 1], x[:, 0], 0 * x[:, 2]], axis=1)
    assert max_principal_strain(scene, u) == pytest.approx(theta**2 / 2, rel=1e-12)


def test_model_names_are_validated():
    """An unknown model is named with the closest valid one; a model that cannot solve the
    scene's law is refused before anything is solved."""
    scene = scene_from_dict(bundled_table("stretch-fiber", {"mesh.divisions": [1, 1, 1]}))
    with pytest.raises(InputError, match=r"unknown model 'P3'; valid models: spring, "):
        compare_scene(scene, models=["spring", "P3"])
    with pytest.raises(InputError, match="anisotropic hyperelastic"):
        compare_scene(scene, models=["spring", "P2-NH"])


def test_bundled_table_changes_divisions():
    scene = scene_from_dict(bundled_table("cantilever", {"mesh.divisions": [10, 1, 1]}))
    assert scene.mesh.n_tets == 60


def test_doctests():
    for mod in (compare, plots):
        assert doctest.testmod(mod).failed == 0


def test_cli_compare_writes_table_and_figure(tmp_path, capsys, scene_file):
    scene = scene_file(bundled_table("stretch-cross", {"mesh.divisions": list((2, 2, 2))}))
    out = tmp_path / "cmp"
    assert main(["compare", str(scene), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "rel L2 err" in text and "reference: P2" in text
    for name in ("compare.csv", "compare.md", "compare.png"):
        assert (out / name).stat().st_size > 0, name
    assert (out / "compare.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    res = json.loads((out / "spring" / "result.json").read_text())
    assert res["model"] == "spring"


def test_cli_compare_json(tmp_path, capsys, monkeypatch, scene_file):
    def no_render(cmp, path):  # rendering is covered above; keep this test fast
        raise RuntimeError("no OpenGL here")

    monkeypatch.setattr(cli_compare, "render_comparison", no_render)
    scene = scene_file(bundled_table("stretch-fiber", {"mesh.divisions": list((2, 2, 2))}))
    assert main(["compare", str(scene), "--out", str(tmp_path / "o"), "--json"]) == 0
    captured = capsys.readouterr()
    payload = json.loads(captured.out)  # stdout is pure JSON (progress went to stderr)
    assert "figure not rendered" in captured.err and "png" not in payload["files"]
    assert payload["reference"] == "P2"
    assert [r["model"] for r in payload["rows"]] == ["spring", "P1", "P2"]
    assert payload["rows"][2]["rel L2 err"] == 0.0


def test_cli_compare_bad_scene_exits_2(capsys):
    assert main(["compare", "no-such-scene"]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_cli_compare_model_failure_exits_3_and_keeps_table(
    tmp_path, capsys, monkeypatch, scene_file
):
    """A failed model becomes a row with converged = False, the others are still compared,
    the table is written and the exit code is 3 (docs/contract.rst#exit-codes)."""
    real = Model.solve_model

    def failing(self, scene, verbose=False):
        if self.name == "spring":
            raise SolverError("spring model blew up at step 7")
        return real(self, scene, verbose)

    monkeypatch.setattr(Model, "solve_model", failing)
    monkeypatch.setattr(cli_compare, "render_comparison", lambda cmp, path: path)
    scene = scene_file(bundled_table("stretch-fiber", {"mesh.divisions": list((2, 2, 2))}))
    out = tmp_path / "o"
    assert main(["compare", str(scene), "--out", str(out)]) == 3
    assert "spring model blew up at step 7" in capsys.readouterr().err
    df = pd.read_csv(out / "compare.csv").set_index("model")
    assert not df.at["spring", "converged"] and df.at["P2", "converged"]
    assert np.isnan(df.at["spring", "rel L2 err"])


def test_cli_compare_models_and_the_stated_reference(tmp_path, capsys, monkeypatch, scene_file):
    """``--models spring,p1``: only those run (any spelling of a registered name), the
    reference is the finest FEM among them, and a note says so."""
    monkeypatch.setattr(cli_compare, "render_comparison", lambda cmp, path: path)
    scene = scene_file(bundled_table("stretch-fiber", {"mesh.divisions": [2, 2, 2]}))
    argv = ["compare", str(scene), "--out", str(tmp_path / "o"), "--json", "--models", "spring,p1"]
    assert main(argv) == 0
    payload = json.loads(capsys.readouterr().out)
    assert [r["model"] for r in payload["rows"]] == ["spring", "P1"]
    assert payload["reference"] == "P1"
    assert any("reference: P1, the finest FEM of the models asked for" in n
               for n in payload["notes"])  # fmt: skip


def test_cli_compare_refuses_an_unknown_model_in_one_line(tmp_path, capsys, scene_file):
    scene = scene_file(bundled_table("stretch-fiber", {"mesh.divisions": [1, 1, 1]}))
    assert main(["compare", str(scene), "--out", str(tmp_path), "--models", "spring,p1-nx"]) == 2
    err = capsys.readouterr().err
    assert "unknown model 'p1-nx' (did you mean P1-NH?)" in err and err.count("\n") == 1


def test_cli_compare_max_time_is_a_failed_row_not_a_crash(tmp_path, capsys, monkeypatch,
                                                          scene_file):  # fmt: skip
    """A model stopped by ``--max-time`` is a FAILED row with the stop's message; the others
    are compared and the exit code is 3. (A cap far below one Newton iteration stops the
    spring model's Newton at its first check after the first force evaluation.)"""
    monkeypatch.setattr(cli_compare, "render_comparison", lambda cmp, path: path)
    scene = scene_file(bundled_table("cantilever", {"mesh.divisions": [10, 1, 1]}))
    out = tmp_path / "o"
    argv = ["compare", str(scene), "--out", str(out), "--models", "spring,P1", "--max-time", "1e-9"]
    code = main(argv)
    err = capsys.readouterr().err
    df = pd.read_csv(out / "compare.csv").set_index("model")
    assert code == 3 and "stopped after" in err
    assert df.at["spring", "status"] == "FAILED" and df.at["P1", "status"] == "ok"
