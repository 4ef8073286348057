"""Volumetric energies ``U(J)`` with their first and second derivatives.

One definition for every model that penalises the volume ratio ``J`` (the FEM's uncoupled
neo-Hookean law and the spring model's axis-volume spring), so that a comparison can use the
same volumetric energy in both:

- ``quadratic``: ``U = kappa/2 (J - 1)^2``,
- ``log``: ``U = kappa/2 ln^2 J``,
- ``simo-taylor``: ``U = kappa/4 (J^2 - 1 - 2 ln J)``.

Each has ``U(1) = U'(1) = 0`` and ``U''(1) = kappa``: at small strain they are the same
energy ``kappa/2 (tr eps)^2``.

Examples
--------
>>> import numpy as np
>>> U, dU, d2U = volumetric_energy(np.array([1.0]), 2.0, "simo-taylor")
>>> float(U[0]), float(dU[0]), float(d2U[0])
(0.0, 0.0, 2.0)
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from .errors import InputError

Volumetric = Literal["quadratic", "log", "simo-taylor"]
VOLUMETRIC_ENERGIES: tuple[str, ...] = ("quadratic", "log", "simo-taylor")
#: Integer codes of the energies for compiled kernels (same order as the names).
VOLUMETRIC_CODES = {name: i for i, name in enumerate(VOLUMETRIC_ENERGIES)}


def volumetric_energy(
    J: np.ndarray, kappa: float | np.ndarray, kind: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``U(J)``, ``U'(J)`` and ``U''(J)`` of the energy ``kind``.

    Parameters
    ----------
    J
        Volume ratios (any shape); ``log`` and ``simo-taylor`` need ``J > 0``.
    kappa
        Bulk modulus (Pa), a scalar or an array broadcastable with ``J``.
    kind
        ``quadratic``, ``log`` or ``simo-taylor``.

    Returns
    -------
    tuple of numpy.ndarray
        The energy density and its first two derivatives in ``J``.

    Raises
    ------
    InputError
        ``kind`` is not one of the three energies.

    Examples
    --------
    >>> volumetric_energy(np.array([2.0]), 1.0, "quadratic")[0]
    array([0.5])
    """
    J = np.asarray(J, dtype=float)
    if kind == "quadratic":
        return 0.5 * kappa * (J - 1.0) ** 2, kappa * (J - 1.0), kappa + 0.0 * J
    if kind == "log":
        lnJ = np.log(J)
        return 0.5 * kappa * lnJ**2, kappa * lnJ / J, kappa * (1.0 - lnJ) / J**2
    if kind == "simo-taylor":
        return (
            0.25 * kappa * (J**2 - 1.0 - 2.0 * np.log(J)),
            0.5 * kappa * (J - 1.0 / J),
            0.5 * kappa * (1.0 + 1.0 / J**2),
        )
    raise InputError(f"volumetric {kind!r} is not one of {', '.join(VOLUMETRIC_ENERGIES)}")
