"""Rule-based fibres at the quadrature points of a P2 space (docs/fem.rst#active-tension).

A scene's frames are one per element; for ``[axes] type = "rule-based"`` the FEM evaluates
the same rule (:func:`springfem.fibres.rule_based_point_frames`) at each quadrature point
instead, and for ``type = "land-ellipsoid"`` Land's closed-form field
(:func:`springfem.land_fibres.land_frames`) at each quadrature point's own coordinates,
so the fibre follows the helix through a wall only one or two P2 elements thick
(docs/verification.rst#land-problem-3-fibres). P1 has one point, the barycentre, where the
rule gives the element frame, so it keeps the scene's frames; a scene whose frames no
longer come from its ``[axes]`` table (replaced in code) keeps them too.

Examples
--------
>>> from springfem.scene import scene_from_dict
>>> from reference_fem.space import Space
>>> scene = scene_from_dict({
...     "mesh": {"generator": "ellipsoid", "size": 6.0},
...     "material": {"law": "guccione", "C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0,
...                  "kappa": 100.0},
...     "axes": {"type": "rule-based", "endo_angle": -90.0, "epi_angle": 90.0},
...     "boundary": [{"region": "base", "fix": ["x", "y", "z"]}]})
>>> q = quadrature_frames(scene, Space(scene.mesh, 2, 2))
>>> q.shape == (scene.mesh.n_tets, 4, 3, 3), quadrature_frames(scene, Space(scene.mesh, 1, 1))
(True, None)
"""

from __future__ import annotations

import numpy as np

from springfem.fibres import rule_based_point_frames
from springfem.land_fibres import land_frames
from springfem.scene import Scene
from springfem.scene.ventricle import land_settings, rule_based_settings

from .space import Space

#: Median ``|f_element . mean of f_points|`` above which the scene's frames are taken to
#: come from its ``[axes]`` rule (measured 0.999 on Land's ventricle at size 4).
SAME_RULE = 0.99


def quadrature_frames(scene: Scene, space: Space) -> np.ndarray | None:
    """The scene's rule-based or Land frames at the quadrature points of ``space``, or ``None``.

    Parameters
    ----------
    scene
        The scene (its ``raw`` ``[axes]`` table and element ``frames``).
    space
        The FEM space (its order and quadrature).

    Returns
    -------
    numpy.ndarray or None
        ``(m, nq, 3, 3)`` frames; ``None`` for P1, frames that are not rule-based, or frames
        that no longer match the rule.
    """
    table = scene.raw.get("axes")
    kw, land = rule_based_settings(table), land_settings(table)
    if (kw is None and land is None) or space.order == 1:
        return None
    if land is not None:
        q = land_frames(space.quadrature_points(), **land)
    elif kw is not None:
        q = rule_based_point_frames(scene.mesh, space.intorder, **kw)
    mean = q[:, :, 0].mean(axis=1)
    mean /= np.maximum(np.linalg.norm(mean, axis=1, keepdims=True), 1e-300)
    if np.median(np.abs((mean * scene.frames[:, 0]).sum(axis=1))) < SAME_RULE:
        return None
    return q
