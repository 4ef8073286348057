"""What the command modules share: the scene of ``SCENE [--set K=V]``, the output folder,
progress lines and JSON on stdout."""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from springfem.files import jsonable, output_folder
from springfem.scene import Scene


def print_json(obj: Any) -> None:
    """Print ``obj`` as indented JSON with sorted keys.

    Parameters
    ----------
    obj
        A JSON-able object.

    Examples
    --------
    >>> print_json({"b": 1, "a": [1, 2]})
    {
      "a": [
        1,
        2
      ],
      "b": 1
    }
    """
    print(json.dumps(obj, indent=2, sort_keys=True))


def scene_of(args: argparse.Namespace) -> Scene:
    """The scene of ``args.scene`` (a file or a bundled name) with its ``--set`` overrides.

    Parameters
    ----------
    args
        Parsed arguments with ``scene`` (and ``set``, if the command takes it).

    Returns
    -------
    Scene
    """
    from ..overrides import load_scene_with
    from ..scenes import scene_path

    return load_scene_with(scene_path(args.scene), getattr(args, "set", None))


def out_folder(args: argparse.Namespace, command: str, name: str) -> Path:
    """``--out``, or the command's default folder ``out/<command>-<name>``.

    Examples
    --------
    >>> out_folder(argparse.Namespace(out="here"), "verdict", "sag")
    PosixPath('here')
    """
    return Path(args.out) if args.out else output_folder(command, name)


def progress_log(quiet: bool) -> Callable[[str], None]:
    """A function printing progress lines: on stdout, or on stderr when stdout carries the
    JSON (``--json``).

    Examples
    --------
    >>> progress_log(False)("solving")
    solving
    """

    def log(line: str) -> None:
        print(line, file=sys.stderr if quiet else sys.stdout, flush=True)

    return log


def print_payload(payload: dict[str, Any]) -> None:
    """Print a command's ``--json`` answer, in its own key order.

    Examples
    --------
    >>> print_payload({"b": 1, "a": None})
    {
      "b": 1,
      "a": null
    }
    """
    print(json.dumps(jsonable(payload), indent=2))


_STARTED: list[float] = []


def args_started(when: float) -> None:
    """Record when the command started (:func:`command_seconds` counts from it)."""
    _STARTED[:] = [when]


def command_seconds() -> float:
    """Wall seconds since the command started (its scene's loading counts against a budget;
    0 when no command is running)."""
    return max(time.perf_counter() - _STARTED[0], 0.0) if _STARTED else 0.0
