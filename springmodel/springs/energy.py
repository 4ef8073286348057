"""The spring energy of each element: the potential of the energy forms, nominal otherwise.

Examples
--------
>>> import numpy as np
>>> from springfem.scene import Material
>>> from springmodel.elements import build_spring_elements
>>> from springmodel.options import SpringOptions
>>> X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> e = build_spring_elements(X, np.array([[0, 1, 2, 3]]), np.eye(3)[None],
...                           material=Material("linear", 1.0e4, 0.3))
>>> spring_energy(X, e, SpringOptions())[1]  # no energy at rest
0.0
>>> bool(spring_energy(1.01 * X, e, SpringOptions())[1] > 0)
True
"""

from __future__ import annotations

import numpy as np

from ..axis_springs import axis_spring_energy
from ..elements import SpringElements
from ..options import SpringOptions
from ..rest_geometry import TORSION_PAIRS
from .points import axis_vectors, intersection_points
from .shear import shear_energy


def spring_energy(
    x: np.ndarray, elements: SpringElements, options: SpringOptions
) -> tuple[np.ndarray, float]:
    """Spring energy per element and in total.

    Exact potential of the energy forms (axial linear/polynomial, torsion ``energy``,
    ``shear`` and ``green``, volume
    ``gradient``). For the non-gradient laws it reports the nominal energy each law is
    derived from (``stress-scaled``: ``k d^2/2``; ``cosine``: ``k/2 dc^2``; ``cubic``:
    ``k (dc^2/2 + b dc^4/4)``; ``angle``: ``k/2 (alpha - alpha0)^2``, all with the energy
    constant ``k_torsion``), which is what an energy-drift measurement should watch.

    Parameters
    ----------
    x
        Node positions ``(n, 3)`` (m).
    elements
        Rest data of the ``n_tets`` spring elements.
    options
        The switched-on parts and their laws.

    Returns
    -------
    W, total
        Energy per element ``(n_tets,)`` (J) and its sum.
    """
    X = x[elements.tets]
    q = intersection_points(x, elements)
    zeta, L, u = axis_vectors(q)
    k, l0 = elements.k_axial, elements.l0
    d = L - l0
    if options.axial in ("quadratic", "cubic"):
        b2, b3 = options.axial_coefficients
        b3 = b3 if options.axial == "cubic" else 0.0
    else:
        b2 = b3 = 0.0
    W = np.sum(k * (d**2 / 2 + b2 * d**3 / (3 * l0) + b3 * d**4 / (4 * l0**2)), axis=1)
    if options.torsion != "off":
        for p, (l, m) in enumerate(TORSION_PAIRS):
            c = np.einsum("kc,kc->k", u[:, l], u[:, m])
            dc = c - elements.c0[:, p]
            kt = elements.k_torsion[:, p]
            if options.torsion == "angle":
                da = np.arccos(np.clip(c, -1.0, 1.0)) - elements.alpha0[:, p]
                W += 0.5 * kt * da**2
            elif options.torsion == "shear":
                W += kt * shear_energy(c, elements.c0[:, p])
            elif options.torsion == "green":  # the Green shear gamma = 2 E_lm
                g = np.einsum("kc,kc->k", zeta[:, l], zeta[:, m])
                g = g / (elements.l0[:, l] * elements.l0[:, m])
                W += 0.5 * kt * (g - elements.c0[:, p]) ** 2
            elif options.torsion == "cubic":
                W += kt * (dc**2 / 2 + options.torsion_cubic * dc**4 / 4)
            else:
                W += 0.5 * kt * dc**2
    if options.barycentric_volume:
        r = np.linalg.norm(X - X.mean(axis=1, keepdims=True), axis=-1)
        dL = r.sum(axis=1) - elements.L0
        W += 0.5 * elements.k_volume * dL**2
    if options.axis_volume or options.coupling:
        W += axis_spring_energy(q[:, 0::2] - q[:, 1::2], elements, options)
    return W, float(W.sum())
