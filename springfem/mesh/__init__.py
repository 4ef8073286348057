"""Tetrahedral meshes: the mesh type, generation, validation, meshio input/output, colouring.

One idea per module: :mod:`~springfem.mesh.tetmesh` (the :class:`TetMesh` type, volumes,
quality, boundary facets), :mod:`~springfem.mesh.generate` (box meshes and their splits),
:mod:`~springfem.mesh.validate` and :mod:`~springfem.mesh.topology` (what is rejected,
repaired or noted), :mod:`~springfem.mesh.io` (meshio files) and
:mod:`~springfem.mesh.colouring` (element colouring), :mod:`~springfem.mesh.nearest` (the
nearest boundary point). Both models use the same
:class:`TetMesh`.

Examples
--------
>>> m = box_mesh((1.0, 1.0, 1.0), (2, 2, 2), split="six")
>>> m.n_points, m.n_tets
(27, 48)
>>> round(float(m.volumes().sum()), 12)
1.0
"""

from .colouring import element_colouring
from .generate import Split, box_mesh
from .io import mesh_from_meshio, read_mesh, write_vtu
from .nearest import NearestPoint, nearest_boundary_point
from .refine import refine_uniform
from .tetmesh import (
    TetMesh,
    boundary_facets,
    displacement_gradients,
    mean_ratio_quality,
    tet_volumes,
)
from .topology import topology_notes
from .validate import MAX_COORDINATE, SLIVER_QUALITY, validate_mesh

__all__ = [
    "MAX_COORDINATE",
    "NearestPoint",
    "SLIVER_QUALITY",
    "Split",
    "TetMesh",
    "boundary_facets",
    "box_mesh",
    "element_colouring",
    "mean_ratio_quality",
    "mesh_from_meshio",
    "nearest_boundary_point",
    "read_mesh",
    "refine_uniform",
    "tet_volumes",
    "displacement_gradients",
    "topology_notes",
    "validate_mesh",
    "write_vtu",
]
