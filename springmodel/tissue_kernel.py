"""Compiled pass of :mod:`springmodel.tissue_element`: the element energies and forces.

One serial loop over the elements, the same formulas as
:func:`springmodel.tissue_element.tissue_energy` (the vectorised numpy reference, which the
tests compare it with to 1e-12): ``Z_l = sum_i G_il x_i / l_l^0``, the six measures
``m = (Z_l . Z_l, Z_l . Z_m)``, the energy ``W(m)`` and ``dW/dm`` of the mode (0 quadratic
springs, 1 exponential stiffening, 2 Guccione, 3 Holzapfel–Ogden), then
``dW/dZ_l = 2 W_l Z_l + sum_m W_lm Z_m`` and the forces ``-sum_l G_il / l_l^0 dW/dZ_l``.

Examples
--------
>>> import numpy as np
>>> x = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> G = np.zeros((1, 4, 3)); G[0, 1, 0] = G[0, 2, 1] = G[0, 3, 2] = 1.0; G[0, 0] = -1.0
>>> W, s, f = np.zeros(1), np.zeros(1), np.zeros((4, 3))
>>> tissue_pass(1.2 * x, np.array([[0, 1, 2, 3]]), G, np.ones((1, 3)), np.ones((1, 3)),
...             np.zeros((1, 3)), np.zeros((1, 3)), np.zeros((1, 3)), np.ones(1), 0.0, 0.0,
...             0, 1.0, np.zeros(8), 60.0, 1e-12, W, s, f, True)
>>> round(float(W[0]), 12)  # three unit linear axial springs stretched by 20 %: 3 x 0.2^2 / 2
0.06
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .rest_geometry import TORSION_PAIRS


@njit(cache=True, fastmath=False)
def _exp_group(a, b, x, max_q):  # pragma: no cover - compiled
    """``(a/(2b)(e^{b x^2} - 1), a x e^{b x^2}, e^{b x^2})`` (``inf`` past ``max_q``)."""
    q = b * x * x
    if q > max_q:
        return math.inf, math.inf, math.inf
    e = math.exp(q)
    return a / (2.0 * b) * (e - 1.0), a * x * e, e


@njit(cache=True, fastmath=False)
def _measure_energy(
    mm, dW, sl, lam, k, l0, ka, kt, c0, kc, V, b2, b3, mode, modulus, law, max_q, tension
):  # fmt: skip  # pragma: no cover - compiled
    """``W(m)`` of element ``k`` and ``dW/dm`` into ``dW`` (6,); returns ``(W, s)``.

    ``sl``, ``lam`` (3,) are scratch for the axial strains and stretches."""
    for a in range(6):
        dW[a] = 0.0
    if mode <= 1:
        W = 0.0
        for l in range(3):
            lam[l] = math.sqrt(mm[l])
            s = lam[l] - 1.0
            sl[l] = s
            kl2 = ka[k, l] * l0[k, l] * l0[k, l]
            W += kl2 * s * s * (0.5 + b2 * s / 3.0 + b3 * s * s / 4.0)
            dW[l] = kl2 * s * (1.0 + b2 * s + b3 * s * s) / (2.0 * lam[l])
        for p in range(3):
            g = mm[3 + p] - c0[k, p]
            W += 0.5 * kt[k, p] * g * g
            dW[3 + p] = kt[k, p] * g
            l, q = TORSION_PAIRS[p]
            c = kc[k, p]
            W += c * sl[l] * sl[q]
            dW[l] += c * sl[q] / (2.0 * lam[l])
            dW[q] += c * sl[l] / (2.0 * lam[q])
        if mode == 0:
            return W, 1.0
        CV = modulus * V
        e = 2.0 * W / CV
        if e > max_q:
            return math.inf, math.inf
        s = math.exp(e)
        for a in range(6):
            dW[a] *= s
        return 0.5 * CV * (s - 1.0), s
    if mode == 2:
        C, b_f, b_t, b_fs = law[0], law[1], law[2], law[3]
        e0, e1, e2 = mm[0] - 1.0, mm[1] - 1.0, mm[2] - 1.0
        Q = (b_f * e0 * e0 + b_t * (e1 * e1 + e2 * e2)) / 4.0
        Q += (b_fs * (mm[3] * mm[3] + mm[4] * mm[4]) + b_t * mm[5] * mm[5]) / 2.0
        if Q > max_q:
            return math.inf, math.inf
        eQ = math.exp(Q)
        h = 0.5 * C * V * eQ
        dW[0], dW[1], dW[2] = h * b_f * e0 / 2.0, h * b_t * e1 / 2.0, h * b_t * e2 / 2.0
        dW[3], dW[4], dW[5] = h * b_fs * mm[3], h * b_fs * mm[4], h * b_t * mm[5]
        return h - 0.5 * C * V, eQ
    a, b, a_f, b_f, a_s, b_s, a_fs, b_fs = (
        law[0], law[1], law[2], law[3], law[4], law[5], law[6], law[7]
    )  # fmt: skip
    c0_, c1, c2, c01, c02, c12 = mm[0], mm[1], mm[2], mm[3], mm[4], mm[5]
    D = c0_ * c1 * c2 + 2 * c01 * c02 * c12 - c0_ * c12 * c12 - c1 * c02 * c02 - c2 * c01 * c01
    if not D > 0.0:
        return math.nan, math.nan
    r = D ** (-1.0 / 3.0)
    I1 = c0_ + c1 + c2
    q = b * (r * I1 - 3.0)
    if q > max_q:
        return math.inf, math.inf
    e = math.exp(q)
    W = a / (2.0 * b) * (e - 1.0)
    d1 = 0.5 * a * e
    t = I1 * r / (3.0 * D)
    dW[0] = d1 * (r - t * (c1 * c2 - c12 * c12))
    dW[1] = d1 * (r - t * (c0_ * c2 - c02 * c02))
    dW[2] = d1 * (r - t * (c0_ * c1 - c01 * c01))
    dW[3] = -d1 * t * 2.0 * (c02 * c12 - c2 * c01)
    dW[4] = -d1 * t * 2.0 * (c01 * c12 - c1 * c02)
    dW[5] = -d1 * t * 2.0 * (c01 * c02 - c0_ * c12)
    s = e
    if a_f != 0.0 and mm[0] - 1.0 > tension:
        psi, p1, eg = _exp_group(a_f, b_f, mm[0] - 1.0, max_q)
        W += psi
        dW[0] += p1
        s = max(s, eg)
    if a_s != 0.0 and mm[1] - 1.0 > tension:
        psi, p1, eg = _exp_group(a_s, b_s, mm[1] - 1.0, max_q)
        W += psi
        dW[1] += p1
        s = max(s, eg)
    if a_fs != 0.0:
        psi, p1, eg = _exp_group(a_fs, b_fs, mm[3], max_q)
        W += psi
        dW[3] += p1
        s = max(s, eg)
    for i in range(6):
        dW[i] *= V
    return V * W, s


@njit(cache=True, fastmath=False)
def tissue_pass(
    x, tets, G, l0, ka, kt, c0, kc, V0, b2, b3, mode, modulus, law, max_q, tension,
    W_out, s_out, f_out, forces
):  # fmt: skip  # pragma: no cover - compiled; checked against the numpy reference in tests
    """Energy and stiffening factor of every element into ``W_out``, ``s_out`` ``(m,)``;
    with ``forces``, add ``-dW/dx`` into ``f_out`` ``(n, 3)``.

    Parameters
    ----------
    x, tets, G, l0, ka, kt, c0, kc, V0
        Positions ``(n, 3)`` and the elements' rest data (connectivity, axis gradients
        ``(m, 4, 3)``, rest lengths, axial, torsion and coupling constants ``(m, 3)``, rest
        cosines (the Green torsions' rest values), rest volumes).
    b2, b3
        Polynomial axial coefficients.
    mode
        0 quadratic springs, 1 exponential stiffening, 2 Guccione, 3 Holzapfel–Ogden.
    modulus
        ``C`` of the exponential stiffening.
    law
        The law's eight parameters (:class:`springmodel.tissue_element.TissueLawParameters`).
    max_q, tension
        The largest exponent evaluated and the tension threshold of Holzapfel–Ogden's
        fibre and sheet terms.
    W_out, s_out, f_out
        Outputs (``f_out`` is added to).
    forces
        Whether to add the forces.

    Returns
    -------
    None
    """
    m = tets.shape[0]
    Z = np.empty((3, 3))
    gZ = np.empty((3, 3))
    mm = np.empty(6)
    dW = np.empty(6)
    sl = np.empty(3)
    lam = np.empty(3)
    for k in range(m):
        for l in range(3):
            for c in range(3):
                v = 0.0
                for i in range(4):
                    v += G[k, i, l] * x[tets[k, i], c]
                Z[l, c] = v / l0[k, l]
            mm[l] = Z[l, 0] * Z[l, 0] + Z[l, 1] * Z[l, 1] + Z[l, 2] * Z[l, 2]
        for p in range(3):
            l, q = TORSION_PAIRS[p]
            mm[3 + p] = Z[l, 0] * Z[q, 0] + Z[l, 1] * Z[q, 1] + Z[l, 2] * Z[q, 2]
        W, s = _measure_energy(
            mm, dW, sl, lam, k, l0, ka, kt, c0, kc, V0[k], b2, b3, mode, modulus, law, max_q,
            tension,
        )  # fmt: skip
        W_out[k] = W
        s_out[k] = s
        if not forces:
            continue
        if not math.isfinite(W):  # past max_q or inverted: forces not finite (Newton cuts back)
            for a in range(6):
                dW[a] = math.nan
        for l in range(3):
            for c in range(3):
                gZ[l, c] = 2.0 * dW[l] * Z[l, c]
        for p in range(3):
            l, q = TORSION_PAIRS[p]
            for c in range(3):
                gZ[l, c] += dW[3 + p] * Z[q, c]
                gZ[q, c] += dW[3 + p] * Z[l, c]
        for i in range(4):
            node = tets[k, i]
            for c in range(3):
                v = 0.0
                for l in range(3):
                    v += G[k, i, l] / l0[k, l] * gZ[l, c]
                f_out[node, c] -= v
