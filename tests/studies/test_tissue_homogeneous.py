"""The tissue study's homogeneous cases: the tissue element equals its law's P1 under every
deformation, the stiffened element only under frame-aligned stretches; the P1 reference is
itself exact there (interior nodes in equilibrium, the forces' virial the law's stress)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from reference_fem import FemProblem
from springfem.materials.laws import tissue_law
from studies import models
from studies.study_tissue import homogeneous as h

SHEARS = [d for d in h.deformations() if d.startswith("shear")]


def case(law, deformation, model):
    return {"law": law, "deformation": deformation, "model": model}


@pytest.mark.parametrize("law", ["guccione", "holzapfel-ogden"])
@pytest.mark.parametrize("deformation", SHEARS)
def test_tissue_element_is_exact_and_the_stiffened_one_is_not_under_shear(law, deformation):
    tissue = h.homogeneous_case(case(law, deformation, "spring-tissue"))
    seed = h.homogeneous_case(case(law, deformation, "spring-stiffened"))
    assert tissue["error"] == "" and tissue["force_error"] < 1e-9
    assert seed["force_error"] > 0.05  # cot theta is 2 E_lm only while |Z_l x Z_m| = 1


def test_the_p1_reference_is_the_law_under_a_homogeneous_deformation():
    scene = h._scene("holzapfel-ogden")
    F = h.deformations()["stretch 1.3 + shear 0.3 f-s"]
    X = scene.mesh.points
    fem_scene, _, law = models.get("P1").fem_settings(scene)
    p = FemProblem(fem_scene, 1, law)
    f = p.internal_force(((X @ F.T) - X).ravel())[0].reshape(-1, 3)
    on_face = np.isclose(X, 0.0) | np.isclose(X, 1.0)
    interior = ~on_face.any(axis=1)
    assert interior.sum() > 3 and np.abs(f[interior]).max() < 1e-10 * np.abs(f).max()
    # the virial of the nodal forces is the stress times the volume: sum_a f_a X_a^T = V P
    P = tissue_law(fem_scene.material).stress(F[None], frames=h.frame()[None])[0]
    assert np.allclose(f.T @ X, P * 1.0, rtol=1e-10, atol=1e-10 * np.abs(P).max())


def test_frame_and_findings():
    R = h.frame()
    assert np.allclose(R @ R.T, np.eye(3))
    df = pd.DataFrame(
        {"law": ["g", "g"], "deformation": ["shear 0.3 f-s", "stretch 1.3 along the fibre"],
         "spring-tissue": [1e-14, 2e-15], "spring-stiffened": [0.3, 1e-15]}
    )  # fmt: skip
    text, head = h.homogeneous_findings(df)
    assert head == {"homogeneous_shear_error_spring-tissue": 1e-14,
                    "homogeneous_shear_error_spring-stiffened": 0.3}  # fmt: skip
    assert "30%" in text[1]
