"""One TOML writer for the tests: scene tables and fuzzed values written as TOML text.

Top-level tables become ``[table]`` sections and arrays of tables ``[[table]]`` entries (the
layout of a scene file), or everything is written inline (``inline=True``, the same data);
deeper tables are inline. Floats keep their ``repr`` (and ``nan``/``inf``), strings are TOML
basic strings, :class:`Raw` text (dates, times) is written as it is.

Examples
--------
>>> print(to_toml({"name": "a", "mesh": {"size": [1.0, 2.0]}, "load": [{"value": 1}]}), end="")
name = "a"
[mesh]
size = [1.0, 2.0]
[[load]]
value = 1
"""

from __future__ import annotations

import json
import math
from typing import Any


class Raw(str):
    """TOML text emitted as is (dates, times)."""


def toml_string(text: str) -> str:
    """A TOML basic string (JSON escapes are TOML escapes; no surrogate pairs, DEL escaped)."""
    return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007f")


def toml_value(v: Any) -> str:
    """The TOML text of one value (inline tables for dicts)."""
    if isinstance(v, Raw):
        return str(v)
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return toml_string(v)
    if isinstance(v, list | tuple):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{toml_string(k)} = {toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(type(v))


def _key(k: str) -> str:
    return k if k.replace("_", "").replace("-", "").isalnum() else toml_string(k)


def to_toml(data: dict, inline: bool = False) -> str:
    """The TOML text of a table (see the module docstring).

    Parameters
    ----------
    data
        The table.
    inline
        Write every top-level value as ``key = value`` (tables inline).

    Returns
    -------
    str
    """
    if inline:
        return "".join(f"{toml_string(k)} = {toml_value(v)}\n" for k, v in data.items())

    def is_tables(v: Any) -> bool:
        return isinstance(v, list) and bool(v) and all(isinstance(x, dict) for x in v)

    lines = [
        f"{_key(k)} = {toml_value(v)}"
        for k, v in data.items()
        if not isinstance(v, dict) and not is_tables(v)
    ]
    for k, v in data.items():
        if isinstance(v, dict):
            lines += [f"[{_key(k)}]"] + [f"{_key(a)} = {toml_value(x)}" for a, x in v.items()]
        elif is_tables(v):
            for item in v:
                lines += [f"[[{_key(k)}]]"]
                lines += [f"{_key(a)} = {toml_value(x)}" for a, x in item.items()]
    return "\n".join(lines) + "\n"
