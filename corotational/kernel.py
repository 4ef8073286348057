"""The co-rotational P1 force kernel (compiled) and its numpy twin.

Per element, with the shape gradients ``g_a = grad N_a`` at rest and volume ``V``::

    F = sum_a (x_a - x_0) (x) g_a                      (a = 1..3)
    R = rotation(F)                                    (corotational.polar)
    eps = sym(R^T F) - I,  sigma = C : eps             (C in the global frame)
    f_a = -V R sigma g_a,  f_0 = -(f_1 + f_2 + f_3)

which is ``f_e = -R_e K_e (R_e^T x_e - X_e)`` with ``K_e`` the linear P1 element stiffness
and ``R_e`` the block-diagonal element rotation (docs/plugins.rst#co-rotational-p1). ``C``
is the isotropic ``(mu, lam)`` or one Voigt matrix per element (``(xx, yy, zz, yz, xz,
xy)``, engineering shears: a transversely isotropic law rotated into the element frames).

Examples
--------
>>> import numpy as np
>>> X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> G, V = shape_gradients(X, np.array([[0, 1, 2, 3]]))
>>> Q = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])
>>> f = forces_numpy(X @ Q.T, np.array([[0, 1, 2, 3]]), G, V, isotropic_d(1.0, 1.0))
>>> bool(abs(f).max() < 1e-14)  # a rigid rotation: no force
True
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from .polar import polar_rotation, rotations

_FLAGS: dict[str, Any] = {"cache": True, "error_model": "numpy", "fastmath": {"contract"}}


def shape_gradients(points: np.ndarray, tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``grad N_1..3`` per element ``(m, 3, 3)`` (row ``a - 1``: ``grad N_a``) and volumes.

    Parameters
    ----------
    points, tets
        The mesh at rest.

    Returns
    -------
    G, V
        ``(m, 3, 3)`` and ``(m,)``.
    """
    x = np.asarray(points, dtype=float)[tets]
    E = x[:, 1:] - x[:, :1]  # rows: x_a - x_0
    # F = E^T G with G rows g_a: at rest F = I, so G = E^-T
    G = np.linalg.inv(E).transpose(0, 2, 1)
    return np.ascontiguousarray(G), np.linalg.det(E) / 6.0


def isotropic_d(mu: float, lam: float) -> np.ndarray:
    """The isotropic Voigt matrix ``(1, 6, 6)`` (engineering shears) of ``mu, lam``.

    Parameters
    ----------
    mu, lam
        Lamé constants.

    Returns
    -------
    ndarray
    """
    D = np.zeros((6, 6))
    D[:3, :3] = lam
    D[range(3), range(3)] += 2 * mu
    D[range(3, 6), range(3, 6)] = mu
    return D[None]


#: Voigt index pairs ``(xx, yy, zz, yz, xz, xy)``.
VOIGT = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))


def gradients(x: np.ndarray, tets: np.ndarray, G: np.ndarray) -> np.ndarray:
    """Deformation gradients ``F (m, 3, 3)`` of positions ``x``.

    Parameters
    ----------
    x, tets
        Positions ``(n, 3)`` and elements.
    G
        :func:`shape_gradients`.

    Returns
    -------
    ndarray
    """
    X = np.asarray(x, dtype=float).reshape(-1, 3)[tets]
    return np.einsum("kac,kad->kcd", X[:, 1:] - X[:, :1], G)


def stress(eps: np.ndarray, D: np.ndarray) -> np.ndarray:
    """``sigma = C : eps`` per element for strains ``(m, 3, 3)``, ``D`` ``(1|m, 6, 6)``."""
    e = np.stack([eps[:, i, j] * (1 if i == j else 2) for i, j in VOIGT], axis=1)
    s = np.einsum("kij,kj->ki", np.broadcast_to(D, (eps.shape[0], 6, 6)), e)
    out = np.empty_like(eps)
    for c, (i, j) in enumerate(VOIGT):
        out[:, i, j] = out[:, j, i] = s[:, c]
    return out


def forces_numpy(
    x: np.ndarray, tets: np.ndarray, G: np.ndarray, V: np.ndarray, D: np.ndarray
) -> np.ndarray:
    """Internal nodal forces ``(n, 3)`` in numpy (the kernel's oracle).

    Parameters
    ----------
    x, tets
        Positions and elements.
    G, V
        :func:`shape_gradients` at rest.
    D
        Voigt matrices ``(1, 6, 6)`` (all elements) or ``(m, 6, 6)``.

    Returns
    -------
    ndarray
    """
    x = np.asarray(x, dtype=float).reshape(-1, 3)
    F = gradients(x, tets, G)
    R = rotations(F)
    S = np.einsum("kji,kjl->kil", R, F)
    eps = 0.5 * (S + S.transpose(0, 2, 1)) - np.eye(3)
    P = np.einsum("kij,kjl->kil", R, stress(eps, D))
    fa = -V[:, None, None] * np.einsum("kil,kal->kai", P, G)  # (m, 3 nodes, 3)
    f = np.zeros_like(x)
    np.add.at(f, tets[:, 1:], fa)
    np.add.at(f, tets[:, 0], -fa.sum(axis=1))
    return f


@njit(**_FLAGS)
def force_kernel(x, tets, G, V, D, per_element, out):  # pragma: no cover - compiled
    """Overwrite ``out (n, 3)`` with the internal forces; return the number of elements
    with ``det F <= 0`` (they get the inverted-element force of the signed rotation).

    ``D`` is ``(1, 6, 6)`` (``per_element`` false) or ``(m, 6, 6)``.
    """
    out[:, :] = 0.0
    F = np.empty((3, 3))
    R = np.empty((3, 3))
    S = np.empty((3, 3))
    sv = np.empty(6)
    sig = np.empty((3, 3))
    W = np.empty((4, 3, 3))
    bad = 0
    for k in range(tets.shape[0]):
        i0 = tets[k, 0]
        for r in range(3):
            for c in range(3):
                s = 0.0
                for a in range(3):
                    s += (x[tets[k, a + 1], r] - x[i0, r]) * G[k, a, c]
                F[r, c] = s
        det = (
            F[0, 0] * (F[1, 1] * F[2, 2] - F[1, 2] * F[2, 1])
            - F[0, 1] * (F[1, 0] * F[2, 2] - F[1, 2] * F[2, 0])
            + F[0, 2] * (F[1, 0] * F[2, 1] - F[1, 1] * F[2, 0])
        )
        if det <= 0.0:
            bad += 1
        polar_rotation(F, R, W)
        # S = R^T F, eps = sym(S) - I in Voigt (engineering shears)
        for i in range(3):
            for j in range(3):
                S[i, j] = R[0, i] * F[0, j] + R[1, i] * F[1, j] + R[2, i] * F[2, j]
        e0, e1, e2 = S[0, 0] - 1.0, S[1, 1] - 1.0, S[2, 2] - 1.0
        e3, e4, e5 = S[1, 2] + S[2, 1], S[0, 2] + S[2, 0], S[0, 1] + S[1, 0]
        d = k if per_element else 0
        for i in range(6):
            sv[i] = (
                D[d, i, 0] * e0 + D[d, i, 1] * e1 + D[d, i, 2] * e2
                + D[d, i, 3] * e3 + D[d, i, 4] * e4 + D[d, i, 5] * e5
            )  # fmt: skip
        sig[0, 0], sig[1, 1], sig[2, 2] = sv[0], sv[1], sv[2]
        sig[1, 2] = sig[2, 1] = sv[3]
        sig[0, 2] = sig[2, 0] = sv[4]
        sig[0, 1] = sig[1, 0] = sv[5]
        v = V[k]
        for i in range(3):  # P = R sigma, f_a = -V P g_a
            p0 = R[i, 0] * sig[0, 0] + R[i, 1] * sig[1, 0] + R[i, 2] * sig[2, 0]
            p1 = R[i, 0] * sig[0, 1] + R[i, 1] * sig[1, 1] + R[i, 2] * sig[2, 1]
            p2 = R[i, 0] * sig[0, 2] + R[i, 1] * sig[1, 2] + R[i, 2] * sig[2, 2]
            total = 0.0
            for a in range(3):
                fa = -v * (p0 * G[k, a, 0] + p1 * G[k, a, 1] + p2 * G[k, a, 2])
                out[tets[k, a + 1], i] += fa
                total += fa
            out[i0, i] -= total
    return bad


@njit(**_FLAGS)
def tangent_kernel(x, tets, G, V, D, per_element, warped, Ke):  # pragma: no cover - compiled
    """Element tangents ``-d f_e / d x_e`` into ``Ke (m, 12, 12)`` (DOF ``3 node + comp``):
    the consistent tangent, or with ``warped`` the warped stiffness ``R K_e R^T``
    (:mod:`corotational.system` gives the formulas; its numpy form is the oracle)."""
    F = np.empty((3, 3))
    R = np.empty((3, 3))
    S = np.empty((3, 3))
    W = np.empty((4, 3, 3))
    sig = np.empty((3, 3))
    g = np.empty((4, 3))
    A = np.empty((3, 3))
    Hi = np.empty((3, 3))
    Wk = np.empty((3, 3))
    dS = np.empty((3, 3))
    ds = np.empty((3, 3))
    M = np.empty((3, 3))
    dP = np.empty((3, 3))
    e = np.empty(6)
    sv = np.empty(6)
    for k in range(tets.shape[0]):
        i0 = tets[k, 0]
        for r in range(3):
            for c in range(3):
                s = 0.0
                for a in range(3):
                    s += (x[tets[k, a + 1], r] - x[i0, r]) * G[k, a, c]
                F[r, c] = s
        for c in range(3):
            g[0, c] = -(G[k, 0, c] + G[k, 1, c] + G[k, 2, c])
            for a in range(3):
                g[a + 1, c] = G[k, a, c]
        polar_rotation(F, R, W)
        for i in range(3):
            for j in range(3):
                S[i, j] = R[0, i] * F[0, j] + R[1, i] * F[1, j] + R[2, i] * F[2, j]
        d = k if per_element else 0
        # sigma = C : (sym S - I)
        e[0], e[1], e[2] = S[0, 0] - 1.0, S[1, 1] - 1.0, S[2, 2] - 1.0
        e[3], e[4], e[5] = S[1, 2] + S[2, 1], S[0, 2] + S[2, 0], S[0, 1] + S[1, 0]
        for i in range(6):
            t = 0.0
            for j in range(6):
                t += D[d, i, j] * e[j]
            sv[i] = t
        sig[0, 0], sig[1, 1], sig[2, 2] = sv[0], sv[1], sv[2]
        sig[1, 2] = sig[2, 1] = sv[3]
        sig[0, 2] = sig[2, 0] = sv[4]
        sig[0, 1] = sig[1, 0] = sv[5]
        # H = tr S I - S and its inverse (zero where singular: no rotation derivative)
        tr = S[0, 0] + S[1, 1] + S[2, 2]
        h00, h11, h22 = tr - S[0, 0], tr - S[1, 1], tr - S[2, 2]
        h01, h02, h12 = (
            -0.5 * (S[0, 1] + S[1, 0]),
            -0.5 * (S[0, 2] + S[2, 0]),
            -0.5 * (S[1, 2] + S[2, 1]),
        )
        c00 = h11 * h22 - h12 * h12
        c01 = h02 * h12 - h01 * h22
        c02 = h01 * h12 - h02 * h11
        det = h00 * c00 + h01 * c01 + h02 * c02
        use_w = (not warped) and abs(det) > 1e-12 * abs(tr) ** 3
        if use_w:
            Hi[0, 0], Hi[0, 1], Hi[0, 2] = c00 / det, c01 / det, c02 / det
            Hi[1, 1] = (h00 * h22 - h02 * h02) / det
            Hi[1, 2] = (h01 * h02 - h00 * h12) / det
            Hi[2, 2] = (h00 * h11 - h01 * h01) / det
            Hi[1, 0], Hi[2, 0], Hi[2, 1] = Hi[0, 1], Hi[0, 2], Hi[1, 2]
        v = V[k]
        for a in range(4):
            for dd in range(3):
                for i in range(3):  # A = R^T (e_dd (x) g_a) = R[dd] (x) g_a
                    for j in range(3):
                        A[i, j] = R[dd, i] * g[a, j]
                if use_w:
                    r0 = A[2, 1] - A[1, 2]
                    r1 = A[0, 2] - A[2, 0]
                    r2 = A[1, 0] - A[0, 1]
                    w0 = Hi[0, 0] * r0 + Hi[0, 1] * r1 + Hi[0, 2] * r2
                    w1 = Hi[1, 0] * r0 + Hi[1, 1] * r1 + Hi[1, 2] * r2
                    w2 = Hi[2, 0] * r0 + Hi[2, 1] * r1 + Hi[2, 2] * r2
                else:
                    w0 = w1 = w2 = 0.0
                Wk[0, 0], Wk[0, 1], Wk[0, 2] = 0.0, -w2, w1
                Wk[1, 0], Wk[1, 1], Wk[1, 2] = w2, 0.0, -w0
                Wk[2, 0], Wk[2, 1], Wk[2, 2] = -w1, w0, 0.0
                for i in range(3):
                    for j in range(3):
                        dS[i, j] = A[i, j] - (
                            Wk[i, 0] * S[0, j] + Wk[i, 1] * S[1, j] + Wk[i, 2] * S[2, j]
                        )
                e[0], e[1], e[2] = dS[0, 0], dS[1, 1], dS[2, 2]
                e[3], e[4], e[5] = dS[1, 2] + dS[2, 1], dS[0, 2] + dS[2, 0], dS[0, 1] + dS[1, 0]
                for i in range(6):
                    t = 0.0
                    for j in range(6):
                        t += D[d, i, j] * e[j]
                    sv[i] = t
                ds[0, 0], ds[1, 1], ds[2, 2] = sv[0], sv[1], sv[2]
                ds[1, 2] = ds[2, 1] = sv[3]
                ds[0, 2] = ds[2, 0] = sv[4]
                ds[0, 1] = ds[1, 0] = sv[5]
                for i in range(3):  # M = W sigma + d sigma, dP = R M
                    for j in range(3):
                        M[i, j] = (
                            Wk[i, 0] * sig[0, j] + Wk[i, 1] * sig[1, j] + Wk[i, 2] * sig[2, j]
                        ) + ds[i, j]
                for i in range(3):
                    for j in range(3):
                        dP[i, j] = R[i, 0] * M[0, j] + R[i, 1] * M[1, j] + R[i, 2] * M[2, j]
                col = 3 * a + dd
                for b in range(4):
                    for i in range(3):
                        Ke[k, 3 * b + i, col] = v * (
                            dP[i, 0] * g[b, 0] + dP[i, 1] * g[b, 1] + dP[i, 2] * g[b, 2]
                        )
