"""``--set key=value``: override values of a scene file without editing it.

A key is dotted (``material.nu``, ``mesh.divisions``, ``load.0.value``: an integer indexes
an array of tables such as ``[[load]]``); a value is TOML (``0.45``, ``[20, 2, 2]``,
``true``, ``"energy"``), and a bare word that is not TOML is taken as a string
(``spring.torsion=energy``). Overrides are applied to the scene's raw table, creating
tables as needed, and the scene is then built and validated by
:func:`springfem.scene.scene_from_dict` as if the file said so: an unknown or mistyped key
is reported by the scene validation, with the ``--set`` that caused it.

The sweep (:mod:`studies.sweep`) applies its grid values through the same functions.

Examples
--------
>>> data = {"material": {"nu": 0.3}, "load": [{"value": [0, 0, -1]}]}
>>> new = apply_overrides(data, [parse_assignment("material.nu=0.45"),
...                              parse_assignment("load.0.value=[0, 0, -2]"),
...                              parse_assignment("spring.torsion=energy")])
>>> new["material"]["nu"], new["load"][0]["value"], new["spring"]
(0.45, [0, 0, -2], {'torsion': 'energy'})
>>> data["material"]["nu"]  # the input is not modified
0.3
"""

from __future__ import annotations

import copy
import os
import tomllib
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from springfem.errors import InputError, SceneError

if TYPE_CHECKING:  # the scene module is imported when a scene is built (fast CLI start-up)
    from springfem.scene import Scene

Assignment = tuple[str, Any]


def parse_value(text: str) -> Any:
    """The TOML value of ``text``; a bare word that is not TOML is a string.

    Parameters
    ----------
    text
        The right-hand side of ``key=value``.

    Returns
    -------
    object
        ``int``, ``float``, ``bool``, ``str``, ``list`` or ``dict``.

    Examples
    --------
    >>> parse_value("0.45"), parse_value("[20, 2, 2]"), parse_value("energy")
    (0.45, [20, 2, 2], 'energy')
    """
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        stripped = text.strip()
        if stripped and not any(c in stripped for c in "[]{}\"'=\n"):
            return stripped
        raise InputError(f"--set: {text!r} is not a TOML value") from None


def parse_assignment(text: str) -> Assignment:
    """``"a.b=value"`` -> ``("a.b", value)`` (see :func:`parse_value`).

    Parameters
    ----------
    text
        One ``--set`` argument.

    Returns
    -------
    tuple
        The dotted key and the typed value.

    Examples
    --------
    >>> parse_assignment("mesh.divisions=[20,2,2]")
    ('mesh.divisions', [20, 2, 2])
    """
    key, sep, value = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise InputError(f"--set {text!r}: expected key=value (e.g. material.nu=0.45)")
    parts = key.split(".")
    if any(not p.strip() for p in parts):
        raise InputError(f"--set {text!r}: empty part in the dotted key {key!r}")
    return key, parse_value(value)


def key_label(key: str) -> str:
    """The dotted key as the scene validation names it: ``load.0.value`` -> ``load[0].value``.

    Examples
    --------
    >>> key_label("load.0.value"), key_label("material.nu")
    ('load[0].value', 'material.nu')
    """
    out = ""
    for part in key.split("."):
        out += f"[{part}]" if part.isdigit() else (f".{part}" if out else part)
    return out


def set_key(data: dict, key: str, value: Any) -> None:
    """Set dotted ``key`` in the nested table ``data`` (in place), creating tables.

    Parameters
    ----------
    data
        The scene's raw table.
    key
        Dotted key; an integer part indexes an array of tables (one past the end appends
        a new table).
    value
        The value to store.
    """
    parts = key.split(".")
    node: Any = data
    for depth, part in enumerate(parts):
        last = depth == len(parts) - 1
        where = ".".join(parts[:depth]) or "the scene"
        if isinstance(node, list):
            if not part.isdigit():
                raise InputError(f"--set {key}: {where} is an array; index it with a number")
            i = int(part)
            if i > len(node) or (i == len(node) and node and not isinstance(node[0], dict)):
                raise InputError(f"--set {key}: {where} has {len(node)} entries (index {i})")
            if i == len(node):
                node.append({})
            if last:
                node[i] = value
            else:
                node = node[i]
            continue
        if not isinstance(node, dict):
            raise InputError(f"--set {key}: {where} is a value, not a table")
        if last:
            node[part] = value
        else:
            node = node.setdefault(part, {})


def apply_overrides(data: Mapping, assignments: Iterable[Assignment]) -> dict:
    """A deep copy of ``data`` with every ``(key, value)`` set (later ones win).

    Parameters
    ----------
    data
        A scene table (as read by :mod:`tomllib`); not modified.
    assignments
        ``(dotted key, value)`` pairs, e.g. from :func:`parse_assignment`.

    Returns
    -------
    dict
    """
    new = copy.deepcopy(dict(data))
    for key, value in assignments:
        set_key(new, key, value)
    return new


def read_scene_table(path: str | os.PathLike) -> dict:
    """The raw table of a scene file (one-line errors for a missing or invalid file)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise SceneError(f"scene file {path} could not be read: {exc.strerror or exc}") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{path}: not valid TOML: {exc}") from None


def scene_with_overrides(
    data: Mapping, assignments: Iterable[Assignment], path: str | os.PathLike | None = None
) -> Scene:
    """Build the scene of ``data`` with ``assignments`` applied.

    Parameters
    ----------
    data
        The scene table.
    assignments
        ``(dotted key, value)`` pairs.
    path
        The scene file (names it in errors, anchors relative mesh paths).

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        From the scene validation, naming the ``--set`` whose key it reports.
    """
    from springfem.scene import scene_from_dict

    assignments = list(assignments)
    try:
        return scene_from_dict(apply_overrides(data, assignments), path=path)
    except SceneError as exc:
        msg = str(exc)
        culprits = [f"{k}={v!r}" for k, v in assignments if _names(msg, k)]
        if culprits:
            raise SceneError(f"{msg} (from --set {', '.join(culprits)})") from None
        raise


def _names(msg: str, key: str) -> bool:
    """Whether an error message names dotted ``key``, a key inside it, or a table holding it."""
    parts = key.split(".")
    for n in range(len(parts), 0, -1):
        label = key_label(".".join(parts[:n]))
        if f" [{label}]:" in msg:  # a section named as such ("[materail]: unknown section")
            return True
        i = msg.find(f" {label}")
        after = msg[i + 1 + len(label) : i + 2 + len(label)] if i >= 0 else ""
        if after == ":" or (n == len(parts) and after in (".", "[")):
            return True
    return False


def load_scene_with(path: str | os.PathLike, sets: Iterable[str] | None = None) -> Scene:
    """Load a scene file with ``--set`` arguments applied (none: as the file says).

    Parameters
    ----------
    path
        The scene file.
    sets
        ``key=value`` strings.

    Returns
    -------
    Scene
    """
    sets = list(sets or [])
    if not sets:
        from springfem.scene import load_scene

        return load_scene(path)
    return scene_with_overrides(read_scene_table(path), map(parse_assignment, sets), path)


def add_set_option(parser) -> None:
    """Add the repeatable ``--set key=value`` option to an argparse (sub)parser."""
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a scene value, e.g. --set material.nu=0.45 (repeatable; TOML values)",
    )
