"""The core both models stand on: errors, mesh, scene, regions, axes, loads, materials,
result and atomic files, and the shared mechanics (one Newton, one linear solver,
integrators).

A regular package (not a namespace package), so that a checkout's ``springfem`` is never
merged with another copy on the path and ``setuptools.packages.find`` ships it. Import the
parts from their modules, e.g. ``from springfem.scene import scene_from_dict``.

Examples
--------
>>> from springfem.scene import scene_from_dict
>>> scene_from_dict({
...     "mesh": {"generator": "box", "size": [1, 1, 1], "divisions": [1, 1, 1]},
...     "material": {"law": "linear", "E": 1.0, "nu": 0.25}}).mesh.n_tets
6
"""

from ._numba_cache import use_source_keyed_numba_cache

use_source_keyed_numba_cache()

#: The models from Python (:mod:`springfem.api`), imported on first use.
_API = ("models", "get_model", "solve")


def __getattr__(name: str):
    if name in _API:
        from . import api

        return getattr(api, name)
    raise AttributeError(f"module 'springfem' has no attribute {name!r}")
