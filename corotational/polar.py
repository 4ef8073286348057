"""The rotation of a deformation gradient, stable for flat and inverted elements.

``F = U_s Sigma V^T`` (singular value decomposition) with ``U_s``, ``V`` rotations and the
smallest singular value negative when ``det F < 0``: Irving, Teran & Fedkiw 2004,
"Invertible finite elements for robust simulation of large deformation" (SCA). The element
rotation is ``R = U_s V^T``; for ``det F > 0`` it is the rotation of the polar decomposition
``F = R S`` (``S`` symmetric positive definite); for an inverted element ``S = R^T F`` is
symmetric with one negative eigenvalue, and ``R`` is still a rotation (``det R = +1``).

How: the eigenvectors ``v_i`` of ``C = F^T F`` by cyclic Jacobi rotations (``V`` made a
rotation), sorted by decreasing eigenvalue; ``u_1 = F v_1 / |F v_1|``, ``u_2`` the part of
``F v_2`` orthogonal to ``u_1`` (any unit vector orthogonal to it when ``F`` has rank one),
``u_3 = u_1 x u_2`` (so ``U_s`` is a rotation whatever the sign of ``det F``: the sign fix
goes to the smallest singular value), ``R = sum_i u_i v_i^T``. A rigid rotation ``F = Q``
gives ``C = I`` and ``R = Q`` to round-off, whatever basis Jacobi returns.

Examples
--------
>>> import numpy as np
>>> Q = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])
>>> R = rotation(Q @ np.diag([1.2, 0.9, 1.0]))
>>> bool(np.allclose(R, Q))
True
>>> R = rotation(np.diag([1.0, 1.0, -0.5]))  # inverted: still a rotation
>>> round(float(np.linalg.det(R)), 12), bool(np.allclose(R.T @ np.diag([1, 1, -0.5]),
...                                                      (R.T @ np.diag([1, 1, -0.5])).T))
(1.0, True)
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

_FLAGS: dict[str, Any] = {"cache": True, "error_model": "numpy"}
#: Jacobi sweeps at most (each sweep three rotations; 4-5 reach round-off from any F).
SWEEPS = 20


@njit(**_FLAGS)
def polar_rotation(F: np.ndarray, R: np.ndarray, W: np.ndarray) -> None:  # pragma: no cover
    """Write the rotation of the 3x3 ``F`` into ``R`` (see the module docstring); ``W`` is
    a ``(4, 3, 3)`` scratch array."""
    # C = F^T F, symmetric
    c00 = F[0, 0] * F[0, 0] + F[1, 0] * F[1, 0] + F[2, 0] * F[2, 0]
    c11 = F[0, 1] * F[0, 1] + F[1, 1] * F[1, 1] + F[2, 1] * F[2, 1]
    c22 = F[0, 2] * F[0, 2] + F[1, 2] * F[1, 2] + F[2, 2] * F[2, 2]
    c01 = F[0, 0] * F[0, 1] + F[1, 0] * F[1, 1] + F[2, 0] * F[2, 1]
    c02 = F[0, 0] * F[0, 2] + F[1, 0] * F[1, 2] + F[2, 0] * F[2, 2]
    c12 = F[0, 1] * F[0, 2] + F[1, 1] * F[1, 2] + F[2, 1] * F[2, 2]
    C = W[0]
    C[0, 0], C[1, 1], C[2, 2] = c00, c11, c22
    C[0, 1] = C[1, 0] = c01
    C[0, 2] = C[2, 0] = c02
    C[1, 2] = C[2, 1] = c12
    V = W[1]
    for i in range(3):
        for j in range(3):
            V[i, j] = 1.0 if i == j else 0.0
    scale = c00 + c11 + c22
    if not scale > 0.0:  # F = 0 (or NaN): no rotation to speak of
        for i in range(3):
            for j in range(3):
                R[i, j] = 1.0 if i == j else 0.0
        return
    for _ in range(SWEEPS):
        off = C[0, 1] * C[0, 1] + C[0, 2] * C[0, 2] + C[1, 2] * C[1, 2]
        if off <= 1e-32 * scale * scale:
            break
        for p, q in ((0, 1), (0, 2), (1, 2)):
            apq = C[p, q]
            if apq == 0.0:
                continue
            theta = (C[q, q] - C[p, p]) / (2.0 * apq)
            t = 1.0 / (abs(theta) + math.sqrt(theta * theta + 1.0))
            if theta < 0.0:
                t = -t
            c = 1.0 / math.sqrt(t * t + 1.0)
            s = t * c
            for k in range(3):  # C <- C J (columns p, q)
                ckp, ckq = C[k, p], C[k, q]
                C[k, p] = c * ckp - s * ckq
                C[k, q] = s * ckp + c * ckq
            for k in range(3):  # C <- J^T C (rows p, q)
                cpk, cqk = C[p, k], C[q, k]
                C[p, k] = c * cpk - s * cqk
                C[q, k] = s * cpk + c * cqk
            for k in range(3):  # V <- V J
                vkp, vkq = V[k, p], V[k, q]
                V[k, p] = c * vkp - s * vkq
                V[k, q] = s * vkp + c * vkq
    # order by decreasing eigenvalue
    o0, o1, o2 = 0, 1, 2
    if C[o1, o1] > C[o0, o0]:
        o0, o1 = o1, o0
    if C[o2, o2] > C[o1, o1]:
        o1, o2 = o2, o1
    if C[o1, o1] > C[o0, o0]:
        o0, o1 = o1, o0
    Vs = W[2]
    for i in range(3):
        Vs[i, 0], Vs[i, 1], Vs[i, 2] = V[i, o0], V[i, o1], V[i, o2]
    det_v = (
        Vs[0, 0] * (Vs[1, 1] * Vs[2, 2] - Vs[1, 2] * Vs[2, 1])
        - Vs[0, 1] * (Vs[1, 0] * Vs[2, 2] - Vs[1, 2] * Vs[2, 0])
        + Vs[0, 2] * (Vs[1, 0] * Vs[2, 1] - Vs[1, 1] * Vs[2, 0])
    )
    if det_v < 0.0:
        for i in range(3):
            Vs[i, 2] = -Vs[i, 2]
    U = W[3]
    for i in range(3):  # F v_1, F v_2
        U[i, 0] = F[i, 0] * Vs[0, 0] + F[i, 1] * Vs[1, 0] + F[i, 2] * Vs[2, 0]
        U[i, 1] = F[i, 0] * Vs[0, 1] + F[i, 1] * Vs[1, 1] + F[i, 2] * Vs[2, 1]
    n0 = math.sqrt(U[0, 0] ** 2 + U[1, 0] ** 2 + U[2, 0] ** 2)
    for i in range(3):
        U[i, 0] /= n0
    d = U[0, 0] * U[0, 1] + U[1, 0] * U[1, 1] + U[2, 0] * U[2, 1]
    for i in range(3):
        U[i, 1] -= d * U[i, 0]
    n1 = math.sqrt(U[0, 1] ** 2 + U[1, 1] ** 2 + U[2, 1] ** 2)
    if n1 <= 1e-12 * n0:  # rank one: any unit vector orthogonal to u_1
        k = 0
        if abs(U[1, 0]) < abs(U[k, 0]):
            k = 1
        if abs(U[2, 0]) < abs(U[k, 0]):
            k = 2
        for i in range(3):
            U[i, 1] = (1.0 if i == k else 0.0) - U[k, 0] * U[i, 0]
        n1 = math.sqrt(U[0, 1] ** 2 + U[1, 1] ** 2 + U[2, 1] ** 2)
    for i in range(3):
        U[i, 1] /= n1
    U[0, 2] = U[1, 0] * U[2, 1] - U[2, 0] * U[1, 1]
    U[1, 2] = U[2, 0] * U[0, 1] - U[0, 0] * U[2, 1]
    U[2, 2] = U[0, 0] * U[1, 1] - U[1, 0] * U[0, 1]
    for i in range(3):
        for j in range(3):
            R[i, j] = U[i, 0] * Vs[j, 0] + U[i, 1] * Vs[j, 1] + U[i, 2] * Vs[j, 2]


@njit(**_FLAGS)
def _rotations(F: np.ndarray, R: np.ndarray) -> None:  # pragma: no cover - compiled
    Fi = np.empty((3, 3))
    Ri = np.empty((3, 3))
    W = np.empty((4, 3, 3))
    for k in range(F.shape[0]):
        Fi[:, :] = F[k]
        polar_rotation(Fi, Ri, W)
        R[k] = Ri


def rotations(F: np.ndarray) -> np.ndarray:
    """The element rotations of gradients ``F (m, 3, 3)``.

    Parameters
    ----------
    F
        Deformation gradients ``(m, 3, 3)``.

    Returns
    -------
    ndarray
        Rotations ``(m, 3, 3)``.
    """
    F = np.ascontiguousarray(F, dtype=np.float64).reshape(-1, 3, 3)
    R = np.empty_like(F)
    _rotations(F, R)
    return R


def rotation(F: np.ndarray) -> np.ndarray:
    """The rotation of one gradient ``F (3, 3)`` (see :func:`rotations`).

    Parameters
    ----------
    F
        ``(3, 3)``.

    Returns
    -------
    ndarray
        ``(3, 3)``.
    """
    return rotations(np.asarray(F)[None])[0]
