"""Axial springs along the three axes (eqs. 2.34–2.38), with optional axial damping.

Axis ``l`` carries the force ``s_l zeta_hat_l`` on ``q_{2l}`` and ``-s_l zeta_hat_l`` on
``q_{2l+1}`` (eq. 2.34), ``d = |zeta_l| - l0_l``; the laws are listed in
:mod:`springmodel.springs`.

Examples
--------
>>> import numpy as np
>>> from types import SimpleNamespace
>>> from springmodel.options import SpringOptions
>>> e = SimpleNamespace(k_axial=np.array([[2.0, 2.0, 2.0]]), l0=np.array([[1.0, 1.0, 1.0]]))
>>> L = np.array([[1.1, 1.0, 0.9]])  # stretched, at rest, compressed
>>> axial_magnitudes(L, None, e, SpringOptions(axial="linear")).round(12).tolist()
[[-0.2, -0.0, 0.2]]
"""

from __future__ import annotations

import numpy as np

from springfem.mesh import tet_volumes

from ..elements import SpringElements
from ..options import SpringOptions
from .points import (
    add_pair_forces,
    axis_vectors,
    distribute,
    intersection_points,
    scatter,
)


def axial_magnitudes(
    L: np.ndarray, x: np.ndarray | None, elements: SpringElements, options: SpringOptions
) -> np.ndarray:
    """Signed axial force magnitudes ``s_l`` (force ``s_l zeta_hat_l`` on ``q_{2l}``).

    Parameters
    ----------
    L
        Current axis lengths ``|zeta_l|`` ``(n_tets, 3)`` (m).
    x
        Node positions ``(n, 3)`` (m); used only by ``stress-scaled`` (for the current
        volume), may be None otherwise.
    elements
        Rest data: ``k_axial`` ``(n_tets, 3)`` (N/m), ``l0`` ``(n_tets, 3)``, ``V0``.
    options
        ``options.axial`` (the law) and ``options.axial_coefficients`` ``(b2, b3)``.

    Returns
    -------
    ndarray
        ``(n_tets, 3)`` (N); negative when the axis is stretched (the force pulls the ends
        together).

    Raises
    ------
    ValueError
        If ``options.axial`` is not one of linear, quadratic, cubic, stress-scaled.
    """
    k, l0 = elements.k_axial, elements.l0
    d = L - l0
    law = options.axial
    if law == "linear":
        return -k * d  # eq. 2.35
    if law in ("quadratic", "cubic"):
        b2, b3 = options.axial_coefficients
        b3 = b3 if law == "cubic" else 0.0
        return -k * (d + b2 * d**2 / l0 + b3 * d**3 / l0**2)  # eq. 2.36
    if law == "stress-scaled":
        V = tet_volumes(x, elements.tets)
        return -k * d * (l0 / L) * (V / elements.V0)[:, None]  # E (d/l0) (V/|zeta|)
    raise ValueError(f"axial law {law!r} is not one of linear, quadratic, cubic, stress-scaled")


def axial_forces(
    x: np.ndarray,
    v: np.ndarray | None,
    elements: SpringElements,
    options: SpringOptions,
) -> np.ndarray:
    """Axial spring forces (2.35–2.38) plus optional axial damping, on the nodes.

    The damping adds ``-c_a ((v_{2l} - v_{2l+1}) . zeta_hat_l)`` to ``s_l`` (zero for rigid
    motion), ``c_a = options.axial_damping`` (N s/m).

    Parameters
    ----------
    x
        Node positions ``(n, 3)`` (m).
    v
        Node velocities ``(n, 3)`` (m/s), or None for no damping.
    elements
        Rest data of the ``n_tets`` spring elements.
    options
        Axial law, its coefficients and ``axial_damping``.

    Returns
    -------
    ndarray
        Nodal forces ``(n, 3)`` (N); net force and net torque zero.
    """
    q = intersection_points(x, elements)
    _, L, u = axis_vectors(q)
    s = axial_magnitudes(L, x, elements, options)
    if options.axial_damping > 0 and v is not None:
        vq = intersection_points(v, elements)
        w = vq[:, 0::2] - vq[:, 1::2]  # relative velocity of the two ends
        s = s - options.axial_damping * np.einsum("klc,klc->kl", w, u)
    fq = np.zeros_like(q)
    for l in range(3):
        add_pair_forces(fq, s[:, l], l, u[:, l])  # eq. 2.34: f_{l,2} = -f_{l,1}
    return scatter(distribute(fq, elements), elements.tets, x.shape[0])
