"""The scene-key reference, read off the parsers: every key each section accepts.

:func:`accepted_keys` parses a corpus of small scenes (every mesh source, law, axes type,
boundary and load kind, and every registered model section) with the parsers recording
each key they ask for, its type and its choices; :func:`reference_rst` writes that as the
tables of the manual's scene-file reference (docs/scenes.rst#every-key-by-section: the docs
build generates them; ``python -m springfem.scene.reference`` prints them). Nothing is
listed by hand, so the reference cannot drift from the parsers, and :func:`literal_keys`
(the string keys in the parsers' source) checks that the corpus reaches every branch.

Examples
--------
The sections are named by what their keys depend on (a material by its law, a mesh by
its source); the parsers' source names the transversely isotropic constants:

>>> _section("load[2]", {"mesh": {}, "material": {"law": "linear"}})
'load'
>>> _section("material", {"mesh": {}, "material": {"law": "guccione"}})
'material (guccione)'
>>> {"E_fiber", "E_cross", "G_fiber"} <= literal_keys()
True
"""

from __future__ import annotations

import ast
import contextlib
import inspect
import re
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from ..errors import SpringFemError
from ..materials.laws import LAWS as TABLE
from .build import model_sections, scene_from_dict
from .reader import ASK_RECORDERS, TableReader
from .types import LAWS

_BOX = {"generator": "box", "size": [1.0, 1.0, 1.0], "divisions": [1, 1, 1]}
_MATERIALS = {
    "linear": {"E": 1e3, "nu": 0.3},
    "transverse-linear": {"E_fiber": 3e3, "E_cross": 1e3, "nu_fiber_cross": 0.3,
                          "nu_cross": 0.3, "G_fiber": 500.0},
    "neo-hookean": {"E": 1e3, "nu": 0.3},
}  # fmt: skip


def _constants(law: str) -> dict:
    """A law's constants in the corpus: the fixed laws' above, a tissue law's example."""
    if law in TABLE:
        return {**TABLE[law].example, "kappa": 100.0}
    return _MATERIALS.get(law, {})


_FIX = [{"region": "x_min", "fix": ["x", "y", "z"]}]


def _corpus() -> Iterator[dict]:
    """Small scenes that take every branch of the parsers (some are invalid on purpose:
    the keys a parser asks for before it refuses a table count too)."""
    base = {"mesh": _BOX, "material": {"law": "linear", **_MATERIALS["linear"]}}
    for law in LAWS:
        yield {**base, "material": {"law": law, **_constants(law)}}
    yield {**base, "material": {"law": "neo-hookean", "mu": 1.0, "kappa": 10.0}}
    yield {**base, "material": {"law": "guccione", **_constants("guccione"),
                                "incompressible": True}}  # fmt: skip
    yield {**base, "mesh": {**_BOX, "split": "delaunay"}}
    yield {**base, "mesh": {"file": "missing.vtu"}}
    yield {**base, "mesh": {"generator": "ellipsoid", "base_z": 1e9}}  # refused before meshing
    yield {**base, "mesh": {"generator": "cook", "divisions": [1, 1, 1]}}
    for axes in ({"type": "uniform"}, {"type": "helix", "range": [0, 1], "angles": [60, -60]},
                 {"type": "cells"}, {"type": "rule-based"},
                 {"type": "land-ellipsoid"}):  # fmt: skip
        yield {**base, "axes": axes}
    yield {**base, "boundary": _FIX}
    yield {**base, "boundary": [{"region": "x_min", "displacement": [0.0, 0.0, 0.1]}]}
    yield {**base, "boundary": [{"region": {"box": [[0, 0, 0], [0, 1, 1]]}, "fix": ["x"]}]}
    for load in ({"type": "traction", "region": "x_max", "value": [0, 0, -1.0]},
                 {"type": "pressure", "region": "x_max", "value": 1.0},
                 {"type": "gravity", "value": [0, 0, -9.81]},
                 {"type": "force", "region": "x_max", "value": [0, 0, -1.0]}):  # fmt: skip
        yield {**base, "boundary": _FIX, "load": [load]}
    yield {**base, "probe": [{"name": "p", "point": [0.5, 0.5, 0.5]}]}
    for name in model_sections():
        yield {**base, name: {}}
    yield {**base, "units": "mm-kPa", "name": "reference"}


def _variant(data: dict, section: str) -> str | None:
    """What a section's keys depend on: the material's law, the mesh's source."""
    if section == "material":
        return data["material"].get("law")
    if section == "mesh":
        mesh = data["mesh"]
        return "file" if "file" in mesh else mesh.get("generator")
    return None


def _section(where: str, data: dict) -> str:
    """``load[0]`` -> ``load``; ``material`` -> ``material (guccione)``, per law."""
    sec = re.sub(r"\[\d+\]", "", where) or "(top level)"
    variant = _variant(data, sec)
    return f"{sec} ({variant})" if variant else sec


def _with_bogus(section: str, key: str, value: Any = "?") -> dict:
    """A scene whose ``section`` holds ``key = value``: its parser asks for the key's type
    (``"?"``), or reads the key's own table (``{}``: a nested section)."""
    base = {"mesh": _BOX, "material": {"law": "linear", **_MATERIALS["linear"]}}
    name, _, variant = section.partition(" (")
    variant = variant.rstrip(")")
    if name == "(top level)":
        return {**base, key: value}
    if name == "material":
        consts = _constants(variant)
        if key in ("mu", "kappa"):  # the other pair of constants
            consts = {k: v for k, v in consts.items() if k not in ("E", "nu")}
        return {**base, "material": {"law": variant, **consts, key: value}}
    if name == "mesh":
        return {**base, "mesh": {**({"file": "missing.vtu"} if variant == "file" else _BOX),
                                 key: value}}  # fmt: skip
    if name in ("boundary", "load", "probe"):
        return {**base, name: [{key: value}]}
    table: Any = {key: value}
    for part in reversed(name.split(".")[1:]):  # a nested section: spring.lms
        table = {part: table}
    return {**base, name.split(".")[0]: table}


def _parse_recording(data: dict, out: dict) -> None:
    """Parse ``data`` (errors expected) and merge the keys its readers asked for."""
    with _recording() as asked:
        with contextlib.suppress(SpringFemError, OSError):
            scene_from_dict(data)
    for reader, keys in asked.values():
        sec = out.setdefault(_section(reader.where, data), {})
        for key, info in keys.items():
            old = sec.get(key)
            if old is None or (old["kind"] is None and info["kind"] is not None):
                sec[key] = info


@contextlib.contextmanager
def _recording() -> Iterator[dict[int, tuple[TableReader, dict[str, dict[str, Any]]]]]:
    """The keys every :class:`TableReader` is asked for inside the block, per reader."""
    asked: dict[int, tuple[TableReader, dict[str, dict[str, Any]]]] = {}

    def record(reader: TableReader, key: str, kind: str | None, choices: Any) -> None:
        keys = asked.setdefault(id(reader), (reader, {}))[1]
        if keys.get(key, {}).get("kind") is None:  # a get() after a has() tells the type
            keys[key] = {"kind": kind, "choices": choices}

    ASK_RECORDERS.append(record)
    try:
        yield asked
    finally:
        ASK_RECORDERS.remove(record)


def accepted_keys() -> dict[str, dict[str, dict[str, Any]]]:
    """Per section, the keys its parser accepts: ``{section: {key: {kind, choices}}}``.

    Returns
    -------
    dict
        Sections in scene-file order; the material section once per law.
    """
    out: dict[str, dict[str, dict[str, Any]]] = {}
    for data in _corpus():
        _parse_recording(data, out)
    todo = list(out)
    while todo:  # keys only tested for: ask for their type, or read them as a table
        section = todo.pop(0)
        keys = out[section]
        for key in [k for k, v in keys.items() if v["kind"] is None]:
            found: dict[str, dict[str, dict[str, Any]]] = {}
            _parse_recording(_with_bogus(section, key), found)
            info = found.get(section, {}).get(key)
            if info is not None and info["kind"] is not None:
                keys[key] = info
                continue
            _parse_recording(_with_bogus(section, key, {}), found)  # a nested table?
            for sub, sub_keys in found.items():
                if sub.startswith(section.split(" (")[0] + ".") and sub not in out:
                    out[sub] = sub_keys
                    todo.append(sub)
    return out


def literal_keys() -> set[str]:
    """The string keys the parsers' source asks for: ``r.get("k", ...)``, ``r.has("k")``,
    ``r.missing("k")`` and the strings of ``for key in (...)`` loops.

    Returns
    -------
    set of str
    """
    from . import output, sections, solver, tissue, ventricle

    files = {Path(str(m.__file__)) for m in (sections, tissue, ventricle, output, solver)}
    files |= {Path(str(inspect.getsourcefile(parse))) for parse in model_sections().values()}
    found: set[str] = set()
    for f in files:
        for node in ast.walk(ast.parse(f.read_text())):
            if (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Attribute)
                and node.func.attr in ("get", "has", "missing")
                and isinstance(node.func.value, ast.Name)
                and node.func.value.id.endswith("r")  # the readers: r, lr, mr ...
                and node.args
                and isinstance(node.args[0], ast.Constant)
                and isinstance(node.args[0].value, str)
            ):
                found.add(node.args[0].value)
            elif isinstance(node, ast.For) and isinstance(node.iter, ast.Tuple):
                if isinstance(node.target, ast.Name) and node.target.id in ("key", "k"):
                    found |= {
                        e.value
                        for e in node.iter.elts
                        if isinstance(e, ast.Constant) and isinstance(e.value, str)
                    }
    return found


def _cell(info: dict[str, Any]) -> str:
    """A key's value column: its kind, and its choices if it has any."""
    kind = {"str": "text", "vec": "vector", "ivec": "integers", "bool": "true/false"}.get(
        info["kind"], info["kind"] or "value"
    )
    choices = info["choices"]
    if choices:
        return f"{kind}: " + ", ".join(f"``{c}``" for c in choices)
    return kind


def reference_rst() -> str:
    """The scene-key tables (reStructuredText), generated by :func:`accepted_keys`.

    One table per section (the material once per law, the mesh once per source), a row
    per key: its name and its value (kind and choices).

    Returns
    -------
    str

    Examples
    --------
    >>> text = reference_rst()
    >>> "``material (guccione)``" in text and "   * - ``b_fs``" in text
    True
    """
    lines = []
    for section, keys in accepted_keys().items():
        lines += [f".. list-table:: ``{section}``", "   :header-rows: 1", "   :widths: 25 75"]
        lines += ["   :width: 100%", ""]
        lines += ["   * - key", "     - value"]
        for k, v in sorted(keys.items()):
            lines += [f"   * - ``{k}``", f"     - {_cell(v)}"]
        lines.append("")
    return "\n".join(lines).rstrip() + "\n"


if __name__ == "__main__":
    sys.stdout.write(reference_rst())
