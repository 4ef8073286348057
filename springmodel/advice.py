"""Warnings when the spring model's calibration predicts a large model error.

The spring element is a P1 element with its own small-strain tangent (DESIGN §4); its
mismatch against the material (:mod:`springmodel.tangent`, the relative Frobenius norm of the
fourth-order tangent, equal to the Mandel Frobenius norm for symmetric tangents) depends on
the element shapes when the barycentric volume spring is on, and on the axis lengths with the
cosine/angle/cubic torsion laws. :func:`model_warnings` turns it into one line for
``springfem inspect`` and ``springfem solve``: how many elements exceed
:data:`MISMATCH_WARN`, and which options remove the mismatch.

The threshold is backed by a measurement (spring vs P1 on the same mesh at 1e-3 of the load,
relative L2 of the displacement; bundled cantilever, sag and both stretch scenes, the
cantilever at 20x4x4 (cells 2:1:1) and on a jittered-Delaunay mesh; variants: seed with
cosine and with energy torsion, ``analytic-lsq``, ``nnls``, axis volume with cosine torsion,
exact with and without coupling; 38 runs). Every run with a median mismatch below 1e-14 was
within 3e-5 of P1 (geometric nonlinearity only). Otherwise the model error was 0.04-3.9
times the median mismatch: the barycentric volume spring's mismatch (0.24-0.94) over-predicts
(errors 2-63%), while the cosine law's skew part (mismatch 0.12 on 2:1:1 cells -> 46% error)
and a transverse material without coupling (mismatch 0.0035 -> 0.6-1.2%) under-predict by up
to ~4x. So :data:`MISMATCH_WARN` = 0.1%: below it the model error is expected to stay below
~0.4%.

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
from .tangent import MISMATCH_NORM

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
    if not options.energy_torsion:
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
        cause.append("the barycentric volume spring depends on the element shapes")
    if not (options.energy_torsion or options.torsion == "off"):
        cause.append(f"{options.torsion} torsion is not the gradient of an energy")
    if transverse and not options.coupling:
        cause.append("an anisotropic material needs the Poisson-coupling springs")
    if options.torsion == "off":
        cause.append("torsion is off (no shear stiffness)")
    fix = fixes(options, transverse)
    fix_text = f"set {', '.join(fix)} in [spring]" if fix else "no option removes it"
    return [
        f"spring model: {bad} of {mm.size} elements have a calibration mismatch above "
        f"{threshold:.1%} (median {np.nanmedian(mm):.2%}, max {np.nanmax(mm):.2%}; "
        f"{MISMATCH_NORM}), which predicts a model error vs P1 of 0.04-4x the median "
        "(measured)" + (f" ({'; '.join(cause)})" if cause else "") + f"; {fix_text}"
    ]


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
