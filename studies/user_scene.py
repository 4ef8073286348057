"""What the studies share when they run on a user's scene (``springfem study NAME --scene``).

A case on a user scene carries the scene table, its file (which anchors a relative mesh
path) and the SHA-256 of the mesh file it names, so the cache recomputes the case when the
table or the mesh changes (:func:`scene_case`). Load factors multiply every load value and
every prescribed displacement of the table (:func:`scaled_table`).

Examples
--------
>>> t = {"name": "b", "load": [{"type": "traction", "region": "x_max", "value": [0, 0, -1]}]}
>>> scaled_table(t, 10.0)["load"][0]["value"]
[0.0, 0.0, -10.0]
>>> scene_label({}, "/tmp/my-heart.toml")
'my-heart'
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np

from springfem.scene import Scene, scene_from_dict

from .registry import mesh_digest


def scene_label(table: dict, path: str | None) -> str:
    """The user scene's name: its ``name``, else the file's stem.

    Parameters
    ----------
    table
        The scene table.
    path
        The scene file.

    Returns
    -------
    str
    """
    return str(table.get("name") or Path(path or "scene").stem)


def scene_case(study: str, version: int, table: dict, path: str | None, **extra) -> dict:
    """A JSON-able cache case on a user scene: the table, its file and its mesh digest.

    Parameters
    ----------
    study
        The study's name (so two studies' cases never share a key).
    version
        The study's case version.
    table
        The scene table.
    path
        The scene file.
    **extra
        What else decides the case (model, level, load factor ...).

    Returns
    -------
    dict
    """
    return {
        "study": study,
        "version": version,
        "table": table,
        "path": path,
        "mesh_digest": mesh_digest(table, path),
        **extra,
    }


def _scaled(value: Any, factor: float) -> Any:
    if isinstance(value, list):
        return [_scaled(v, factor) for v in value]
    return float(value) * factor


def scaled_table(table: dict, factor: float) -> dict:
    """The table with every load value and prescribed displacement times ``factor``.

    Parameters
    ----------
    table
        The scene table.
    factor
        The load factor.

    Returns
    -------
    dict
        A copy (the input is not changed).
    """
    data = copy.deepcopy(table)
    for load in data.get("load", []):
        if "value" in load:
            load["value"] = _scaled(load["value"], factor)
    for bc in data.get("boundary", []):
        if "displacement" in bc:
            bc["displacement"] = _scaled(bc["displacement"], factor)
    return data


def case_scene(case: dict, factor: float = 1.0) -> Scene:
    """The scene of a user-scene case, its loads times ``factor``.

    Parameters
    ----------
    case
        A case of :func:`scene_case`.
    factor
        The load factor.

    Returns
    -------
    Scene
    """
    table = case["table"] if factor == 1.0 else scaled_table(case["table"], factor)
    return scene_from_dict(table, path=case["path"])


def body_size(scene: Scene) -> float:
    """The largest extent of the body's bounding box (m).

    Parameters
    ----------
    scene
        The scene.

    Returns
    -------
    float
    """
    lo, hi = scene.mesh.bounding_box()
    return float(np.max(np.asarray(hi) - np.asarray(lo)))
