"""Plausibility of a solution (springfem.plausibility) on homogeneous deformations whose
element volume ratio, volume change and strain are known in closed form, on a jittered
Delaunay box (not a hexahedral split)."""

from __future__ import annotations

import numpy as np
import pytest

from springfem.plausibility import (
    J_RANGE,
    SMALL_STRAIN,
    VOLUME_CHANGE_ANY,
    VOLUME_CHANGE_NEARLY_INCOMPRESSIBLE,
    check_solution,
    nearly_incompressible,
)
from springfem.scene import scene_from_dict


def block(law="neo-hookean", nu=0.3, **material):
    mesh = {"generator": "box", "size": [2.0, 1.0, 1.0], "divisions": [4, 2, 2],
            "split": "delaunay", "seed": 1}  # fmt: skip
    mat = {"law": law, "E": 3.0e3, "nu": nu, **material} if law != "guccione" else material
    return scene_from_dict({"mesh": mesh, "material": mat})


def stretch(scene, lam):
    """u of the homogeneous deformation x -> diag(lam) X (J = prod(lam) in every tet)."""
    return scene.mesh.points * (np.asarray(lam) - 1.0)


def quantities(scene, u, law="neo-hookean"):
    return {f.quantity: f for f in check_solution(scene, u, law)}


def test_a_plausible_state_has_no_finding():
    s = block()
    assert check_solution(s, stretch(s, [1.03, 0.99, 0.99]), "neo-hookean") == []


def test_the_volume_loss_of_a_nearly_incompressible_body_is_flagged():
    """At nu = 0.45 a uniform compression to J = 0.9^3 = 0.729 (-27 %) is flagged, for
    nu = 0.3 it is within the 50 % any material may lose; -65 % (J = 0.35) is flagged for
    both, with the volume change in the line."""
    lam = [0.9, 0.9, 0.9]
    soft, stiff = block(nu=0.3), block(nu=0.45)
    assert nearly_incompressible(stiff) and not nearly_incompressible(soft)
    assert "volume change" in quantities(stiff, stretch(stiff, lam))
    assert "volume change" not in quantities(soft, stretch(soft, lam))
    lam65 = [0.35 ** (1 / 3)] * 3
    f = quantities(soft, stretch(soft, lam65))["volume change"]
    assert f.value == pytest.approx(0.35 - 1.0, rel=1e-12) and "-65.0%" in f.line
    assert VOLUME_CHANGE_NEARLY_INCOMPRESSIBLE < 0.27 < VOLUME_CHANGE_ANY < 0.65


def test_element_volume_ratios_outside_the_range_and_inverted_elements():
    s = block()
    j = quantities(s, stretch(s, [0.4, 0.4, 0.4]))["J"]  # J = 0.064 everywhere
    assert j.value == pytest.approx(0.064, rel=1e-12) and j.value < J_RANGE[0]
    assert "element " in j.where
    # mirror the body through x = 0: every element inverted (J = -1)
    u = stretch(s, [-1.0, 1.0, 1.0])
    inv = quantities(s, u)["J"]
    assert inv.value == pytest.approx(-1.0) and f"{s.mesh.n_tets} inverted elements" in inv.line


def test_small_strain_laws_beyond_their_range():
    """A 10 % stretch: Green-Lagrange strain 0.1 + 0.1^2/2 = 0.105, flagged for the linear
    law only, with the element named."""
    s = block(law="linear")
    f = quantities(s, stretch(s, [1.1, 1.0, 1.0]), "linear")["strain"]
    assert f.value == pytest.approx(0.105, rel=1e-12) and f.value > SMALL_STRAIN
    assert "strain" not in quantities(s, stretch(s, [1.1, 1.0, 1.0]), "neo-hookean/coupled")


def test_a_displacement_beyond_the_body_and_a_non_finite_one():
    s = block()
    u = np.zeros_like(s.mesh.points)
    u[:, 2] = 5.0  # a rigid translation by more than the diagonal (sqrt 6 = 2.45)
    f = quantities(s, u)["displacement"]
    assert f.value == pytest.approx(5.0) and "node " in f.where
    u[0, 0] = np.nan
    (bad,) = check_solution(s, u, "neo-hookean")
    assert bad.line == "the displacement is not finite"
