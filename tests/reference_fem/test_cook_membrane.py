"""Cook's membrane (scene ``cook-membrane``): the mesh generator, and the nodal-volume P1
corner displacement against the Taylor–Hood P2/P1 reference at nu = 0.4999.

The issue's target: nodal-volume P1 within 3 % of the P2/P1 value on a fine mesh. Measured
values are in docs/fem.rst#nodal-volume-measurements.
"""

import tomllib
from pathlib import Path

import numpy as np
import pytest

from reference_fem import solve
from springfem.errors import MeshError
from springfem.mesh.cook import cook_membrane_mesh
from springfem.scene import load_scene, scene_from_dict

#: The locking comparison's Poisson ratio (the file keeps 0.49, which every model solves).
NU = 0.4999
SCENE = Path(__file__).resolve().parents[2] / "studies" / "scenes" / "cook-membrane.toml"


def cook_scene(divisions, fem):
    data = tomllib.loads(SCENE.read_text())
    data["mesh"]["divisions"] = list(divisions)
    data["material"]["nu"] = NU
    data["fem"] = {"load_steps": 2, **fem}
    return scene_from_dict(data, path=SCENE)


def corner_uy(divisions, fem) -> float:
    sol = solve(cook_scene(divisions, fem))
    assert sol.result.converged
    return sol.result.probes["corner"][1]


def test_mesh_fills_the_panel_with_jittered_positive_tets():
    m = cook_membrane_mesh((6, 5, 2), thickness=10.0, jitter=0.25, seed=4)
    assert (m.volumes() > 0).all()
    # the trapezoid's area (44 + 16) / 2 * 48 = 1440 mm^2, times the thickness
    assert m.volumes().sum() == pytest.approx(14400.0, rel=1e-12)
    lo, hi = m.bounding_box()
    np.testing.assert_allclose([lo, hi], [[0, 0, 0], [48, 60, 10]], atol=1e-12)
    # jittered: the interior edges are not those of the mapped grid
    grid = cook_membrane_mesh((6, 5, 2), thickness=10.0, jitter=0.0)
    assert np.abs(m.points - grid.points).max() > 0.1
    # the panel's corners are kept exactly
    for c in [(0, 0), (48, 44), (48, 60), (0, 44)]:
        assert np.isclose(m.points[:, :2], c).all(axis=1).sum() == 3  # nz + 1 layers


def test_mesh_arguments_are_checked():
    with pytest.raises(MeshError, match="jitter"):
        cook_membrane_mesh((2, 2, 1), jitter=0.4)
    with pytest.raises(MeshError, match="divisions"):
        cook_membrane_mesh((0, 2, 1))


def test_bundled_scene_loads():
    scene = load_scene(SCENE)
    assert scene.mesh.n_tets == 16 * 16 * 2 * 6
    assert [p.name for p in scene.probes] == ["corner"]


@pytest.mark.slow
def test_nodal_volume_converges_where_p1_locks():
    """Refining 8x8x1 -> 16x16x2 brings nodal-volume P1 closer to the P2/P1 reference;
    plain P1 stays locked (a refinement does not cure locking, docs/volumetric.rst#why-p1-locks).
    """
    reference = corner_uy((16, 16, 2), {"order": 2, "formulation": "mixed"})
    nodal = [corner_uy(d, {"formulation": "nodal-volume"}) for d in [(8, 8, 1), (16, 16, 2)]]
    p1 = [corner_uy(d, {"order": 1}) for d in [(8, 8, 1), (16, 16, 2)]]
    err = np.abs(1.0 - np.array(nodal) / reference)
    assert err[1] < 0.75 * err[0]  # at least O(h^0.4): a locked method does not converge
    assert max(p1) < 0.3 * reference  # P1 keeps less than a third: locked


#: The issue's target: locking-free P1 within 3 % of the converged P2/P1 value.
TARGET = 0.03


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="measured 2.902 mm against 3.096 (-6.3 %) on 32x32x2: P1's bending error",
)
def test_nodal_volume_within_the_target_of_taylor_hood_on_the_fine_mesh():
    reference = corner_uy((32, 32, 2), {"order": 2, "formulation": "mixed"})
    nodal = corner_uy((32, 32, 2), {"formulation": "nodal-volume"})
    assert nodal == pytest.approx(reference, rel=TARGET)
