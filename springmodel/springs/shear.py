"""The ``shear`` torsion law as a function of the cosine ``c`` between two axes.

``U = k/2 delta^2`` with ``delta = s0^3 (cot(theta) - cot(theta0))``, ``theta`` the angle
between the two axes, ``cot(theta) = c / sqrt(1 - c^2)`` and ``s0 = sin(theta0)``. In a
simple shear by ``gamma`` of two initially orthogonal axes ``cot(theta) = tan(gamma)``, the
simple-shear amount, so ``U = k/2 tan^2(gamma)``: convex in the shear amount at every angle,
whereas the ``energy`` law ``U = k/2 (c - c0)^2 = k/2 sin^2(gamma)`` has its moment
``k/2 sin(2 gamma)`` peak at 45 deg and loses its shear stiffness beyond. Near rest
``delta = (c - c0) + O((c - c0)^2)`` (``d cot / dc = (1 - c^2)^(-3/2)``, times ``s0^3``), so
the two laws have the same small-strain tangent.

The functions return ``U / k`` and its first two derivatives in ``c`` (the chain rule to the
axis vectors is the ``energy`` law's, with ``c - c0`` replaced by ``dU/dc / k``). ``1 - c^2``
is floored at :data:`SHEAR_FLOOR` (two axes parallel to round-off), as in the fused kernel.

Examples
--------
>>> import numpy as np
>>> c = np.sin(np.radians(30.0))  # 30 deg simple shear of orthogonal axes
>>> bool(abs(shear_energy(c, 0.0) - 0.5 * np.tan(np.radians(30.0)) ** 2) < 1e-15)
True
>>> [float(v) for v in shear_derivatives(np.array(0.0), np.array(0.0))]  # at rest: 0 and 1
[0.0, 1.0]
"""

from __future__ import annotations

import numpy as np

#: Floor of ``1 - c^2`` (axes parallel to round-off); the fused kernel uses the same value.
SHEAR_FLOOR = 1e-12


def shear_measure(c: np.ndarray, c0: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``delta`` and its derivatives ``d delta / dc``, ``d^2 delta / dc^2``.

    Parameters
    ----------
    c, c0
        Current and rest cosines between the two axes (broadcastable arrays).

    Returns
    -------
    delta, d1, d2
        ``s0^3 (cot(theta) - cot(theta0))``, ``s0^3 (1 - c^2)^(-3/2)`` and
        ``3 c s0^3 (1 - c^2)^(-5/2)``.
    """
    c, c0 = np.asarray(c, dtype=float), np.asarray(c0, dtype=float)
    g = np.maximum(1.0 - c * c, SHEAR_FLOOR)
    g0 = 1.0 - c0 * c0
    s03 = g0 * np.sqrt(g0)
    delta = s03 * (c / np.sqrt(g) - c0 / np.sqrt(g0))
    d1 = s03 / (g * np.sqrt(g))
    d2 = 3.0 * c * d1 / g
    return delta, d1, d2


def shear_energy(c: np.ndarray, c0: np.ndarray) -> np.ndarray:
    """``U / k = delta^2 / 2``.

    Parameters
    ----------
    c, c0
        Current and rest cosines.

    Returns
    -------
    ndarray
        The energy per unit torsion constant (dimensionless).
    """
    delta, _, _ = shear_measure(c, c0)
    return 0.5 * delta * delta


def shear_derivatives(c: np.ndarray, c0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``dU/dc / k = delta delta'`` and ``d^2U/dc^2 / k = delta'^2 + delta delta''``.

    Parameters
    ----------
    c, c0
        Current and rest cosines.

    Returns
    -------
    d1, d2
        First and second derivatives of ``U / k`` in ``c``.
    """
    delta, d1, d2 = shear_measure(c, c0)
    return delta * d1, d1 * d1 + delta * d2
