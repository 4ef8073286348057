"""The pure scene builder: a plain mapping in, a validated :class:`Scene` out.

The model sections of a scene belong to the packages built on the core: each registers its
parser, through the entry-point group ``springfem.sections`` (:mod:`springfem.plugins`) or
with :func:`register_section`, and the builder validates the section with it. A section no
package registered is an unknown section.

Examples
--------
>>> box = {"generator": "box", "size": [1, 1, 1], "divisions": [1, 1, 1]}
>>> scene_from_dict({"mesh": box, "material": {"law": "linear", "E": 1.0, "nu": 0.25},
...                  "materail": {}})
Traceback (most recent call last):
...
springfem.errors.SceneError: <scene>: [materail]: unknown section; did you mean [material]?
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..errors import SceneError
from ..files import safe_filename
from ..mesh import TetMesh
from ..plugins import entry_points, load
from .reader import TableReader, _key_label, _show, suggestion
from .sections import (
    SECTION_KEYS,
    material_keys,
    parse_axes,
    parse_boundary,
    parse_load,
    parse_material,
    parse_mesh,
    parse_probe,
)
from .types import UNIT_SYSTEMS, Material, Scene

_SECTION_PARSERS: dict[str, Callable[[TableReader], Any]] = {}

#: The sections and keys of a scene's top level besides the model sections.
SECTIONS = ("name", "units", "mesh", "material", "axes", "boundary", "load", "probe")


def register_section(name: str, parse: Callable[[TableReader], Any]) -> None:
    """Register the parser of a model section, so scenes validate it when they load.

    Parameters
    ----------
    name
        The section's name (``[name]`` in a scene file).
    parse
        Takes a :class:`TableReader` over the section's table, returns the options object
        and raises :class:`SceneError` (via ``reader.fail``) on bad input.

    Returns
    -------
    None

    Raises
    ------
    ValueError
        If ``name`` is a core section or another parser has it.
    """
    if name in SECTIONS:
        raise ValueError(f"[{name}] is a core section, not a model section")
    old = _SECTION_PARSERS.get(name)
    if old is not None and old is not parse:
        raise ValueError(f"model section [{name}] is registered twice")
    _SECTION_PARSERS[name] = parse


def model_sections() -> dict[str, Callable[[TableReader], Any]]:
    """The registered model sections and their parsers (the entry points loaded once).

    Returns
    -------
    dict
        Section name -> parser.
    """
    for name, value in entry_points("springfem.sections").items():
        if name not in _SECTION_PARSERS:
            register_section(name, load(value))
    return dict(_SECTION_PARSERS)


def _unknown_top_level(data: dict, file: str) -> SceneError | None:
    """The error for the first unknown top-level key or section, with a suggestion."""
    known = (*SECTIONS, *model_sections())
    extra = sorted(set(data) - set(known))
    if not extra:
        return None
    key = extra[0]
    near = suggestion(key, known)
    if isinstance(data[key], dict | list):
        hint = f"; did you mean [{near}]?" if near else ""
        return SceneError(f"{file}: [{_key_label(key)}]: unknown section{hint}")
    hint = f"; did you mean {near!r}?" if near else ""
    return SceneError(f"{file}: {_key_label(key)}: unknown key{hint}")


def scene_from_dict(data: dict, path: str | os.PathLike | None = None) -> Scene:
    """Build and validate a scene from a plain mapping: the one way scenes are made.

    The mapping has the layout of a scene file (``name``, ``[mesh]``, ``[material]``,
    ``[axes]``, ``[[boundary]]``, ``[[load]]``, ``[[probe]]`` and the model sections), so
    studies and tests build scenes as data and change a value by editing a dict. Objects
    built in code may stand in for two tables, and are used as they are: a
    :class:`~springfem.mesh.TetMesh` (a verification geometry) for ``[mesh]`` (then
    ``axes = {"type": "cells"}`` reads its ``fiber`` and ``sheet`` cell data), and a
    :class:`Material` for ``[material]``.

    Parameters
    ----------
    data
        The scene table (not modified); ``data["mesh"]`` is a table or a
        :class:`~springfem.mesh.TetMesh`, ``data["material"]`` a table or a
        :class:`Material`.
    path
        The scene file's path, if any: names it in errors and anchors relative mesh paths
        (default: the current folder).

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        One line naming the file and the offending key.

    Examples
    --------
    >>> box = {"generator": "box", "size": [1, 1, 1], "divisions": [1, 1, 1]}
    >>> s = scene_from_dict({"mesh": box, "material": {"law": "linear", "E": 1.0, "nu": 0.25}})
    >>> s.name, s.mesh.n_tets
    ('scene', 6)
    >>> scene_from_dict({"mesh": s.mesh, "material": {"law": "linear", "E": 1.0, "nu": 0.25},
    ...                  "load": [{"type": "gravity", "value": [0, 0, -9.81]}]}).loads[0].type
    'gravity'
    """
    file = str(path) if path is not None else "<scene>"
    base = Path(path).parent if path is not None else Path.cwd()
    top = TableReader(data, "", file)
    name = top.get("name", "str", default=Path(file).stem if path else "scene")
    safe = safe_filename(name)  # the name becomes part of default output paths
    units = top.get("units", "str", default="SI", choices=tuple(UNIT_SYSTEMS))
    for section in ("mesh", "material"):
        if section not in data:
            raise _unknown_top_level(data, file) or SceneError(
                f"{file}: [{section}]: missing section (required)"
            )
    if isinstance(data["mesh"], TetMesh):
        mesh = data["mesh"]
    else:
        mesh = parse_mesh(TableReader(data["mesh"], "mesh", file, SECTION_KEYS["mesh"]), base)
    top.used.add("mesh")
    if isinstance(data["material"], Material):
        material = data["material"]
    else:
        material = parse_material(
            TableReader(data["material"], "material", file, material_keys()), units
        )
    top.used.add("material")
    frames = parse_axes(TableReader(data.get("axes", {}), "axes", file, SECTION_KEYS["axes"]), mesh)
    top.used.add("axes")
    boundaries = [
        parse_boundary(TableReader(b, f"boundary[{i}]", file, SECTION_KEYS["boundary"]), mesh)
        for i, b in enumerate(_array_of_tables(data, "boundary", file))
    ]
    loads = [
        parse_load(TableReader(b, f"load[{i}]", file, SECTION_KEYS["load"]), mesh)
        for i, b in enumerate(_array_of_tables(data, "load", file))
    ]
    probes = [
        parse_probe(TableReader(b, f"probe[{i}]", file, SECTION_KEYS["probe"]), mesh)
        for i, b in enumerate(_array_of_tables(data, "probe", file))
    ]
    names = [p.name for p in probes]
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise SceneError(f"{file}: probe: duplicate probe name {_show(dup[0])}")
    top.used.update({"boundary", "load", "probe"})
    parsers = model_sections()
    options = {
        name: parse(TableReader(data.get(name, {}), name, file, root=data))
        for name, parse in parsers.items()
    }
    top.used.update(parsers)
    unknown = _unknown_top_level(data, file)
    if unknown is not None:
        raise unknown
    if safe != name:
        mesh.notes.append(
            f"{file}: name {_show(name)} can't be part of a folder name; using {safe!r}"
        )
    return Scene(
        name=safe,
        mesh=mesh,
        material=material,
        frames=frames,
        boundaries=boundaries,
        loads=loads,
        probes=probes,
        options=options,
        path=Path(path) if path is not None else None,
        raw=data,
        units=units,
    )


def _array_of_tables(data: dict, key: str, file: str) -> list:
    """The list of tables under ``key`` (``[[key]]`` in TOML), empty when absent."""
    v = data.get(key, [])
    if not isinstance(v, list) or not all(isinstance(x, dict) for x in v):
        raise SceneError(f"{file}: {key}: must be an array of tables ([[{key}]])")
    return v
