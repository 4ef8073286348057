"""Tests of the ablation study's cases on coarse bundled scenes and of its winner rule."""

import numpy as np
import pandas as pd
import pytest

from studies.scenes import comparison_scenes
from studies.study_ablation import (
    ALL_VARIANTS,
    TOLERANCE,
    Settings,
    cheapest_adequate,
    fem_case,
    model_error,
    spring_case,
)


def _scene(name: str, divisions=None):
    div = divisions or Settings.quick().divisions.get(name) or Settings.quick().extra[name]
    if name.startswith("cantilever-"):
        return comparison_scenes({}, {name: div})[0]
    return comparison_scenes({name: div}, {})[0]


def _run(scene: str, variants: tuple[str, ...], divisions=None) -> tuple[dict, dict]:
    s = _scene(scene, divisions)
    fem = fem_case(s.case("ablation-test", 0))
    assert fem["status"] == "ok"
    out = {}
    for v in variants:
        case = s.case("ablation-test", 0, variant=v, dr_steps=500)
        r = spring_case(case)
        r["error"], r["probe_error"] = model_error(case, r, fem["u"])
        out[v] = r
    return fem, out


def test_full_model_beats_axial_only_in_stretch():
    # stretch-cross (3³×6 tets): axial springs alone solve (the stretch is along the
    # axes) but carry no Poisson coupling; the full model must be at least as accurate
    # (measured 0.337 against 0.520). Torsion changes nothing without volume springs here.
    _, r = _run(
        "stretch-cross", ("spring-axial", "spring-axial+energy", "spring-axial+energy+volume")
    )
    assert all(x["status"] == "ok" for x in r.values())
    assert r["spring-axial+energy+volume"]["error"] <= r["spring-axial"]["error"]
    assert r["spring-axial+energy"]["error"] == pytest.approx(r["spring-axial"]["error"], rel=1e-3)
    assert r["spring-axial+energy+volume"]["kernel_rate"] > 0


def test_axial_only_fails_honestly_in_bending(dk_reference):
    # Cantilever (20×2×2×6 tets): axial springs alone leave zero-energy modes, so the
    # static solve must report a failure (not a wrong answer). The model errors of the
    # full model (analytic and nnls calibration) against P1 are those of the spring model's
    # linearisation, the D_k FEM (conftest.py), independent of the force kernel: the
    # nonlinear kinematics add O(tip deflection / L) (Timoshenko: 4e-3), the tolerance.
    from studies.metrics import timoshenko_tip_deflection

    fem, r = _run(
        "cantilever",
        ("spring-axial", "spring-axial+energy+volume", "spring-axial+energy+volume+nnls"),
    )
    assert r["spring-axial"]["status"] == "fails"
    assert "singular" in r["spring-axial"]["message"]
    assert np.isnan(r["spring-axial"]["error"])
    dk_p1_displacement, _ = dk_reference
    scene = _scene("cantilever").build()
    u_p1 = np.asarray(fem["u"])
    rotation = timoshenko_tip_deflection(0.1 * 1e-4, 0.1, 0.01, 0.01, 1.0e4, 0.3) / 0.1
    for v in ("spring-axial+energy+volume", "spring-axial+energy+volume+nnls"):
        assert r[v]["status"] == "ok"
        u_dk = dk_p1_displacement(scene, ALL_VARIANTS[v].spring_options(scene))
        expected = np.linalg.norm(u_dk - u_p1) / np.linalg.norm(u_p1)
        assert r[v]["error"] == pytest.approx(expected, abs=rotation), v
    # and the nnls calibration is the better one in bending (0.013 against 0.17)
    assert r["spring-axial+energy+volume+nnls"]["error"] < r["spring-axial+energy+volume"]["error"]


def test_cheapest_adequate_rule():
    df = pd.DataFrame(
        {
            "variant": [
                "spring-axial",
                "spring-axial+cosine",
                "spring-axial+energy",
                "spring-axial+energy+volume",
                "spring-axial+energy+volume+nnls",
            ],
            "status": ["fails", "ok", "ok", "ok", "ok"],
            "error": [np.nan, 0.50, 0.105, 0.10, 0.20],
            "solve_time": [0.001, 0.01, 0.60, 0.40, 0.30],
        }
    )
    # adequate: error <= 1.1 x 0.10 -> axial+energy (0.105) and axial+energy+volume;
    # the faster of the two is axial+energy+volume (0.40 s against 0.60 s, not a tie)
    assert cheapest_adequate(df).variant == "spring-axial+energy+volume"
    # within the 25 % time tie, the variant with fewer parts wins
    df.loc[df.variant == "spring-axial+energy", "solve_time"] = 0.45
    assert cheapest_adequate(df).variant == "spring-axial+energy"
    # a failed variant never wins, however fast; with a wide tolerance the cheap one does
    assert cheapest_adequate(df, tolerance=5.0).variant == "spring-axial+cosine"
    assert cheapest_adequate(df, max_error=0.01) is None
    assert TOLERANCE == pytest.approx(0.10)


@pytest.mark.parametrize(
    "scene, divisions",
    [("cantilever-unstructured", (10, 2, 2)), ("cantilever-elongated", (5, 1, 1))],
)
def test_exact_element_on_other_meshes(scene, divisions):
    """On a jittered Delaunay mesh and on 2:1:1 cells the exact element's small-strain
    stiffness is still P1's (docs/theory.rst#the-exact-element-is-the-p1-element): against linear P1
    only the finite-strain spring
    kinematics remain, a relative change O(theta) with the tip rotation theta = w / L =
    4e-3 (Timoshenko): bound 1.5e-2 (about 4 theta, the constant unknown); the specification's
    element's
    full variant misses by more than 5x that (its volume spring depends on the shape)."""
    _, r = _run(scene, ("spring-exact-no-coupling", "spring-axial+energy+volume"), divisions)
    assert r["spring-exact-no-coupling"]["status"] == "ok"
    assert r["spring-exact-no-coupling"]["error"] < 1.5e-2
    assert r["spring-axial+energy+volume"]["error"] > 5 * r["spring-exact-no-coupling"]["error"]
