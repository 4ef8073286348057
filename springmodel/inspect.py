"""Scene statistics for ``springfem inspect``: mesh, quality, axes, intersections."""

from __future__ import annotations

from typing import Any

import numpy as np

from springfem.scene import Scene

from .advice import scene_warnings
from .inert import inert_keys
from .intersections import axis_vectors, cast_rays
from .options import SpringOptions
from .tangent import MISMATCH_NORM


def inspect_scene(scene: Scene, calibration: bool = True) -> dict[str, Any]:
    """Counts, volume, element quality, axis lengths and ray-cast success of a scene.

    With ``calibration`` (and the spring calibration module present) the distribution of
    the spring element's calibration mismatch is included too (its norm named in
    ``calibration_mismatch_norm``), and ``warnings`` lists the predicted model errors and the
    options that fix them (:mod:`springmodel.advice`).

    Parameters
    ----------
    scene
        The scene to describe.
    calibration
        Include the calibration mismatch and warnings.

    Returns
    -------
    dict
        JSON-ready statistics.

    Examples
    --------
    The default element (the exact one) matches P1 on every tet; the specification's
    element does not, and says so:

    >>> from springfem.scene import scene_from_dict
    >>> d = {"mesh": {"generator": "box", "size": [0.1, 0.01, 0.01], "divisions": [10, 1, 1]},
    ...      "material": {"law": "linear", "E": 1.0e4, "nu": 0.3}}
    >>> report = inspect_scene(scene_from_dict(d))
    >>> report["tets"], len(report["warnings"])
    (60, 0)
    >>> seed = inspect_scene(scene_from_dict({**d, "spring": {"element": "seed"}}))
    >>> [("calibration mismatch" in w) for w in seed["warnings"]]
    [True]
    """
    mesh = scene.mesh
    q = mesh.quality()
    rc = cast_rays(mesh.points, mesh.tets, scene.frames)
    lengths = np.linalg.norm(axis_vectors(mesh.points, mesh.tets, rc.coefficients), axis=2)
    lo, hi = mesh.bounding_box()
    out: dict[str, Any] = {
        "scene": scene.name,
        "mesh": mesh.source,
        "nodes": mesh.n_points,
        "tets": mesh.n_tets,
        "volume": float(mesh.volumes().sum()),
        "bounding_box": [lo.tolist(), hi.tolist()],
        "quality_min": float(q.min()),
        "quality_max": float(q.max()),
        "axis_length_min": float(lengths.min()),
        "axis_length_max": float(lengths.max()),
        "all_rays_hit": int(rc.all_hit.sum()),
        "material": scene.material.law,
        "boundaries": [b.region.name for b in scene.boundaries],
        "loads": [ld.type for ld in scene.loads],
        "probes": [p.name for p in scene.probes],
    }
    if calibration:
        out.update(_calibration_stats(scene))
    return out


def _calibration_stats(scene: Scene) -> dict[str, Any]:
    try:
        from .model import SpringModel
    except ImportError:  # spring model not built yet
        return {}
    options = SpringOptions.of(scene)
    model = SpringModel(scene, options)
    mm = np.asarray(model.elements.mismatch)
    return {
        "calibration": options.calibration,
        "calibration_mismatch_norm": MISMATCH_NORM,
        "calibration_mismatch_min": float(mm.min()),
        "calibration_mismatch_median": float(np.median(mm)),
        "calibration_mismatch_max": float(mm.max()),
        "warnings": scene_warnings(scene, mm, options),
        "notes": inert_keys(scene, options),
    }
