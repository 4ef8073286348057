"""docs/recipes.rst#keeping-region-names: the recipe's files keep (or lose) the names as
the page says. Independent reference: the sets are chosen by geometry (tets left / right
of x = 1 in a 2 x 1 x 1 box) and counted here; a surface set is the x = 0 face."""

import meshio
import numpy as np
import pytest

from springfem.mesh import box_mesh, read_mesh


def _tagged():
    mesh = box_mesh((2.0, 1.0, 1.0), (4, 2, 2))
    left = mesh.points[mesh.tets].mean(axis=1)[:, 0] < 1.0
    return mesh, left, np.where(left, 1, 2)


def test_gmsh22_keeps_volume_and_surface_names(tmp_path):
    mesh, left, tags = _tagged()
    bf = mesh.boundary_facets()
    face = bf[np.all(mesh.points[bf][:, :, 0] == 0.0, axis=1)]  # x = 0: 2 x 2 squares x 2
    cells = [("tetra", mesh.tets), ("triangle", face)]
    data = {
        "gmsh:physical": [tags, np.full(len(face), 3)],
        "gmsh:geometrical": [tags, np.full(len(face), 3)],
    }
    names = {"muscle": np.array([1, 3]), "tendon": np.array([2, 3]), "base": np.array([3, 2])}
    path = tmp_path / "body.msh"
    meshio.write(path, meshio.Mesh(mesh.points, cells, cell_data=data, field_data=names),
                 file_format="gmsh22", binary=False)  # fmt: skip
    back = read_mesh(path)
    assert sorted(back.cell_sets) == ["muscle", "tendon"]
    assert len(back.cell_sets["muscle"]) == int(left.sum()) == mesh.n_tets // 2
    assert len(back.facet_sets["base"]) == len(face) == 8


@pytest.mark.parametrize("fmt", ["vtu", "gmsh"])
def test_the_writers_the_recipe_warns_about_lose_the_names(tmp_path, fmt):
    mesh, left, tags = _tagged()
    if fmt == "vtu":
        m = meshio.Mesh(mesh.points, [("tetra", mesh.tets)],
                        cell_sets={"muscle": [np.flatnonzero(left)]})  # fmt: skip
        path = tmp_path / "body.vtu"
        meshio.write(path, m)
    else:
        data = {"gmsh:physical": [tags], "gmsh:geometrical": [tags]}
        m = meshio.Mesh(mesh.points, [("tetra", mesh.tets)], cell_data=data,
                        field_data={"muscle": np.array([1, 3])})  # fmt: skip
        path = tmp_path / "body41.msh"
        meshio.write(path, m, file_format="gmsh", binary=False)
    assert "muscle" not in read_mesh(path).cell_sets
