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

from springfem.scene import parse_scene
from studies import compare, compare_output, plots
from studies.cli import main
from studies.compare import (
    bundled_scene_text,
    compare_scene,
    max_principal_strain,
    model_settings,
)

COARSE = (3, 3, 3)  # 162 tets: all three models solve in well under a second
SIGMA = {"stretch-fiber": 300.0, "stretch-cross": 100.0}  # traction on x_max (Pa)
E_LOAD = {"stretch-fiber": 3.0e4, "stretch-cross": 1.0e4}  # E_fiber, E_cross (Pa)
L = 0.01  # cube edge (m)

# Spring model vs the analytic end displacement, measured on the 3x3x3 six-tet mesh:
# +0.93 % (along the fibers) and +4.1 % (across). The analytic calibration cannot match the
# transversely isotropic material on these meshes (DESIGN §4); the tolerances are about twice
# the measured model error, so a calibration tweak passes and a wrong spring constant
# (typically >= 10 %) fails.
SPRING_AXIAL_TOL = {"stretch-fiber": 0.02, "stretch-cross": 0.08}
# Spring vs P1 on the same mesh, relative L2 over all vertex components: measured 0.25
# (fiber) and 0.34 (cross), dominated by the wrong lateral (Poisson) contraction (+77 %, +42 %).
SPRING_P1_L2_TOL = 0.40


@pytest.fixture(scope="module", params=["stretch-fiber", "stretch-cross"])
def stretch(request):
    name = request.param
    scene = parse_scene(bundled_scene_text(name, COARSE))
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


def test_spring_probe_against_uniaxial_stress(stretch):
    name, cmp = stretch
    exact = SIGMA[name] / E_LOAD[name] * L
    ux = cmp.solutions["spring"].result.probes["corner"][0]
    assert abs(ux / exact - 1) < SPRING_AXIAL_TOL[name]


def test_spring_vs_p1_same_mesh(stretch):
    name, cmp = stretch
    e = cmp.errors("spring", "P1")
    assert 0.0 < e["rel_l2"] < SPRING_P1_L2_TOL
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
    scene = parse_scene(bundled_scene_text("stretch-fiber", (1, 1, 1)))
    x = scene.mesh.points
    eps = 0.1
    u = np.zeros_like(x)
    u[:, 0] = eps * x[:, 0]  # uniaxial: Green-Lagrange E_xx = eps + eps^2 / 2
    assert max_principal_strain(scene, u) == pytest.approx(eps + eps**2 / 2, rel=1e-12)
    theta = 0.3  # linearised rotation about z: E = theta^2 / 2 in the x-y plane
    u = theta * np.stack([-x[:, 1], x[:, 0], 0 * x[:, 2]], axis=1)
    assert max_principal_strain(scene, u) == pytest.approx(theta**2 / 2, rel=1e-12)


def test_model_names_are_validated():
    scene = parse_scene(bundled_scene_text("stretch-fiber", (1, 1, 1)))
    with pytest.raises(ValueError, match="unknown model"):
        model_settings(scene, "P3")
    with pytest.raises(ValueError, match="anisotropic hyperelastic"):
        model_settings(scene, "P2-NH")


def test_bundled_scene_text_changes_divisions():
    scene = parse_scene(bundled_scene_text("cantilever", (10, 1, 1)))
    assert scene.mesh.n_tets == 60


def test_doctests():
    for mod in (compare, plots):
        assert doctest.testmod(mod).failed == 0


def test_cli_compare_writes_table_and_figure(tmp_path, capsys):
    scene = tmp_path / "coarse.toml"
    scene.write_text(bundled_scene_text("stretch-cross", (2, 2, 2)))
    out = tmp_path / "cmp"
    assert main(["compare", str(scene), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "rel L2 err" in text and "reference: P2" in text
    for name in ("compare.csv", "compare.md", "compare.png"):
        assert (out / name).stat().st_size > 0, name
    assert (out / "compare.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    res = json.loads((out / "spring" / "result.json").read_text())
    assert res["model"] == "spring"


def test_cli_compare_json(tmp_path, capsys, monkeypatch):
    def no_render(cmp, path):  # rendering is covered above; keep this test fast
        raise RuntimeError("no OpenGL here")

    monkeypatch.setattr(compare_output, "render_comparison", no_render)
    scene = tmp_path / "coarse.toml"
    scene.write_text(bundled_scene_text("stretch-fiber", (2, 2, 2)))
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


def test_cli_compare_model_failure_exits_3_and_keeps_table(tmp_path, capsys, monkeypatch):
    """A failed model becomes a row with converged = False, the others are still compared,
    the table is written and the exit code is 3 (DESIGN §6)."""
    real = compare.solve_model

    def failing(scene, name):
        if name == "spring":
            raise compare.SolverError("spring model blew up at step 7")
        return real(scene, name)

    monkeypatch.setattr(compare, "solve_model", failing)
    monkeypatch.setattr(compare_output, "render_comparison", lambda cmp, path: path)
    scene = tmp_path / "coarse.toml"
    scene.write_text(bundled_scene_text("stretch-fiber", (2, 2, 2)))
    out = tmp_path / "o"
    assert main(["compare", str(scene), "--out", str(out)]) == 3
    assert "spring model blew up at step 7" in capsys.readouterr().err
    df = pd.read_csv(out / "compare.csv").set_index("model")
    assert not df.at["spring", "converged"] and df.at["P2", "converged"]
    assert np.isnan(df.at["spring", "rel L2 err"])
