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
