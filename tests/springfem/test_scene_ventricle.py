"""Scene wiring of the ventricle: ``[mesh] generator = "ellipsoid"``, ``[axes] type =
"rule-based"``, the bundled Land problem 2/3 scenes, and one-line errors naming the key."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest

from springfem.ellipsoid import wall_volume
from springfem.errors import SceneError
from springfem.scene import load_scene, scene_from_dict

SCENES = Path(__file__).resolve().parents[2] / "studies" / "scenes"

BASE = {
    "mesh": {"generator": "ellipsoid", "size": 4.0},
    "material": {"law": "guccione", "C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0,
                 "kappa": 200.0},
    "axes": {"type": "rule-based", "endo_angle": 0.0, "epi_angle": 0.0},
}  # fmt: skip


def _scene(**edits):
    data = copy.deepcopy(BASE)
    for path, value in edits.items():
        section, key = path.split("__")
        if value is None:
            data[section].pop(key, None)
        else:
            data[section][key] = value
    return scene_from_dict(data)


@pytest.fixture(scope="module")
def lv():
    return _scene()


def test_ellipsoid_generator_gives_the_land_wall(lv):
    m = lv.mesh
    assert sorted(m.facet_sets) == ["base", "endo", "epi"]
    # defaults are Land's geometry: the faceted wall is within a few % of the exact volume
    assert m.volumes().sum() == pytest.approx(wall_volume(), rel=0.05)
    assert m.points[:, 2].max() == pytest.approx(5.0, abs=1e-9)
    assert m.points[:, 2].min() == pytest.approx(-20.0, abs=1e-6)  # apex towards -z


def test_ellipsoid_keys_change_the_geometry():
    s = _scene(mesh__endo=[6.0, 15.0], mesh__epi=[9.0, 18.0], mesh__base_z=3.0)
    assert s.mesh.points[:, 2].max() == pytest.approx(3.0, abs=1e-9)
    assert s.mesh.volumes().sum() == pytest.approx(wall_volume((6, 15), (9, 18), 3.0), rel=0.05)


def test_rule_based_zero_helix_is_circumferential(lv):
    # helix angle 0 everywhere: the fibre is normal to the long axis and to the radius
    f = lv.frames[:, 0]
    c = lv.mesh.centers()
    away = np.hypot(c[:, 0], c[:, 1]) > 3.0  # off the apex, where "circumferential" exists
    assert np.abs(f[away, 2]).max() < 0.05  # tets are coarse: the P2 gradient is nearly radial
    radial = c[away, :2] / np.linalg.norm(c[away, :2], axis=1, keepdims=True)
    # the coarse mesh (one or two tets through a 3 mm wall) tilts grad d off the radius by
    # up to ~10 deg; a helix of 0 would still be ~90 deg from the radius, well above 15 deg
    assert np.abs(np.einsum("ij,ij->i", f[away, :2], radial)).max() < np.sin(np.radians(15))
    depth = lv.mesh.cell_data["transmural_depth"]
    assert depth.min() >= 0.0 and depth.max() <= 1.0
    np.testing.assert_allclose(np.einsum("kij,klj->kil", lv.frames, lv.frames),
                               np.tile(np.eye(3), (lv.mesh.n_tets, 1, 1)), atol=1e-12)  # fmt: skip


def test_rule_based_90_degrees_is_longitudinal():
    s = _scene(axes__endo_angle=90.0, axes__epi_angle=90.0)
    c = s.mesh.centers()
    mid = np.abs(c[:, 2]) < 3.0  # near the equator the longitudinal direction is z
    assert np.abs(s.frames[mid, 0, 2]).min() > 0.9


@pytest.mark.parametrize(
    ("edits", "match"),
    [
        ({"mesh__endo": [7.0]}, r"mesh\.endo: must be a list of 2 numbers"),
        ({"mesh__epi": [6.0, 20.0]}, r"mesh\.epi: radii \[6\.0, 20\.0\] must exceed"),
        ({"mesh__base_z": 30.0}, r"mesh\.base_z: 30\.0 must lie within"),
        ({"mesh__size": -1.0}, r"mesh\.size: must be positive"),
        ({"mesh__size": 0.01}, r"mesh\.size: "),
        (
            {"mesh__size": None, "mesh__sise": 3.0},
            r"mesh\.sise: unknown key; did you mean 'size'",
        ),
        ({"mesh__divisions": [2, 2, 2]}, r"mesh\.divisions: unknown key"),
        ({"axes__endo_angle": "x"}, r"axes\.endo_angle: must be a number"),
        ({"axes__epi": "outside"}, r"axes\.epi: mesh has no facet region 'outside'"),
        ({"axes__axis": "w"}, r"axes\.axis: 'w' is not one of x, y, z"),
        (
            {"axes__endo_angle": None, "axes__endo_angel": 1.0},
            r"axes\.endo_angel: unknown key; did you mean 'endo_angle'",
        ),
    ],
)
def test_bad_keys_give_one_line_errors(edits, match):
    with pytest.raises(SceneError, match=match) as info:
        _scene(**edits)
    assert "\n" not in str(info.value)


def test_ventricle_keys_are_refused_for_a_box():
    box = {"generator": "box", "size": [1, 1, 1], "divisions": [1, 1, 1], "endo": [7, 17]}
    data = {"mesh": box, "material": {"law": "linear", "E": 1.0, "nu": 0.3}}
    with pytest.raises(SceneError, match=r"mesh\.endo: unknown key"):
        scene_from_dict(data)


@pytest.mark.parametrize("name", ["land-ventricle", "land-ventricle-fibres"])
def test_bundled_ventricle_scenes_load_with_apex_probes(name):
    s = load_scene(SCENES / f"{name}.toml")
    probes = {p.name: p.point.tolist() for p in s.probes}
    assert probes == {"endo_apex": [0.0, 0.0, -17.0], "epi_apex": [0.0, 0.0, -20.0]}
    assert s.material.incompressible and s.loads[0].region.name == "endo"
    assert s.boundaries[0].region.name == "base" and s.boundaries[0].components == (0, 1, 2)
    if name.endswith("fibres"):
        # Land's fibres: longitudinal on both surfaces (+-90 deg), circumferential mid-wall
        depth = s.mesh.cell_data["transmural_depth"]
        f, c = s.frames[:, 0], s.mesh.centers()
        mid = (np.abs(depth - 0.5) < 0.1) & (np.hypot(c[:, 0], c[:, 1]) > 3.0)
        assert mid.any() and np.abs(f[mid, 2]).max() < 0.5
