"""Scenes: a mesh, a material, anisotropy axes, boundaries, loads and probes.

One idea per module: :mod:`~springfem.scene.types` (the dataclasses),
:mod:`~springfem.scene.reader` (typed access to a table, one-line messages),
:mod:`~springfem.scene.sections` (the section parsers), :mod:`~springfem.scene.build`
(the pure :func:`scene_from_dict` and the model-section registry),
:mod:`~springfem.scene.loader` (TOML files), :mod:`~springfem.scene.load_time` (loads as
functions of time), :mod:`~springfem.scene.dynamics` (the ``[dynamics]`` section) and
:mod:`~springfem.scene.limits` (mesh size limits). Scene files are data: they are parsed
with :mod:`tomllib` and validated key by key; they never execute code. Every problem raises
:class:`~springfem.errors.SceneError` with one line naming the file and the key.

Examples
--------
>>> s = scene_from_dict({
...     "name": "cube",
...     "mesh": {"generator": "box", "size": [1.0, 1.0, 1.0], "divisions": [2, 2, 2]},
...     "material": {"law": "linear", "E": 1.0e3, "nu": 0.3},
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
... })
>>> s.mesh.n_tets, s.material.mu
(48, 384.6153846153846)
"""

from ..errors import SceneError
from .build import SECTIONS, model_sections, register_section, scene_from_dict
from .dynamics import DynamicsOptions, RayleighDamping, parse_dynamics
from .limits import BYTES_PER_TET, MAX_TETS, check_mesh_size, machine_memory
from .load_time import TimeFunction, parse_time
from .loader import load_scene, parse_scene
from .output import OutputOptions, parse_output
from .reader import MAX_INT, MAX_MAGNITUDE, MIN_MAGNITUDE, TableReader, suggestion
from .sections import opt_splits
from .solver import SolverOptions, model_precision, parse_solver
from .types import (
    AXES_TYPES,
    COMPONENTS,
    FORMULATIONS,
    LAWS,
    LENGTH_UNITS,
    LOAD_TYPES,
    UNIT_SYSTEMS,
    VOLUMETRIC,
    Boundary,
    Law,
    Load,
    Material,
    Probe,
    Scene,
    default_density,
)

register_section("output", parse_output)
register_section("solver", parse_solver)
register_section("dynamics", parse_dynamics)

__all__ = [
    "DynamicsOptions",
    "RayleighDamping",
    "parse_dynamics",
    "TimeFunction",
    "parse_time",
    "SolverOptions",
    "model_precision",
    "parse_solver",
    "AXES_TYPES",
    "BYTES_PER_TET",
    "COMPONENTS",
    "FORMULATIONS",
    "LAWS",
    "LENGTH_UNITS",
    "LOAD_TYPES",
    "MAX_INT",
    "MAX_MAGNITUDE",
    "MAX_TETS",
    "MIN_MAGNITUDE",
    "OutputOptions",
    "SECTIONS",
    "UNIT_SYSTEMS",
    "VOLUMETRIC",
    "Boundary",
    "Law",
    "Load",
    "Material",
    "Probe",
    "Scene",
    "SceneError",
    "TableReader",
    "check_mesh_size",
    "default_density",
    "load_scene",
    "machine_memory",
    "opt_splits",
    "parse_scene",
    "model_sections",
    "register_section",
    "scene_from_dict",
    "suggestion",
]
