"""The ``shear`` torsion measure for the compiled float64 kernels (Hessian, stiffening).

The same formulas as :func:`springmodel.springs.shear.shear_measure` (the numpy reference the
tests compare the kernels with), one cosine at a time; the force kernels of
:mod:`springmodel.fastkernels` keep their own precision-generic slope.

Examples
--------
>>> delta, d1, d2 = shear_terms(0.0, 0.0)  # at rest between orthogonal axes
>>> float(delta), float(d1), float(d2)
(0.0, 1.0, 0.0)
"""

from __future__ import annotations

import math

from numba import njit

from .springs.shear import SHEAR_FLOOR


@njit(cache=True, fastmath=False)
def shear_terms(c, c0):  # pragma: no cover - compiled; checked against the numpy reference
    """``delta = s0^3 (cot(theta) - cot(theta0))`` and its first two derivatives in ``c``.

    Parameters
    ----------
    c, c0
        Current and rest cosines between two axes.

    Returns
    -------
    delta, d1, d2
        ``delta``, ``s0^3 (1 - c^2)^(-3/2)`` and ``3 c d1 / (1 - c^2)`` (``1 - c^2`` floored
        at :data:`~springmodel.springs.shear.SHEAR_FLOOR`).
    """
    g = max(1.0 - c * c, SHEAR_FLOOR)
    g0 = 1.0 - c0 * c0
    s03 = g0 * math.sqrt(g0)
    delta = s03 * (c / math.sqrt(g) - c0 / math.sqrt(g0))
    d1 = s03 / (g * math.sqrt(g))
    return delta, d1, 3.0 * c * d1 / g
