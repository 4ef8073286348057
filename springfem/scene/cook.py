"""Scene parser of Cook's membrane: ``[mesh] generator = "cook"``.

Keys: ``divisions`` (cells along x, the height and the thickness), ``thickness`` (mm),
``jitter`` and ``seed`` (:func:`springfem.mesh.cook.cook_membrane_mesh`).

Examples
--------
>>> from springfem.scene.reader import TableReader
>>> r = TableReader({"generator": "cook", "divisions": [4, 4, 1]}, "mesh", "<scene>")
>>> parse_cook(r).n_tets
96
"""

from __future__ import annotations

import math

from ..errors import InputError
from ..mesh import TetMesh
from ..mesh.cook import cook_membrane_mesh
from .limits import check_mesh_size
from .reader import TableReader


def parse_cook(r: TableReader) -> TetMesh:
    """``[mesh] generator = "cook"``: ``divisions``, ``thickness``, ``jitter``, ``seed``.

    Parameters
    ----------
    r
        Reader over the ``[mesh]`` table (``generator`` may be read already).

    Returns
    -------
    TetMesh
    """
    r.get("generator", "str", choices=("cook",))
    div = r.get("divisions", "ivec", default=[16, 16, 2], length=3, positive=True)
    thickness = r.get("thickness", "float", default=10.0, positive=True)
    jitter = r.get("jitter", "float", default=0.2, nonneg=True)
    seed = r.get("seed", "int", default=0)
    r.finish()
    too_big = check_mesh_size(6 * math.prod(int(d) for d in div))
    if too_big:
        raise r.fail("divisions", too_big)
    try:
        nx, ny, nz = (int(d) for d in div)
        return cook_membrane_mesh((nx, ny, nz), thickness, jitter, seed)
    except InputError as exc:
        raise r.fail("jitter", str(exc)) from None
