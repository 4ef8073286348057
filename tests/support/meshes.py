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


def gmsh_box(path, size: float, dims=(0.1, 0.02, 0.02)) -> None:
    """Write an unstructured gmsh box ``dims`` (element size ``size``, one physical volume
    ``body``) to ``path``; skips the test when gmsh is missing."""
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
        gmsh.model.mesh.generate(3)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
