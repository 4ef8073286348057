"""Region names survive a VTU round trip: ``region`` cell data plus a FieldData name table.

Independent check: the sets are chosen by geometry (tets left / right of the middle of a
box), written with :func:`write_result`, and read back by meshio, pyvista and
:func:`read_mesh`; before the change a VTU carried no region at all.
"""

import numpy as np
import pytest

from springfem.mesh import box_mesh, read_mesh
from springfem.result import Result, write_result


def _mesh_with_regions():
    mesh = box_mesh((2.0, 1.0, 1.0), (4, 2, 2))
    centres = mesh.points[mesh.tets].mean(axis=1)
    left = np.flatnonzero(centres[:, 0] < 1.0)
    right = np.flatnonzero(centres[:, 0] >= 1.0)
    mesh.cell_sets.update({"muscle": left, "tendon sheath": right})
    return mesh, left, right


def _write(tmp_path, mesh):
    res = Result("s", "fem", "P1", "linear", {}, {}, {}, {}, 0.0, True, 1)
    return write_result(tmp_path, res, mesh, np.zeros((mesh.n_points, 3)))[1]


def test_region_names_round_trip_through_read_mesh(tmp_path):
    mesh, left, right = _mesh_with_regions()
    back = read_mesh(_write(tmp_path, mesh))
    assert set(back.cell_sets) >= {"muscle", "tendon sheath"}
    assert not any(k.startswith(("tag:", "region:")) for k in back.cell_sets)
    np.testing.assert_array_equal(np.sort(back.cell_sets["muscle"]), left)
    np.testing.assert_array_equal(np.sort(back.cell_sets["tendon sheath"]), right)
    assert "region" not in back.cell_data  # the ids became the sets, not a field


def test_region_names_are_visible_to_paraview_readers(tmp_path):
    pv = pytest.importorskip("pyvista")
    mesh, left, _ = _mesh_with_regions()
    grid = pv.read(str(_write(tmp_path, mesh)))
    table = {name: int(grid.field_data[name][0]) for name in grid.field_data.keys()}
    assert set(table) == {"muscle", "tendon sheath"}
    ids = np.asarray(grid.cell_data["region"])
    assert np.all(ids[left] == table["muscle"]) and set(np.unique(ids)) == set(table.values())


def test_a_surface_load_on_a_volume_region_says_what_it_acts_on(tmp_path):
    """The left half's boundary facets: its x = 0 face (1 x 1) and its share of the four
    side faces (1 x 1 each), 5 in all; the whole box is closed (area 2 * (2 + 2 + 1))."""
    from springfem.scene import scene_from_dict

    mesh, left, _ = _mesh_with_regions()
    vtu = _write(tmp_path / "halves", mesh)
    mesh.cell_sets.clear()
    mesh.cell_sets["body"] = np.arange(mesh.n_tets)
    whole = _write(tmp_path / "whole", mesh)

    def scene(region):
        return scene_from_dict({
            "mesh": {"file": str(whole if region == "body" else vtu)},
            "material": {"law": "linear", "E": 1e3, "nu": 0.3},
            "boundary": [{"region": "x_max", "fix": ["x", "y", "z"]}],
            "load": [{"type": "pressure", "region": region, "value": 10.0}],
        })  # fmt: skip

    (note,) = [n for n in scene("muscle").mesh.notes if "volume region" in n]
    assert "load[0].region: muscle is a volume region; the pressure acts on" in note
    assert float(note.split("area ")[1].rstrip(")")) == pytest.approx(5.0, rel=1e-12)
    (closed,) = [n for n in scene("body").mesh.notes if "volume region" in n]
    assert float(closed.split("area ")[1].split(")")[0]) == pytest.approx(10.0, rel=1e-12)
    assert closed.endswith("so its net force is zero")
    assert not [n for n in scene("x_min").mesh.notes if "volume region" in n]
