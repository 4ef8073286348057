"""Element Hessians of the conservative spring energies, compiled (numba, parallel).

One pass per element: the 9x9 Hessian in the axis vectors (axial, energy or shear torsion
(``torsion`` code 0 off, 1 energy, 2 shear), Poisson
coupling, axis volume), mapped to the 12 vertex DOFs with ``G``, plus the barycentric volume
spring on the vertices. Formulas in :mod:`springmodel.hessian`; checked against the numpy
reference (:mod:`springmodel.hessian_numpy`) in the tests.

``_element_matrices_numba`` runs over the elements on all threads,
``_element_matrices_serial`` on one; both call the same per-element function, so they give
identical bits. :class:`springmodel.hessian.SpringHessian` picks by size, with the force
kernels' rule. The compiled functions have no public API of their own: their examples are
:class:`~springmodel.hessian.SpringHessian`'s, and the tests check them against the numpy
reference (:mod:`springmodel.hessian_numpy`).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .shear_numba import shear_terms


@njit(cache=True, parallel=True, fastmath=False)
def _element_matrices_numba(
    x, tets, G, l0, ka, kt, c0, kv, L0, b2, b3, torsion, volume, pair_l, pair_m,
    coupling, axes, kc, kjv, idet, out
):  # fmt: skip  # pragma: no cover - compiled; checked against the numpy reference in the tests
    for k in prange(tets.shape[0]):
        _element_matrix(
            k, x, tets, G, l0, ka, kt, c0, kv, L0, b2, b3, torsion, volume, pair_l, pair_m,
            coupling, axes, kc, kjv, idet, out,
        )  # fmt: skip


@njit(cache=True, fastmath=False)
def _element_matrices_serial(
    x, tets, G, l0, ka, kt, c0, kv, L0, b2, b3, torsion, volume, pair_l, pair_m,
    coupling, axes, kc, kjv, idet, out
):  # fmt: skip  # pragma: no cover - compiled; checked against the numpy reference in the tests
    for k in range(tets.shape[0]):
        _element_matrix(
            k, x, tets, G, l0, ka, kt, c0, kv, L0, b2, b3, torsion, volume, pair_l, pair_m,
            coupling, axes, kc, kjv, idet, out,
        )  # fmt: skip


@njit(cache=True, fastmath=False)
def _element_matrix(
    k, x, tets, G, l0, ka, kt, c0, kv, L0, b2, b3, torsion, volume, pair_l, pair_m,
    coupling, axes, kc, kjv, idet, out
):  # fmt: skip  # pragma: no cover - compiled; checked against the numpy reference in the tests
    X = np.empty((4, 3))
    for i in range(4):
        for c in range(3):
            X[i, c] = x[tets[k, i], c]
    U = np.zeros((3, 3))
    Ls = np.empty(3)
    H = np.zeros((9, 9))
    # axial: f'' uu^T + f'/L (I - uu^T), eqs. 2.35-2.36
    for l in range(3):
        for c in range(3):
            z = 0.0
            for i in range(4):
                z += G[k, i, l] * X[i, c]
            U[l, c] = z
        L = np.sqrt(U[l, 0] ** 2 + U[l, 1] ** 2 + U[l, 2] ** 2)
        Ls[l] = L
        for c in range(3):
            U[l, c] /= L
        r = (L - l0[k, l]) / l0[k, l]
        f1 = ka[k, l] * (L - l0[k, l]) * (1.0 + b2 * r + b3 * r * r)
        f2 = ka[k, l] * (1.0 + 2.0 * b2 * r + 3.0 * b3 * r * r)
        s = f1 / L
        for a in range(3):
            for b in range(3):
                v = (f2 - s) * U[l, a] * U[l, b]
                if a == b:
                    v += s
                H[3 * l + a, 3 * l + b] += v
    # torsion, U = k phi(c): k (phi'' grad c grad c^T + phi' grad^2 c); code 1 energy
    # (phi' = c - c0, phi'' = 1), 2 shear (springmodel.springs.shear)
    if torsion:
        ga = np.empty(3)
        gb = np.empty(3)
        for p in range(3):
            l = pair_l[p]
            q = pair_m[p]
            A = Ls[l]
            B = Ls[q]
            c = U[l, 0] * U[q, 0] + U[l, 1] * U[q, 1] + U[l, 2] * U[q, 2]
            if torsion == 2:
                delta, e1, e2 = shear_terms(c, c0[k, p])
                dc = delta * e1
                d2 = e1 * e1 + delta * e2
            else:
                dc = c - c0[k, p]
                d2 = 1.0
            kk = kt[k, p]
            kg = kk * d2
            for a in range(3):
                ga[a] = (U[q, a] - c * U[l, a]) / A
                gb[a] = (U[l, a] - c * U[q, a]) / B
            for a in range(3):
                for b in range(3):
                    dab = 1.0 if a == b else 0.0
                    pa = dab - U[l, a] * U[l, b]
                    pb = dab - U[q, a] * U[q, b]
                    haa = -(U[l, a] * ga[b] + ga[a] * U[l, b]) / A - c * pa / (A * A)
                    hbb = -(U[q, a] * gb[b] + gb[a] * U[q, b]) / B - c * pb / (B * B)
                    hab = (pa - U[q, a] * U[q, b] + c * U[l, a] * U[q, b]) / (A * B)
                    H[3 * l + a, 3 * l + b] += kg * ga[a] * ga[b] + kk * dc * haa
                    H[3 * q + a, 3 * q + b] += kg * gb[a] * gb[b] + kk * dc * hbb
                    v = kg * ga[a] * gb[b] + kk * dc * hab
                    H[3 * l + a, 3 * q + b] += v
                    H[3 * q + b, 3 * l + a] += v
    # Poisson coupling c s_l s_m
    if coupling:
        for p in range(3):
            l = pair_l[p]
            q = pair_m[p]
            c = kc[k, p]
            sl = Ls[l] / l0[k, l] - 1.0
            sq = Ls[q] / l0[k, q] - 1.0
            dl = c * sq / (l0[k, l] * Ls[l])
            dq = c * sl / (l0[k, q] * Ls[q])
            cr = c / (l0[k, l] * l0[k, q])
            for a in range(3):
                for b in range(3):
                    dab = 1.0 if a == b else 0.0
                    H[3 * l + a, 3 * l + b] += dl * (dab - U[l, a] * U[l, b])
                    H[3 * q + a, 3 * q + b] += dq * (dab - U[q, a] * U[q, b])
                    H[3 * l + a, 3 * q + b] += cr * U[l, a] * U[q, b]
                    H[3 * q + b, 3 * l + a] += cr * U[l, a] * U[q, b]
    # axis volume V0 U(J): V0 (U'' gJ gJ^T + U' d^2J), codes 3/4/5 = quadratic/log/simo
    if axes:
        Z = np.empty((3, 3))
        for l in range(3):
            for c in range(3):
                Z[l, c] = U[l, c] * Ls[l]
        gJ = np.empty((3, 3))
        for l in range(3):
            m1 = (l + 1) % 3
            m2 = (l + 2) % 3
            gJ[l, 0] = (Z[m1, 1] * Z[m2, 2] - Z[m1, 2] * Z[m2, 1]) * idet[k]
            gJ[l, 1] = (Z[m1, 2] * Z[m2, 0] - Z[m1, 0] * Z[m2, 2]) * idet[k]
            gJ[l, 2] = (Z[m1, 0] * Z[m2, 1] - Z[m1, 1] * Z[m2, 0]) * idet[k]
        J = Z[0, 0] * gJ[0, 0] + Z[0, 1] * gJ[0, 1] + Z[0, 2] * gJ[0, 2]
        if axes == 3:
            dU = J - 1.0
            d2U = 1.0
        elif axes == 4:
            dU = np.log(J) / J
            d2U = (1.0 - np.log(J)) / (J * J)
        else:
            dU = 0.5 * (J - 1.0 / J)
            d2U = 0.5 * (1.0 + 1.0 / (J * J))
        dU *= kjv[k]
        d2U *= kjv[k]
        for l in range(3):
            for a in range(3):
                for q in range(3):
                    for b in range(3):
                        H[3 * l + a, 3 * q + b] += d2U * gJ[l, a] * gJ[q, b]
        for l in range(3):
            q = (l + 1) % 3
            n = (l + 2) % 3
            s = dU * idet[k]
            # E[a, b] = eps_abc z_c on (l, q), its transpose on (q, l)
            for a in range(3):
                for b in range(3):
                    e = 0.0
                    if (a + 1) % 3 == b:
                        e = Z[n, (b + 1) % 3]
                    elif (b + 1) % 3 == a:
                        e = -Z[n, (a + 1) % 3]
                    H[3 * l + a, 3 * q + b] += s * e
                    H[3 * q + b, 3 * l + a] += s * e
    # K[3i+a, 3j+b] = sum_{l,q} G[i,l] H[3l+a, 3q+b] G[j,q]
    T = np.zeros((12, 9))
    for i in range(4):
        for a in range(3):
            for col in range(9):
                t = 0.0
                for l in range(3):
                    t += G[k, i, l] * H[3 * l + a, col]
                T[3 * i + a, col] = t
    K = out[k]
    for row in range(12):
        for j in range(4):
            for b in range(3):
                t = 0.0
                for q in range(3):
                    t += T[row, 3 * q + b] * G[k, j, q]
                K[row, 3 * j + b] = t
    # volume (gradient form): k_s (grad L grad L^T + dL grad^2 L)
    if volume:
        xb = np.zeros(3)
        for i in range(4):
            for c in range(3):
                xb[c] += 0.25 * X[i, c]
        xh = np.empty((4, 3))
        rr = np.empty(4)
        dL = -L0[k]
        for i in range(4):
            for c in range(3):
                xh[i, c] = X[i, c] - xb[c]
            rr[i] = np.sqrt(xh[i, 0] ** 2 + xh[i, 1] ** 2 + xh[i, 2] ** 2)
            dL += rr[i]
            for c in range(3):
                xh[i, c] /= rr[i]
        gL = np.empty((4, 3))
        for c in range(3):
            mean = 0.25 * (xh[0, c] + xh[1, c] + xh[2, c] + xh[3, c])
            for i in range(4):
                gL[i, c] = xh[i, c] - mean
        Hr = np.empty((4, 3, 3))
        S = np.zeros((3, 3))
        for i in range(4):
            for a in range(3):
                for b in range(3):
                    v = -xh[i, a] * xh[i, b]
                    if a == b:
                        v += 1.0
                    Hr[i, a, b] = v / rr[i]
                    S[a, b] += Hr[i, a, b] / 16.0
        ks = kv[k]
        for i in range(4):
            for j in range(4):
                for a in range(3):
                    for b in range(3):
                        h2 = S[a, b] - 0.25 * (Hr[i, a, b] + Hr[j, a, b])
                        if i == j:
                            h2 += Hr[i, a, b]
                        K[3 * i + a, 3 * j + b] += ks * (gL[i, a] * gL[j, b] + dL * h2)
    for row in range(12):
        for col in range(row + 1, 12):
            v = 0.5 * (K[row, col] + K[col, row])
            K[row, col] = v
            K[col, row] = v


@njit(cache=True, fastmath=False)
def _scatter_add(data, index_map, Ke):  # pragma: no cover - compiled; checked in the tests
    """``data[index_map[k, e]] += Ke[k].flat[e]``: element matrices summed into CSR data.

    Serial (the sums collide across elements) and in element order, so the result is
    deterministic; one pass over the element matrices, no temporaries.
    """
    m = Ke.shape[0]
    for k in range(m):
        K = Ke[k]
        row = index_map[k]
        e = 0
        for r in range(12):
            for c in range(12):
                data[row[e]] += K[r, c]
                e += 1
