"""The sweep file: a scene, the models to run, and the cases (a grid or a list).

.. code-block:: toml

    name = "cantilever-nu"                     # optional; default: the file's stem
    scene = "cantilever"                       # a bundled name or a path relative to this file
    models = ["spring", "P1", "P2"]            # any model of studies.models ("P1-NH", ...);
                                               # default: these and, when a case is nearly
                                               # incompressible, the locking-free ones
    reference = "P2"                           # optional; default: the finest FEM listed
    [grid]                                     # every combination (or [[cases]] tables)
    "material.nu" = [0.3, 0.45]
    "mesh.divisions" = [[20, 2, 2], [40, 4, 4]]

Keys are the dotted ``--set`` keys of :mod:`studies.overrides`; an unquoted dotted key
(``material.nu = [...]``) means the same. Every case's scene is built and validated when
the file is read, so a bad key or value is reported before anything is solved.

Examples
--------
>>> spec = parse_sweep({"scene": "cantilever", "models": ["spring", "p1"],
...                     "grid": {"material.nu": [0.3, 0.45], "spring.torsion": ["cosine"]}})
>>> spec.models, spec.reference, spec.keys, [c["material.nu"] for c in spec.cases]
(('spring', 'P1'), 'P1', ('material.nu', 'spring.torsion'), [0.3, 0.45])
"""

from __future__ import annotations

import itertools
import os
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from springfem.errors import InputError, SceneError
from springfem.model_api import declared

from . import models as registry
from .overrides import apply_overrides, parse_assignment, read_scene_table, scene_with_overrides
from .scenes import scene_path as bundled

REFERENCE_PREFERENCE = ("fem-P2-mixed", "P2-NH", "P2", "P1-NH", "P1")
"""The finest FEM first (P2/P1 mixed, free of locking, first; P2 before P1; neo-Hookean,
valid at any strain, before linear)."""


def default_locking_free(scenes: Sequence) -> list[str]:
    """The locking-free models a sweep without ``models`` adds: those of
    :func:`studies.models.locking_free_models` when a case is nearly incompressible,
    kept if they apply to every case (P2/P1 mixed, added so, becomes the reference).

    Parameters
    ----------
    scenes
        The cases' scenes.

    Returns
    -------
    list of str
    """
    from .models import locking_free_models

    found = [n for s in scenes for n in locking_free_models(s)]
    return [
        n
        for n in registry.LOCKING_FREE
        if n in found and all(registry.get(n).applies(s) is None for s in scenes)
    ]


TOP_KEYS = ("name", "scene", "models", "reference", "grid", "cases")


@dataclass
class SweepSpec:
    """A parsed sweep file.

    Attributes
    ----------
    name
        Names the default output folder ``out/sweep-<name>``.
    scene_path
        The scene file; ``scene_data`` is its raw table.
    models
        Model names of :mod:`studies.models`, the reference included.
    reference
        The model every other one is compared with.
    keys
        The swept dotted keys, in file order (the table's first columns).
    cases
        One mapping ``key -> value`` per case (a ``[[cases]]`` table may omit keys).
    """

    name: str
    scene_path: Path
    scene_data: dict
    models: tuple[str, ...]
    reference: str
    keys: tuple[str, ...]
    cases: list[dict[str, Any]]

    def task(self, i: int) -> dict[str, Any]:
        """What a worker needs to run case ``i`` (and what its cache key hashes)."""
        return {
            "scene_path": str(self.scene_path),
            "scene": self.scene_data,
            "values": self.cases[i],
            "models": list(self.models),
            "reference": self.reference,
        }


def flatten(table: Mapping, prefix: str = "") -> dict[str, Any]:
    """``{"a": {"b": 1}, "c.d": 2}`` -> ``{"a.b": 1, "c.d": 2}`` (TOML's dotted keys).

    Examples
    --------
    >>> flatten({"material": {"nu": 0.3}, "mesh.divisions": [1, 1, 1]})
    {'material.nu': 0.3, 'mesh.divisions': [1, 1, 1]}
    """
    out: dict[str, Any] = {}
    for k, v in table.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(flatten(v, key + "."))
        else:
            out[key] = v
    return out


def load_sweep(path: str | os.PathLike, sets: Sequence[str] | None = None) -> SweepSpec:
    """Read and validate a sweep file (one-line :class:`InputError` on bad input).

    Parameters
    ----------
    path
        The sweep TOML file.
    sets
        ``--set key=value`` overrides of the scene, applied under every case.

    Returns
    -------
    SweepSpec
    """
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise InputError(f"sweep file {path} could not be read: {exc.strerror or exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{path}: not valid TOML: {exc}") from None
    return parse_sweep(data, path, sets)


def parse_sweep(
    data: Mapping, path: str | os.PathLike | None = None, sets: Sequence[str] | None = None
) -> SweepSpec:
    """Validate a sweep table; ``path`` (the sweep file) anchors a relative scene path.

    Parameters
    ----------
    data
        The sweep table.
    path
        The sweep file, if any.
    sets
        ``--set key=value`` overrides of the scene, applied under every case.

    Returns
    -------
    SweepSpec
    """
    file = str(path) if path is not None else "<sweep>"
    base = Path(path).parent if path is not None else Path.cwd()

    def fail(msg: str) -> InputError:
        return InputError(f"{file}: {msg}")

    for k in data:
        if k not in TOP_KEYS:
            raise fail(f"{k}: unknown key (valid: {', '.join(TOP_KEYS)})")
    scene = data.get("scene")
    if not isinstance(scene, str):
        raise fail('scene: missing or not a string (a bundled name or a path, e.g. "sag")')
    scene_path = _scene_file(scene, base, fail)
    models = data.get("models", ["spring", "P1", "P2"])
    if not isinstance(models, list) or not models or not all(isinstance(m, str) for m in models):
        raise fail("models: must be a non-empty list of model names")
    try:
        models = [registry.get(m).name for m in models]
    except InputError as exc:
        raise fail(f"models: {exc}") from None
    if len(set(models)) != len(models):
        raise fail("models: a model is listed twice")
    keys, cases = _cases(data, fail)
    scene_data = apply_overrides(read_scene_table(scene_path), map(parse_assignment, sets or []))
    scenes = []
    for case in cases:  # every case's scene is valid before anything is solved
        try:
            scenes.append(scene_with_overrides(scene_data, case.items(), path=scene_path))
        except (SceneError, InputError) as exc:
            raise InputError(f"{file}: case {_show_case(case)}: {exc}") from None
    if "models" not in data:
        models += [n for n in default_locking_free(scenes) if n not in models]
    reference = data.get("reference")
    if reference is None:
        reference = next((m for m in REFERENCE_PREFERENCE if m in models), None)
        if reference is None:
            raise fail('no FEM model listed: add one to models or set reference = "P2"')
    else:
        try:
            reference = registry.get(reference).name
        except InputError as exc:
            raise fail(f"reference: {exc}") from None
        if not declared(registry.get(reference), "reference", default=False):
            raise fail(f"reference: {reference!r} is not a FEM model")
    if reference not in models:
        models = [*models, reference]
    name = data.get("name", Path(file).stem if path is not None else "sweep")
    if not isinstance(name, str) or not name:
        raise fail("name: must be a non-empty string")
    return SweepSpec(name, scene_path, scene_data, tuple(models), reference, keys, cases)


def _scene_file(scene: str, base: Path, fail) -> Path:
    p = base / scene
    if p.is_file():
        return p
    try:
        return bundled(scene)
    except InputError as exc:
        raise fail(f"scene: no file {p} and no bundled scene ({exc})") from None


def _cases(data: Mapping, fail) -> tuple[tuple[str, ...], list[dict[str, Any]]]:
    """The swept keys and the cases of ``[grid]`` or ``[[cases]]``."""
    if "grid" in data and "cases" in data:
        raise fail("use [grid] or [[cases]], not both")
    if "grid" in data:
        if not isinstance(data["grid"], dict):
            raise fail("grid: must be a table of key = [values]")
        grid = flatten(data["grid"])
        for k, v in grid.items():
            if not isinstance(v, list) or not v:
                raise fail(f"grid.{k}: must be a non-empty list of values")
        keys = tuple(grid)
        return keys, [
            dict(zip(keys, combo, strict=True)) for combo in itertools.product(*grid.values())
        ]
    if "cases" in data:
        tables = data["cases"]
        if not isinstance(tables, list) or not all(isinstance(t, dict) for t in tables):
            raise fail("cases: must be an array of tables ([[cases]])")
        cases = [flatten(t) for t in tables]
        keys = tuple(dict.fromkeys(k for c in cases for k in c))
        return keys, cases
    return (), [{}]  # no grid: one case, the scene as it is


def _show_case(case: Mapping) -> str:
    return ", ".join(f"{k}={v!r}" for k, v in case.items()) or "(the scene as is)"
