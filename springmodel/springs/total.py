"""The sum of the switched-on spring forces, and whether it derives from an energy.

Examples
--------
>>> from springmodel.options import SpringOptions
>>> is_conservative(SpringOptions(torsion="energy"))  # all energy forms, no damping
True
>>> is_conservative(SpringOptions(torsion="cosine"))  # the spec's torsion is no gradient
False
"""

from __future__ import annotations

import numpy as np

from ..elements import SpringElements
from ..options import SpringOptions, VolumeForm
from .axial import axial_forces
from .axis_volume import axis_forces
from .torsion import torsion_forces
from .volume import resolve_volume_form, volume_forces


def internal_forces(
    x: np.ndarray,
    v: np.ndarray | None,
    elements: SpringElements,
    options: SpringOptions,
    volume_form: VolumeForm | None = None,
) -> np.ndarray:
    """Sum of the enabled spring forces at positions ``x`` and velocities ``v``.

    Only the enabled parts are computed: axial always, torsion unless ``off``, volume if
    ``options.volume`` (barycentric or axes), coupling if on; damping terms only if their
    coefficient is positive and ``v`` given.

    Parameters
    ----------
    x, v
        Positions (m) and velocities (m/s) ``(n, 3)`` (``v`` None: no damping).
    elements, options
        :class:`~springmodel.elements.SpringElements` rest data and
        :class:`~springmodel.options.SpringOptions` parts and laws.
    volume_form
        Overrides ``options.volume_form``.

    Returns
    -------
    ndarray
        Nodal forces ``(n, 3)`` (N).
    """
    f = axial_forces(x, v, elements, options)
    if options.torsion != "off":
        f += torsion_forces(x, elements, options)
    if options.barycentric_volume:
        f += volume_forces(x, v, elements, options, volume_form)
    if options.axis_volume or options.coupling:
        f += axis_forces(x, v, elements, options)
    return f


def is_conservative(options: SpringOptions, volume_form: VolumeForm | None = None) -> bool:
    """Whether the enabled forces are ``-grad`` of :func:`~springmodel.springs.spring_energy`.

    Parameters
    ----------
    options
        Parts, laws, damping and LMS settings.
    volume_form
        Overrides ``options.volume_form``.

    Returns
    -------
    bool
        True for axial ``linear``/``quadratic``/``cubic``, torsion ``off``/``energy``/``shear``/
        ``green`` (its energy is :mod:`springmodel.tissue_element`'s),
        barycentric volume (if on) in ``gradient`` form, no damping and no LMS on the
        barycentric volume springs.
    """
    return (
        options.axial in ("linear", "quadratic", "cubic")
        and (options.torsion == "off" or options.energy_torsion or options.green_torsion)
        and (
            not options.barycentric_volume
            or resolve_volume_form(options, volume_form) == "gradient"
        )
        and options.axial_damping == 0
        and (not options.volume or options.volume_damping == 0)
        and (options.lms is None or not options.barycentric_volume)
    )
