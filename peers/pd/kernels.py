"""The compiled local step of Projective Dynamics: per element, the projections of ``F`` onto
the rotations and onto the unit-determinant matrices (:mod:`.energy`), scattered as the
right-hand side ``b_a += V (2 mu R + 3 lam S) g_a`` of the global solve.

Examples
--------
>>> import numpy as np
>>> from ..xpbd.constraints import rest_shape
>>> X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> tets = np.array([[0, 1, 2, 3]])
>>> G, V = rest_shape(X, tets)
>>> b = np.zeros((4, 3))
>>> local_step(X * 1.1, tets, G, V, 1.0, 2.0, b)  # R = I and S = I for a uniform stretch
>>> bool(np.allclose(b.sum(axis=0), 0.0)), round(float(b[1, 0]), 12)  # (2 + 6) V g_1
(True, 1.333333333333)
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

_FLAGS: dict[str, Any] = {"cache": True, "error_model": "numpy", "fastmath": {"contract"}}


@njit(**_FLAGS)
def _phi(s, k, minus):  # pragma: no cover - compiled
    """``sum ln s'_i(k)`` and its derivative (``-inf`` where an ``s'_i`` is zero); the
    root of ``s'^2 - s s' - k`` with ``+ sqrt``, or ``- sqrt`` for index ``minus``."""
    phi = 0.0
    dphi = 0.0
    for i in range(3):
        root = np.sqrt(max(s[i] * s[i] + 4.0 * k, 0.0))
        sp = 0.5 * (s[i] - root) if i == minus else 0.5 * (s[i] + root)
        if not sp > 0.0:
            return -np.inf, np.inf
        phi += np.log(sp)
        dphi += (-1.0 if i == minus else 1.0) / (max(root, 1e-300) * sp)
    return phi, dphi


@njit(**_FLAGS)
def unit_determinant(s, out):  # pragma: no cover - compiled
    """``out = s'``: the nearest singular values with product one (:mod:`.energy`): ``k``
    by Newton inside a bracket (bisection where a step would leave it) on the ``+`` branch,
    or by bisection with the smallest ``|s|`` on the ``-`` branch when the ``+`` branch
    has no root (``s`` far from the unit-determinant set)."""
    m = 0
    for i in range(1, 3):
        if s[i] * s[i] < s[m] * s[m]:
            m = i
    lo = -0.25 * s[m] * s[m]
    minus = -1
    if _phi(s, lo, -1)[0] > 0.0:
        minus = m
        hi = 0.0
        for _ in range(200):  # phi decreases from > 0 at lo to -inf at 0
            k = 0.5 * (lo + hi)
            if _phi(s, k, m)[0] > 0.0:
                lo = k
            else:
                hi = k
            if hi - lo <= 1e-16 * max(abs(lo), 1e-300):
                break
        k = 0.5 * (lo + hi)
    else:
        phi, dphi = _phi(s, 0.0, -1)
        if phi > 0.0:
            hi, k = 0.0, 0.0
        else:
            lo, hi = 0.0, 1.0
            while _phi(s, hi, -1)[0] < 0.0:
                hi *= 4.0
            k = hi
            phi, dphi = _phi(s, k, -1)
        for _ in range(200):
            if phi > 0.0:
                hi = k
            else:
                lo = k
            k_new = k - phi / dphi if np.isfinite(phi) else 0.5 * (lo + hi)
            if not (lo < k_new < hi):
                k_new = 0.5 * (lo + hi)
            done = abs(k_new - k) <= 1e-15 * (1.0 + abs(k)) or hi - lo <= 1e-15 * (1.0 + abs(k))
            k = k_new
            if done:
                break
            phi, dphi = _phi(s, k, -1)
    for i in range(3):
        root = np.sqrt(max(s[i] * s[i] + 4.0 * k, 0.0))
        out[i] = 0.5 * (s[i] - root) if i == minus else 0.5 * (s[i] + root)


@njit(**_FLAGS)
def signed_svd3(F, U, s, Vt):  # pragma: no cover - compiled
    """``F = U diag(s) Vt`` with rotations ``U, Vt`` (the smallest ``s`` carries the sign of
    ``det F``): cyclic Jacobi on ``F^T F`` for ``V`` and the squared singular values, then
    ``u_i = F v_i / s_i`` for the two largest and ``u_3 = u_1 x u_2``; LAPACK's SVD when the
    two largest are not well separated from zero."""
    C = np.empty((3, 3))
    W = np.eye(3)
    for r in range(3):
        for d in range(3):
            C[r, d] = F[0, r] * F[0, d] + F[1, r] * F[1, d] + F[2, r] * F[2, d]
    scale = C[0, 0] + C[1, 1] + C[2, 2]
    for _ in range(12):
        off = C[0, 1] * C[0, 1] + C[0, 2] * C[0, 2] + C[1, 2] * C[1, 2]
        if off <= 1e-30 * scale * scale:
            break
        for p, q in ((0, 1), (0, 2), (1, 2)):
            if C[p, q] == 0.0:
                continue
            theta = (C[q, q] - C[p, p]) / (2.0 * C[p, q])
            t = (1.0 if theta >= 0 else -1.0) / (abs(theta) + np.sqrt(theta * theta + 1.0))
            c = 1.0 / np.sqrt(t * t + 1.0)
            sn = t * c
            for k in range(3):  # C <- J^T C J, W <- W J
                ckp, ckq = C[k, p], C[k, q]
                C[k, p] = c * ckp - sn * ckq
                C[k, q] = sn * ckp + c * ckq
            for k in range(3):
                cpk, cqk = C[p, k], C[q, k]
                C[p, k] = c * cpk - sn * cqk
                C[q, k] = sn * cpk + c * cqk
            for k in range(3):
                wkp, wkq = W[k, p], W[k, q]
                W[k, p] = c * wkp - sn * wkq
                W[k, q] = sn * wkp + c * wkq
    lam0, lam1, lam2 = C[0, 0], C[1, 1], C[2, 2]
    i0, i1, i2 = 0, 1, 2  # descending order
    if lam0 < lam1:
        i0, i1 = i1, i0
    if C[i1, i1] < lam2:
        i1, i2 = i2, i1
    if C[i0, i0] < C[i1, i1]:
        i0, i1 = i1, i0
    s0 = np.sqrt(max(C[i0, i0], 0.0))
    s1 = np.sqrt(max(C[i1, i1], 0.0))
    if not s1 > 1e-8 * max(s0, 1e-300):
        U2, s2, Vt2 = np.linalg.svd(F)
        dU, dV = np.linalg.det(U2), np.linalg.det(Vt2)
        for r in range(3):
            for d in range(3):
                U[r, d] = U2[r, d] * (dU if d == 2 else 1.0)
                Vt[r, d] = Vt2[r, d] * (dV if r == 2 else 1.0)
            s[r] = s2[r]
        s[2] *= dU * dV
        return
    for r in range(3):
        Vt[0, r] = W[r, i0]
        Vt[1, r] = W[r, i1]
    Vt[2, 0] = Vt[0, 1] * Vt[1, 2] - Vt[0, 2] * Vt[1, 1]
    Vt[2, 1] = Vt[0, 2] * Vt[1, 0] - Vt[0, 0] * Vt[1, 2]
    Vt[2, 2] = Vt[0, 0] * Vt[1, 1] - Vt[0, 1] * Vt[1, 0]
    for r in range(3):
        U[r, 0] = (F[r, 0] * Vt[0, 0] + F[r, 1] * Vt[0, 1] + F[r, 2] * Vt[0, 2]) / s0
        U[r, 1] = F[r, 0] * Vt[1, 0] + F[r, 1] * Vt[1, 1] + F[r, 2] * Vt[1, 2]
    dot = U[0, 0] * U[0, 1] + U[1, 0] * U[1, 1] + U[2, 0] * U[2, 1]
    for r in range(3):
        U[r, 1] -= dot * U[r, 0]
    nrm = np.sqrt(U[0, 1] * U[0, 1] + U[1, 1] * U[1, 1] + U[2, 1] * U[2, 1])
    for r in range(3):
        U[r, 1] /= nrm
    U[0, 2] = U[1, 0] * U[2, 1] - U[2, 0] * U[1, 1]
    U[1, 2] = U[2, 0] * U[0, 1] - U[0, 0] * U[2, 1]
    U[2, 2] = U[0, 0] * U[1, 1] - U[1, 0] * U[0, 1]
    s[0] = s0
    s[1] = s1
    acc = 0.0
    for r in range(3):
        acc += U[r, 2] * (F[r, 0] * Vt[2, 0] + F[r, 1] * Vt[2, 1] + F[r, 2] * Vt[2, 2])
    s[2] = acc


@njit(**_FLAGS)
def local_step(x, tets, G, V, mu, lam, b):  # pragma: no cover - compiled
    """Add every element's ``V (2 mu R + 3 lam S) g_a`` to ``b`` ``(n, 3)`` (not zeroed here)."""
    F = np.empty((3, 3))
    P = np.empty((3, 3))
    U = np.empty((3, 3))
    Vt = np.empty((3, 3))
    s = np.empty(3)
    sp = np.empty(3)
    for k in range(tets.shape[0]):
        i0 = tets[k, 0]
        for r in range(3):
            for d in range(3):
                F[r, d] = (
                    (x[tets[k, 1], r] - x[i0, r]) * G[k, 0, d]
                    + (x[tets[k, 2], r] - x[i0, r]) * G[k, 1, d]
                    + (x[tets[k, 3], r] - x[i0, r]) * G[k, 2, d]
                )
        signed_svd3(F, U, s, Vt)
        unit_determinant(s, sp)
        for r in range(3):
            for d in range(3):
                acc = 0.0
                for j in range(3):
                    acc += U[r, j] * (2.0 * mu + 3.0 * lam * sp[j]) * Vt[j, d]
                P[r, d] = V[k] * acc
        for a in range(3):
            node = tets[k, a + 1]
            for r in range(3):
                t = P[r, 0] * G[k, a, 0] + P[r, 1] * G[k, a, 1] + P[r, 2] * G[k, a, 2]
                b[node, r] += t
                b[i0, r] -= t


@njit(**_FLAGS)
def neo_hookean(x, tets, G, V, mu, lam, grad, want_grad):  # pragma: no cover - compiled
    """The coupled neo-Hookean strain energy ``sum_e V_e psi(F_e)`` (``inf`` as soon as an
    element has ``J <= 0``); with ``want_grad`` its gradient ``V P g_a`` is added to
    ``grad`` ``(n, 3)``, ``P = mu (F - F^-T) + lam ln J F^-T`` (:mod:`.energy`)."""
    F = np.empty((3, 3))
    C = np.empty((3, 3))
    total = 0.0
    for k in range(tets.shape[0]):
        i0 = tets[k, 0]
        for r in range(3):
            for d in range(3):
                F[r, d] = (
                    (x[tets[k, 1], r] - x[i0, r]) * G[k, 0, d]
                    + (x[tets[k, 2], r] - x[i0, r]) * G[k, 1, d]
                    + (x[tets[k, 3], r] - x[i0, r]) * G[k, 2, d]
                )
        for j in range(3):  # cof F = J F^-T, column j = f_(j+1) x f_(j+2)
            j1, j2 = (j + 1) % 3, (j + 2) % 3
            C[0, j] = F[1, j1] * F[2, j2] - F[2, j1] * F[1, j2]
            C[1, j] = F[2, j1] * F[0, j2] - F[0, j1] * F[2, j2]
            C[2, j] = F[0, j1] * F[1, j2] - F[1, j1] * F[0, j2]
        J = F[0, 0] * C[0, 0] + F[1, 0] * C[1, 0] + F[2, 0] * C[2, 0]
        if not J > 0.0:
            return np.inf
        lnJ = np.log(J)
        ic = 0.0
        for r in range(3):
            for d in range(3):
                ic += F[r, d] * F[r, d]
        total += V[k] * (0.5 * mu * (ic - 3.0) - mu * lnJ + 0.5 * lam * lnJ * lnJ)
        if want_grad:
            c = (lam * lnJ - mu) / J
            for a in range(3):
                node = tets[k, a + 1]
                for r in range(3):
                    t = 0.0
                    for d in range(3):
                        t += (mu * F[r, d] + c * C[r, d]) * G[k, a, d]
                    t *= V[k]
                    grad[node, r] += t
                    grad[i0, r] -= t
    return total
