"""Warnings when the spring model's calibration predicts a large model error.

The spring element is a P1 element with its own small-strain tangent
(docs/theory.rst#the-effective-small-strain-matrix-d-k); its
mismatch against the material (:mod:`springmodel.tangent`, the relative Frobenius norm of the
fourth-order tangent, equal to the Mandel Frobenius norm for symmetric tangents) depends on
the element shapes when the barycentric volume spring is on, and on the axis lengths with the
cosine/angle/cubic torsion laws. :func:`model_warnings` turns it into one line for
``springfem inspect`` and ``springfem solve``: the median and largest mismatch, how many
elements exceed :data:`MISMATCH_WARN`, and the ``[spring]`` settings that remove it.

The threshold is a measured one: spring model against P1 on the same mesh at 1e-3 of the
load over the bundled scenes, 2:1:1 cells and a jittered Delaunay mesh, for every
calibration and volume variant. An element with a mismatch below round-off was within
geometric nonlinearity of P1; otherwise the model error was of the order of the median
mismatch (a fraction of it to a few times it). Below :data:`MISMATCH_WARN` = 0.1 % the
model error stays a small fraction of a percent (docs/theory.rst#measured-calibration-mismatch).

Examples
--------
>>> import numpy as np
>>> from springmodel.options import SpringOptions
>>> fixes(SpringOptions(), transverse=False)
['volume = "axes"', 'torsion = "energy"', 'calibration = "exact"']
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .options import SpringOptions

#: Mismatch above which an element is counted in the warning (relative, 0.1%; see above).
MISMATCH_WARN = 1e-3


def fixes(options: SpringOptions, transverse: bool) -> list[str]:
    """The ``[spring]`` settings that make the element exact, of those not already set.

    Parameters
    ----------
    options
        The scene's spring options.
    transverse
        The material is anisotropic (needs the Poisson-coupling springs).

    Returns
    -------
    list of str
        TOML lines, empty when the options are already the exact ones.
    """
    out = []
    if not options.axis_volume:
        out.append('volume = "axes"')
    if not (options.energy_torsion or options.green_torsion):
        out.append('torsion = "energy"')
    if options.calibration != "exact":
        out.append('calibration = "exact"')
    if transverse and not options.coupling:
        out.append("coupling = true")
    return out


def model_warnings(
    mismatch: np.ndarray, options: SpringOptions, transverse: bool, threshold: float = MISMATCH_WARN
) -> list[str]:
    """Warnings (one line each) for a large predicted model error; empty if none.

    Parameters
    ----------
    mismatch
        Per-element calibration mismatch ``(m,)`` (``nan`` if unknown: no warning).
    options
        The spring options the mismatch belongs to.
    transverse
        Anisotropic material.
    threshold
        Mismatch above which an element counts (default :data:`MISMATCH_WARN`).

    Returns
    -------
    list of str
    """
    mm = np.asarray(mismatch, dtype=float)
    if not np.isfinite(mm).any():
        return []
    bad = int(np.sum(mm > threshold))
    if bad == 0:
        return []
    cause = []
    if options.barycentric_volume:
        cause.append("barycentric volume springs depend on the tet shapes")
    if not (options.energy_torsion or options.green_torsion or options.torsion == "off"):
        cause.append(f"{options.torsion} torsion is no energy")
    if transverse and not options.coupling:
        cause.append("anisotropy needs coupling springs")
    if options.torsion == "off":
        cause.append("torsion is off (no shear stiffness)")
    fix = fixes(options, transverse)
    head = (
        f"spring model: calibration mismatch {np.nanmedian(mm):.2%} (median; max "
        f"{np.nanmax(mm):.2%}; {bad} of {mm.size} tets above {threshold:.1%})"
    )
    if len(fix) > 1:  # the fix implies the cause; the named element sets them all
        alone = ", ".join(fix)
        return [f'{head}, so much model error vs P1; set [spring] element = "exact" (or {alone})']
    if fix:
        return [f"{head}, so much model error vs P1; set {fix[0]} in [spring]"]
    why = f" ({', '.join(cause)})" if cause else ""
    return [f"{head}{why}: the element's constants cannot match the law's tangent exactly"]


def scene_warnings(scene: Any, mismatch: np.ndarray, options: SpringOptions) -> list[str]:
    """:func:`model_warnings` for a scene's material.

    Parameters
    ----------
    scene
        The scene (its material says whether it is transversely isotropic).
    mismatch
        Per-element calibration mismatch ``(m,)``.
    options
        Spring options.

    Returns
    -------
    list of str
        One-line warnings (empty when the model fits the material).
    """
    from springfem.materials import is_transverse

    return model_warnings(mismatch, options, is_transverse(scene.material))
