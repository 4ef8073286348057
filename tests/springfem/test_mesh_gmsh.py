"""A gmsh mesh written without physical groups reads (meshio's gmsh:* sets are skipped)."""

from __future__ import annotations

import numpy as np
import pytest

from springfem.mesh import read_mesh

gmsh = pytest.importorskip("gmsh")


def test_gmsh_box_without_physical_groups_reads(tmp_path):
    path = tmp_path / "box.msh"
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("box")
        gmsh.model.occ.addBox(0, 0, 0, 2.0, 1.0, 0.5)
        gmsh.model.occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.4)
        gmsh.option.setNumber("Mesh.SaveAll", 1)  # every element, no physical group needed
        gmsh.model.mesh.generate(3)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    mesh = read_mesh(path)
    assert mesh.n_tets > 20
    # independent check: the tets fill the box exactly (volume 2 x 1 x 0.5)
    assert float(mesh.volumes().sum()) == pytest.approx(1.0, rel=1e-12)
    assert not any(name.startswith("gmsh:") for name in mesh.cell_sets)
    assert np.all(mesh.volumes() > 0)
