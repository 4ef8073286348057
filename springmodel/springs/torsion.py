"""Torsion springs between each pair of axes (eqs. 2.40–2.50, and the energy form).

For the pairs ``(l, m)`` in (0,1), (0,2), (1,2), ``c = zeta_hat_l . zeta_hat_m``; the laws
``energy``, ``shear`` (:mod:`springmodel.springs.shear`), ``cosine``, ``cubic`` and
``angle`` and their signs are described in
:mod:`springmodel.springs`.

Examples
--------
>>> import numpy as np
>>> from types import SimpleNamespace
>>> from springmodel.options import SpringOptions
>>> x = np.zeros((4, 3))
>>> torsion_forces(x, SimpleNamespace(), SpringOptions(torsion="off")).shape  # law off
(4, 3)
"""

from __future__ import annotations

import numpy as np

from ..elements import SpringElements
from ..options import ENERGY_TORSION, GREEN_TORSION, SpringOptions
from ..rest_geometry import TORSION_PAIRS
from .points import add_pair_forces, axis_vectors, distribute, intersection_points, scatter
from .shear import shear_derivatives


def torsion_forces(x: np.ndarray, elements: SpringElements, options: SpringOptions) -> np.ndarray:
    """Torsion spring forces for the law ``options.torsion``, on the nodes.

    Parameters
    ----------
    x
        Node positions ``(n, 3)`` (m).
    elements
        Rest data: cosines ``c0`` and angles ``alpha0`` ``(n_tets, 3)``, ``k_torsion`` (J,
        energy and shear laws) and ``k_torsion_force`` (N, the other laws).
    options
        ``options.torsion`` (``off``, ``angle``, ``cosine``, ``cubic``, ``energy``,
        ``shear``, ``green``) and
        ``options.torsion_cubic`` (the ``cubic`` law's ``b``).

    Returns
    -------
    ndarray
        Nodal forces ``(n, 3)`` (N); zeros for ``off``. Net force is zero for every law;
        net torque is zero for ``energy``, ``shear`` and ``green``, and for the other laws only when
        the two axes of each pair are equally long.

    Raises
    ------
    ValueError
        If ``options.torsion`` is not one of off, angle, cosine, cubic, energy, shear, green.
    """
    law = options.torsion
    if law == "off":
        return np.zeros_like(x)
    q = intersection_points(x, elements)
    zeta, L, u = axis_vectors(q)
    fq = np.zeros_like(q)
    kf = elements.k_torsion_force
    for p, (l, m) in enumerate(TORSION_PAIRS):
        ul, um = u[:, l], u[:, m]
        if law == GREEN_TORSION:  # -dU/dx, U = k/2 (gamma - gamma0)^2 on the Green shear
            ll, lm = elements.l0[:, l], elements.l0[:, m]
            g = np.einsum("kc,kc->k", zeta[:, l], zeta[:, m]) / (ll * lm)
            s = -elements.k_torsion[:, p] * (g - elements.c0[:, p]) / (ll * lm)
            add_pair_forces(fq, s, l, zeta[:, m])
            add_pair_forces(fq, s, m, zeta[:, l])
            continue
        c = np.einsum("kc,kc->k", ul, um)  # eq. 2.32
        dc = c - elements.c0[:, p]
        if law in ENERGY_TORSION:  # -dU/dx, U = k phi(c): dc is phi'(c)
            if law == "shear":
                dc, _ = shear_derivatives(c, elements.c0[:, p])
            k = elements.k_torsion[:, p]
            add_pair_forces(fq, -k * dc / L[:, l], l, um - c[:, None] * ul)
            add_pair_forces(fq, -k * dc / L[:, m], m, ul - c[:, None] * um)
            continue
        if law == "cosine":
            s = -kf[:, p] * dc  # eqs. 2.44–2.45
        elif law == "cubic":
            s = -kf[:, p] * (dc + options.torsion_cubic * dc**3)  # eqs. 2.47–2.50
        elif law == "angle":
            alpha = np.arccos(np.clip(c, -1.0, 1.0))
            s = kf[:, p] * (alpha - elements.alpha0[:, p])  # eqs. 2.40–2.41, restoring sign
        else:
            raise ValueError(
                f"torsion law {law!r} is not one of off, angle, cosine, cubic, energy, shear, green"
            )
        add_pair_forces(fq, s, l, um)  # f_{l->m} on the ends of axis l
        add_pair_forces(fq, s, m, ul)  # f_{m->l} on the ends of axis m
    return scatter(distribute(fq, elements), elements.tets, x.shape[0])
