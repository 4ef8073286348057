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
#: Jacobi sweeps at most (each sweep three rotations; 3-5 reach round-off from any F).
SWEEPS = 20
#: Newton's polar iteration runs where ``det F > NEWTON_MIN_DET |F|^3 / 3^1.5`` (the
#: well-conditioned, uninverted elements), at most this many iterations.
NEWTON_MIN_DET = 1e-2
NEWTON_ITERATIONS = 12


@njit(**_FLAGS)
def _jacobi(app, aqq, apq, arp, arq):  # pragma: no cover - compiled
    """One Jacobi rotation zeroing ``a_pq`` of a symmetric 3x3 (Numerical Recipes' update):
    the new ``a_pp, a_qq, a_rp, a_rq`` and the rotation's ``c, s``."""
    if apq == 0.0:
        return app, aqq, arp, arq, 1.0, 0.0
    theta = (aqq - app) / (2.0 * apq)
    t = 1.0 / (abs(theta) + math.sqrt(theta * theta + 1.0))
    if theta < 0.0:
        t = -t
    c = 1.0 / math.sqrt(t * t + 1.0)
    s = t * c
    return app - t * apq, aqq + t * apq, c * arp - s * arq, s * arp + c * arq, c, s


@njit(**_FLAGS)
def _newton_polar(f00, f01, f02, f10, f11, f12, f20, f21, f22, R):  # pragma: no cover
    """The polar rotation by Newton's iteration ``X <- (g X + X^-T / g) / 2`` with
    Higham's determinant scaling ``g = |det X|^(-1/3)``, for a well-conditioned ``F`` with
    ``det F > 0`` (then it converges quadratically to the rotation of ``F = R S``); writes
    ``R`` and returns ``True``, or ``False`` (inverted, flat or slow: the Jacobi path)."""
    ff = f00 * f00 + f01 * f01 + f02 * f02 + f10 * f10 + f11 * f11 + f12 * f12
    ff += f20 * f20 + f21 * f21 + f22 * f22
    det = (
        f00 * (f11 * f22 - f12 * f21)
        - f01 * (f10 * f22 - f12 * f20)
        + f02 * (f10 * f21 - f11 * f20)
    )
    if not det > NEWTON_MIN_DET * (ff / 3.0) ** 1.5:
        return False
    x00, x01, x02, x10, x11, x12, x20, x21, x22 = f00, f01, f02, f10, f11, f12, f20, f21, f22
    for _ in range(NEWTON_ITERATIONS):
        c00, c01, c02 = x11 * x22 - x12 * x21, x12 * x20 - x10 * x22, x10 * x21 - x11 * x20
        c10, c11, c12 = x02 * x21 - x01 * x22, x00 * x22 - x02 * x20, x01 * x20 - x00 * x21
        c20, c21, c22 = x01 * x12 - x02 * x11, x02 * x10 - x00 * x12, x00 * x11 - x01 * x10
        d = x00 * c00 + x01 * c01 + x02 * c02  # X^-T = cof(X) / det X
        g = 1.0 if abs(d - 1.0) < 0.5 else d ** (-1.0 / 3.0)  # scale only far from J = 1
        a, b = 0.5 * g, 0.5 / (g * d)
        y00, y01, y02 = a * x00 + b * c00, a * x01 + b * c01, a * x02 + b * c02
        y10, y11, y12 = a * x10 + b * c10, a * x11 + b * c11, a * x12 + b * c12
        y20, y21, y22 = a * x20 + b * c20, a * x21 + b * c21, a * x22 + b * c22
        change = (
            abs(y00 - x00) + abs(y01 - x01) + abs(y02 - x02)
            + abs(y10 - x10) + abs(y11 - x11) + abs(y12 - x12)
            + abs(y20 - x20) + abs(y21 - x21) + abs(y22 - x22)
        )  # fmt: skip
        x00, x01, x02, x10, x11, x12, x20, x21, x22 = y00, y01, y02, y10, y11, y12, y20, y21, y22
        if change < 1e-6:  # quadratic: the error is now ~1e-12, after one more step round-off
            c00, c01, c02 = x11 * x22 - x12 * x21, x12 * x20 - x10 * x22, x10 * x21 - x11 * x20
            c10, c11, c12 = x02 * x21 - x01 * x22, x00 * x22 - x02 * x20, x01 * x20 - x00 * x21
            c20, c21, c22 = x01 * x12 - x02 * x11, x02 * x10 - x00 * x12, x00 * x11 - x01 * x10
            h = 0.5 / (x00 * c00 + x01 * c01 + x02 * c02)
            R[0, 0], R[0, 1], R[0, 2] = (
                0.5 * x00 + h * c00,
                0.5 * x01 + h * c01,
                0.5 * x02 + h * c02,
            )
            R[1, 0], R[1, 1], R[1, 2] = (
                0.5 * x10 + h * c10,
                0.5 * x11 + h * c11,
                0.5 * x12 + h * c12,
            )
            R[2, 0], R[2, 1], R[2, 2] = (
                0.5 * x20 + h * c20,
                0.5 * x21 + h * c21,
                0.5 * x22 + h * c22,
            )
            return True
    return False


@njit(**_FLAGS)
def polar_rotation(F: np.ndarray, R: np.ndarray, W: np.ndarray) -> None:  # pragma: no cover
    """Write the rotation of the 3x3 ``F`` into ``R`` (see the module docstring); ``W`` is
    a ``(4, 3, 3)`` scratch array (unused: kept for the callers' signature)."""
    f00, f01, f02 = F[0, 0], F[0, 1], F[0, 2]
    f10, f11, f12 = F[1, 0], F[1, 1], F[1, 2]
    f20, f21, f22 = F[2, 0], F[2, 1], F[2, 2]
    if _newton_polar(f00, f01, f02, f10, f11, f12, f20, f21, f22, R):
        return
    # C = F^T F
    a00 = f00 * f00 + f10 * f10 + f20 * f20
    a11 = f01 * f01 + f11 * f11 + f21 * f21
    a22 = f02 * f02 + f12 * f12 + f22 * f22
    a01 = f00 * f01 + f10 * f11 + f20 * f21
    a02 = f00 * f02 + f10 * f12 + f20 * f22
    a12 = f01 * f02 + f11 * f12 + f21 * f22
    scale = a00 + a11 + a22
    if not scale > 0.0:  # F = 0 (or NaN): no rotation to speak of
        for i in range(3):
            for j in range(3):
                R[i, j] = 1.0 if i == j else 0.0
        return
    v00, v01, v02 = 1.0, 0.0, 0.0
    v10, v11, v12 = 0.0, 1.0, 0.0
    v20, v21, v22 = 0.0, 0.0, 1.0
    tol = 1e-32 * scale * scale
    for _ in range(SWEEPS):
        if a01 * a01 + a02 * a02 + a12 * a12 <= tol:
            break
        # (p, q, r) = (0, 1, 2)
        a00, a11, a02, a12, c, s = _jacobi(a00, a11, a01, a02, a12)
        a01 = 0.0
        v00, v01 = c * v00 - s * v01, s * v00 + c * v01
        v10, v11 = c * v10 - s * v11, s * v10 + c * v11
        v20, v21 = c * v20 - s * v21, s * v20 + c * v21
        # (p, q, r) = (0, 2, 1)
        a00, a22, a01, a12, c, s = _jacobi(a00, a22, a02, a01, a12)
        a02 = 0.0
        v00, v02 = c * v00 - s * v02, s * v00 + c * v02
        v10, v12 = c * v10 - s * v12, s * v10 + c * v12
        v20, v22 = c * v20 - s * v22, s * v20 + c * v22
        # (p, q, r) = (1, 2, 0)
        a11, a22, a01, a02, c, s = _jacobi(a11, a22, a12, a01, a02)
        a12 = 0.0
        v01, v02 = c * v01 - s * v02, s * v01 + c * v02
        v11, v12 = c * v11 - s * v12, s * v11 + c * v12
        v21, v22 = c * v21 - s * v22, s * v21 + c * v22
    # the eigenvectors of the largest and the middle eigenvalue
    if a00 >= a11 and a00 >= a22:
        x0, x1, x2 = v00, v10, v20
        if a11 >= a22:
            y0, y1, y2 = v01, v11, v21
        else:
            y0, y1, y2 = v02, v12, v22
    elif a11 >= a22:
        x0, x1, x2 = v01, v11, v21
        if a00 >= a22:
            y0, y1, y2 = v00, v10, v20
        else:
            y0, y1, y2 = v02, v12, v22
    else:
        x0, x1, x2 = v02, v12, v22
        if a00 >= a11:
            y0, y1, y2 = v00, v10, v20
        else:
            y0, y1, y2 = v01, v11, v21
    # v_3 = v_1 x v_2: V a rotation
    z0, z1, z2 = x1 * y2 - x2 * y1, x2 * y0 - x0 * y2, x0 * y1 - x1 * y0
    # u_1 = F v_1 / |F v_1|, u_2 = the part of F v_2 orthogonal to u_1, u_3 = u_1 x u_2
    p0 = f00 * x0 + f01 * x1 + f02 * x2
    p1 = f10 * x0 + f11 * x1 + f12 * x2
    p2 = f20 * x0 + f21 * x1 + f22 * x2
    n0 = math.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
    p0, p1, p2 = p0 / n0, p1 / n0, p2 / n0
    q0 = f00 * y0 + f01 * y1 + f02 * y2
    q1 = f10 * y0 + f11 * y1 + f12 * y2
    q2 = f20 * y0 + f21 * y1 + f22 * y2
    d = p0 * q0 + p1 * q1 + p2 * q2
    q0, q1, q2 = q0 - d * p0, q1 - d * p1, q2 - d * p2
    n1 = math.sqrt(q0 * q0 + q1 * q1 + q2 * q2)
    if n1 <= 1e-12 * n0:  # rank one: any unit vector orthogonal to u_1
        if abs(p0) <= abs(p1) and abs(p0) <= abs(p2):
            q0, q1, q2 = 1.0 - p0 * p0, -p0 * p1, -p0 * p2
        elif abs(p1) <= abs(p2):
            q0, q1, q2 = -p1 * p0, 1.0 - p1 * p1, -p1 * p2
        else:
            q0, q1, q2 = -p2 * p0, -p2 * p1, 1.0 - p2 * p2
        n1 = math.sqrt(q0 * q0 + q1 * q1 + q2 * q2)
    q0, q1, q2 = q0 / n1, q1 / n1, q2 / n1
    r0, r1, r2 = p1 * q2 - p2 * q1, p2 * q0 - p0 * q2, p0 * q1 - p1 * q0
    # R = u_1 v_1^T + u_2 v_2^T + u_3 v_3^T
    R[0, 0] = p0 * x0 + q0 * y0 + r0 * z0
    R[0, 1] = p0 * x1 + q0 * y1 + r0 * z1
    R[0, 2] = p0 * x2 + q0 * y2 + r0 * z2
    R[1, 0] = p1 * x0 + q1 * y0 + r1 * z0
    R[1, 1] = p1 * x1 + q1 * y1 + r1 * z1
    R[1, 2] = p1 * x2 + q1 * y2 + r1 * z2
    R[2, 0] = p2 * x0 + q2 * y0 + r2 * z0
    R[2, 1] = p2 * x1 + q2 * y1 + r2 * z1
    R[2, 2] = p2 * x2 + q2 * y2 + r2 * z2


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
