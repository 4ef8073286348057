"""P1 nodal loads and reactions, against totals computed by hand."""

import numpy as np
import pytest

from springfem.loads import external_forces, lumped_masses, reactions
from springfem.scene import scene_from_dict


def scene(*loads, fixed="x_min"):
    """A 0.2 x 0.1 x 0.05 five-tet block, clamped on ``fixed``, with the given loads."""
    return scene_from_dict(
        {
            "mesh": {
                "generator": "box",
                "size": [0.2, 0.1, 0.05],
                "divisions": [4, 3, 2],
                "split": "five",
            },
            "material": {"law": "linear", "E": 1.0e3, "nu": 0.3, "density": 800.0},
            "boundary": [{"region": fixed, "fix": ["x", "y", "z"]}],
            "load": list(loads),
        }
    )


def test_gravity_total_is_weight():
    s = scene({"type": "gravity", "value": [0.0, 0.0, -9.81]})
    f = external_forces(s)
    assert lumped_masses(s).sum() == pytest.approx(800 * 0.2 * 0.1 * 0.05)
    np.testing.assert_allclose(f.sum(0), [0, 0, -9.81 * 800 * 0.001], rtol=1e-12)


def test_traction_total_is_value_times_area_and_force_is_total():
    s = scene(
        {"type": "traction", "region": "x_max", "value": [1.0, 2.0, 3.0]},
        {"type": "force", "region": "y_max", "value": [0.0, 0.0, 5.0]},
    )
    f = external_forces(s)
    np.testing.assert_allclose(f.sum(0), [0.005, 0.010, 0.015 + 5.0], rtol=1e-12)


def test_pressure_on_closed_surface_cancels_and_follows():
    s = scene({"type": "pressure", "region": "y_max", "value": 10.0}, fixed="x_max")
    f = external_forces(s)
    # pressure pushes into the body: -p n with n = +y on y_max
    np.testing.assert_allclose(f.sum(0), [0, -10.0 * 0.2 * 0.05, 0], atol=1e-15)
    # follower: rotating the body rotates the force
    rot = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])
    fr = external_forces(s, x=s.mesh.points @ rot.T)
    np.testing.assert_allclose(fr.sum(0), rot @ f.sum(0), atol=1e-15)


def test_reactions_balance_the_load():
    s = scene()
    r = np.zeros((s.mesh.n_points, 3))
    left = s.boundaries[0].region.nodes
    r[left] = [1.0, -2.0, 0.5]
    out = reactions(s, r)
    np.testing.assert_allclose(out["x_min"], -len(left) * np.array([1.0, -2.0, 0.5]))


@pytest.mark.parametrize("reverse", [False, True])
def test_pressure_on_a_file_facet_set_pushes_into_the_body_in_any_vertex_order(tmp_path, reverse):
    # a mesh file's facet set keeps the file's vertex order; cardiac-geometries' gmsh ventricle
    # orders every facet inward, which once turned the spring model's pressure around
    import meshio

    from springfem.mesh import boundary_facets, box_mesh
    from springfem.scene import load_scene

    m = box_mesh((0.2, 0.1, 0.05), (4, 3, 2), "five")
    bf = boundary_facets(m.tets)
    top = bf[np.isclose(m.points[bf][:, :, 1], 0.1).all(1)]
    top = top[:, ::-1] if reverse else top
    top[::2] = top[::2, [1, 2, 0]]  # a cyclic shift keeps the orientation
    mesh = meshio.Mesh(
        m.points,
        [("triangle", top), ("tetra", m.tets)],
        cell_data={
            "gmsh:physical": [np.full(len(top), 7), np.full(m.n_tets, 3)],
            "gmsh:geometrical": [np.full(len(top), 1), np.full(m.n_tets, 1)],
        },
        field_data={"top": np.array([7, 2]), "body": np.array([3, 3])},
    )
    meshio.write(tmp_path / "block.msh", mesh, file_format="gmsh22", binary=False)
    (tmp_path / "s.toml").write_text(
        '[mesh]\nfile = "block.msh"\n[material]\nlaw = "linear"\nE = 1e3\nnu = 0.3\n'
        '[[boundary]]\nregion = "x_min"\nfix = ["x", "y", "z"]\n'
        '[[load]]\ntype = "pressure"\nregion = "top"\nvalue = 10.0\n'
    )
    s = load_scene(tmp_path / "s.toml")
    f = external_forces(s)
    # -p n A with the outward n = +y, as on the box face y_max (test above)
    np.testing.assert_allclose(f.sum(0), [0, -10.0 * 0.2 * 0.05, 0], atol=1e-15)
    assert (f[:, 1] <= 1e-15).all()
