"""Fixtures of the studies tests: a scene table written as a TOML file for the CLI."""

from __future__ import annotations

import json
import tomllib

import pytest


def _value(v) -> str:
    """A TOML value: numbers, strings and booleans (JSON spells them the TOML way), arrays
    and inline tables."""
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_value(x)}" for k, x in v.items()) + " }"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    return json.dumps(v)


def scene_toml(data: dict) -> str:
    """The TOML text of a scene table (top-level keys, tables, arrays of tables)."""
    lines = [f"{k} = {_value(v)}" for k, v in data.items() if not isinstance(v, (dict, list))]
    for key, v in data.items():
        if isinstance(v, dict):
            lines += [f"[{key}]"] + [f"{k} = {_value(x)}" for k, x in v.items()]
        elif isinstance(v, list):
            for item in v:
                lines += [f"[[{key}]]"] + [f"{k} = {_value(x)}" for k, x in item.items()]
    text = "\n".join(lines) + "\n"
    if tomllib.loads(text) != data:  # the writer must round-trip what it was given
        raise AssertionError("scene table does not round-trip through TOML")
    return text


@pytest.fixture
def scene_file(tmp_path):
    """``scene_file(table, name="scene.toml")``: write a scene table as TOML, return its path."""

    def write(data: dict, name: str = "scene.toml"):
        path = tmp_path / name
        path.write_text(scene_toml(data), encoding="utf-8")
        return path

    return write
