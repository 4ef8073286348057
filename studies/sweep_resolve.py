"""Sweep cases that resolve to the same computation, so a sweep solves them once.

Two cases are the same when, after their values are applied and every option is resolved,
each model would solve the same problem: the same scene apart from its ``[spring]``
section, and for each spring model the same resolved options (calibration aside) and
the same calibrated spring constants. A sweep over ``spring.calibration = ["analytic",
"exact"]`` on an isotropic law, whose two calibrations give the same constants for the
specification's parts, then solves each pair once. :func:`resolved_key` is that identity;
:func:`duplicates` groups the cases by it.

Examples
--------
The cantilever's material is isotropic: ``exact`` gives the specification's parts the
``analytic`` constants, ``analytic-lsq`` other volume constants.

>>> from studies.sweep_file import parse_sweep
>>> cal = ["analytic", "exact", "analytic-lsq"]
>>> grid = {"mesh.divisions": [[4, 1, 1]], "spring.calibration": cal}
>>> spec = parse_sweep({"scene": "cantilever", "models": ["spring", "P1"], "grid": grid})
>>> duplicates([spec.task(i) for i in range(3)])
{1: 0}
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from springfem.errors import SpringFemError
from springfem.files import jsonable
from springfem.model_api import declared

from . import models
from .overrides import scene_with_overrides

#: The calibrated constants that define a spring element.
CONSTANTS = ("k_axial", "k_torsion", "k_volume", "k_axis_volume", "k_coupling")


def resolved_key(task: dict[str, Any]) -> str:
    """The identity of a sweep case's computation (see the module docstring).

    Parameters
    ----------
    task
        :meth:`studies.sweep_file.SweepSpec.task`.

    Returns
    -------
    str
        A SHA-256 hex digest.
    """
    from springmodel.elements import build_spring_elements

    scene = scene_with_overrides(task["scene"], task["values"].items(), path=task["scene_path"])
    raw = {k: v for k, v in scene.raw.items() if k not in ("spring", "name")}
    h = hashlib.sha256(json.dumps(jsonable(raw), sort_keys=True, default=str).encode())
    h.update(np.ascontiguousarray(scene.mesh.points).tobytes())
    h.update(np.ascontiguousarray(scene.mesh.tets).tobytes())
    h.update(repr((task["models"], task["reference"])).encode())
    for name in task["models"]:
        opts = declared(models.get(name), "spring_options", scene)
        if opts is None:
            continue
        h.update(repr(replace(opts, calibration="analytic")).encode())
        el = build_spring_elements(
            scene.mesh.points, scene.mesh.tets, scene.frames, opts, scene.material
        )
        for c in CONSTANTS:
            value = getattr(el, c, None)
            if value is not None:
                h.update(np.ascontiguousarray(value, dtype=float).tobytes())
    return h.hexdigest()


def duplicates(tasks: Sequence[dict[str, Any]]) -> dict[int, int]:
    """Case index -> the index of the first case with the same computation.

    Parameters
    ----------
    tasks
        The sweep's tasks, in case order.

    Returns
    -------
    dict
        Only the later cases of each group (empty when every case differs).
    """
    first: dict[str, int] = {}
    out: dict[int, int] = {}
    for i, task in enumerate(tasks):
        try:
            key = resolved_key(task)
        except (SpringFemError, ValueError):  # the case's own solve reports the problem
            continue
        if key in first:
            out[i] = first[key]
        else:
            first[key] = i
    return out


def difference(a: dict[str, Any], b: dict[str, Any]) -> str:
    """The swept values in which two cases differ, as ``key = a vs b``.

    Parameters
    ----------
    a, b
        The two cases' values.

    Returns
    -------
    str

    Examples
    --------
    >>> difference({"spring.calibration": "exact", "material.nu": 0.3},
    ...            {"spring.calibration": "analytic", "material.nu": 0.3})
    'spring.calibration = exact vs analytic'
    """
    keys = [k for k in a if a.get(k) != b.get(k)]
    return ", ".join(f"{k} = {a.get(k)} vs {b.get(k)}" for k in keys)
