"""Compiled pass of :mod:`springmodel.stiffening`: ``W_q``, ``s_e`` and the added forces.

One serial loop over the elements, the same formulas as
:func:`springmodel.stiffening.deviatoric_energy` (the vectorised numpy reference, which the
tests compare it with): the axis vectors ``zeta_l = sum_i G[k, i, l] x_i``, the polynomial
axial energy, the ``energy`` (code 1) or ``shear`` (code 2) torsion law, the Poisson coupling,
then ``s_e = exp(2 W_q / (C V))`` and, when asked, the forces ``-(s_e - 1) grad W_q`` summed
into the nodes (or the gradients per element, for the tangent). Measured with
``springfem bench forces --tets 40000 --repeats 5 --variants`` (40,500 tets, float64, serial,
load 0.8-1.0): the stiffened exact element (fused kernel + this pass) 4.9 M tets/s against
22-24 M tets/s for the fused kernels alone, i.e. this pass costs about 3.5 kernels; the
numpy reference is about 50 kernels. Fusing it into the kernel would remove most of it.

Examples
--------
>>> import numpy as np
>>> x = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> G = np.zeros((1, 4, 3)); G[0, 1, 0] = G[0, 2, 1] = G[0, 3, 2] = 1.0; G[0, 0] = -1.0
>>> W, s = np.zeros(1), np.zeros(1)
>>> f = np.zeros((4, 3))
>>> stiffening_pass(1.2 * x, np.array([[0, 1, 2, 3]]), G, np.ones((1, 3)),
...                 np.ones((1, 3)), np.zeros((1, 3)), np.zeros((1, 3)), np.zeros((1, 3)),
...                 np.ones(1), 0.0, 0.0, 0, False, 10.0, 60.0, W, s, f, True,
...                 np.empty((1, 4, 3)), False)
>>> round(float(W[0]), 12)  # three unit axial springs stretched by 20 %: 3 x 0.2^2 / 2
0.06
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .rest_geometry import TORSION_PAIRS
from .shear_numba import shear_terms


@njit(cache=True, fastmath=False)
def stiffening_pass(
    x, tets, G, l0, ka, kt, c0, kc, V0, b2, b3, torsion, coupling, modulus, max_q,
    W_out, s_out, f_out, forces, g_out, gradients
):  # fmt: skip  # pragma: no cover - compiled; checked against the numpy reference in tests
    """``W_q`` and ``s_e`` of every element into ``W_out``, ``s_out`` ``(m,)``; with
    ``forces``, add ``-(s_e - 1) grad W_q`` into ``f_out`` ``(n, 3)``.

    Parameters
    ----------
    x, tets, G, l0, ka, kt, c0, kc, V0
        Positions ``(n, 3)`` and the elements' rest data (connectivity, axis gradients
        ``(m, 4, 3)``, rest lengths, axial, torsion and coupling constants ``(m, 3)``, rest
        cosines, rest volumes).
    b2, b3
        Polynomial axial coefficients.
    torsion
        0 off, 1 ``energy``, 2 ``shear``.
    coupling
        Poisson coupling on.
    modulus, max_q
        ``C`` and the largest exponent evaluated (beyond it ``s_e = inf``).
    W_out, s_out, f_out
        Outputs (``f_out`` is added to).
    forces
        Whether to add the forces.
    g_out, gradients
        ``grad W_q`` of each element's vertices ``(m, 4, 3)``, written when ``gradients``.

    Returns
    -------
    None
    """
    m = tets.shape[0]
    z = np.empty((3, 3))
    U = np.empty((3, 3))
    L = np.empty(3)
    gz = np.empty((3, 3))
    sl = np.empty(3)
    for k in range(m):
        for l in range(3):
            for c in range(3):
                v = 0.0
                for i in range(4):
                    v += G[k, i, l] * x[tets[k, i], c]
                z[l, c] = v
            L[l] = math.sqrt(z[l, 0] ** 2 + z[l, 1] ** 2 + z[l, 2] ** 2)
            for c in range(3):
                U[l, c] = z[l, c] / L[l]
        W = 0.0
        for l in range(3):
            d = L[l] - l0[k, l]
            r = d / l0[k, l]
            W += ka[k, l] * d * d * (0.5 + b2 * r / 3.0 + b3 * r * r / 4.0)
            f1 = ka[k, l] * d * (1.0 + b2 * r + b3 * r * r)
            for c in range(3):
                gz[l, c] = f1 * U[l, c]
            sl[l] = L[l] / l0[k, l] - 1.0
        for p in range(3):
            l, q = TORSION_PAIRS[p]
            if torsion != 0:
                cos = U[l, 0] * U[q, 0] + U[l, 1] * U[q, 1] + U[l, 2] * U[q, 2]
                kk = kt[k, p]
                if torsion == 2:
                    delta, e1, _ = shear_terms(cos, c0[k, p])
                    W += 0.5 * kk * delta * delta
                    d1 = kk * delta * e1
                else:
                    dc = cos - c0[k, p]
                    W += 0.5 * kk * dc * dc
                    d1 = kk * dc
                for c in range(3):
                    gz[l, c] += d1 * (U[q, c] - cos * U[l, c]) / L[l]
                    gz[q, c] += d1 * (U[l, c] - cos * U[q, c]) / L[q]
            if coupling:
                cp = kc[k, p]
                W += cp * sl[l] * sl[q]
                for c in range(3):
                    gz[l, c] += cp * sl[q] / l0[k, l] * U[l, c]
                    gz[q, c] += cp * sl[l] / l0[k, q] * U[q, c]
        e = 2.0 * W / (modulus * V0[k])
        s = math.exp(e) if e <= max_q else math.inf
        W_out[k] = W
        s_out[k] = s
        if forces or gradients:
            w = s - 1.0
            for i in range(4):
                node = tets[k, i]
                for c in range(3):
                    v = 0.0
                    for l in range(3):
                        v += G[k, i, l] * gz[l, c]
                    if forces:
                        f_out[node, c] -= w * v
                    if gradients:
                        g_out[k, i, c] = v
