"""Meshes several test modules share, built once per process.

Examples
--------
>>> ventricle_mesh(4.0) is ventricle_mesh(4.0)
True
"""

from __future__ import annotations

from functools import cache

from springfem.ellipsoid import ellipsoid_mesh
from springfem.mesh import TetMesh


@cache
def ventricle_mesh(size: float) -> TetMesh:
    """Land's truncated-ellipsoid ventricle (gmsh) at element ``size`` (mm); do not modify."""
    return ellipsoid_mesh(size=size)


def gmsh_box(path, size: float, dims=(0.1, 0.02, 0.02), x_faces=None) -> None:
    """Write an unstructured gmsh box ``dims`` (element size ``size``, one physical volume
    ``body``) to ``path``; skips the test when gmsh is missing. ``x_faces = (low, high)``
    also names its faces x = 0 and x = dims[0] as physical surfaces."""
    import pytest

    gmsh = pytest.importorskip("gmsh")
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("box")
        gmsh.model.occ.addBox(0, 0, 0, *dims)
        gmsh.model.occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMin", size)
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.model.addPhysicalGroup(3, [1], name="body")
        for _, s in gmsh.model.getEntities(2) if x_faces else ():
            x0, _, _, x1, _, _ = gmsh.model.getBoundingBox(2, s)
            if x1 - x0 < 1e-5:  # a face x = const (OCC pads bounding boxes by its tolerance)
                gmsh.model.addPhysicalGroup(2, [s], name=x_faces[x0 > dims[0] / 2])
        gmsh.model.mesh.generate(3)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
