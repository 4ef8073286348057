"""The compiled XPBD frame: substeps of prediction, constraint projection and velocity
update (Macklin, Müller & Chentanez 2016, algorithm 1; small steps as in Macklin et al.
2019), with the constraints of :mod:`.constraints`.

Per substep of length ``h``::

    v += h a_ext;  p = x + h v;  lambda = 0
    repeat `iterations` times, for each element, for C in (C_D, C_H):
        d_lambda = (-C(p) - alpha~ lambda) / (sum_a w_a |grad_a C|^2 + alpha~)
                   with alpha~ = alpha / h^2
        p_a += w_a grad_a C d_lambda;  lambda += d_lambda
    v = (p - x) / h;  x = p;  then damping

An element's two constraints are solved together (``coupled``: the 2 x 2 system of both
``d_lambda`` with the off-diagonal ``sum_a w_a grad_a C_D . grad_a C_H``, as Macklin & Müller
2021 recommend) or one after the other (``sequential``). Only the coupled solve leaves an
undeformed element at rest: there ``grad C_D`` and ``grad C_H`` are parallel, and the two
corrections cancel exactly, where the sequential solve moves it by ``O(h^2)`` per substep.

``w`` are inverse masses per DOF (zero on supported DOFs, which therefore never move).
Gauss–Seidel visits the elements colour by colour (:func:`springfem.mesh.element_colouring`:
elements of one colour share no node, so a colour could run in parallel and gives the same
answer as this serial sweep); Jacobi computes every correction from the same ``p`` and adds
them all, each (its ``d_lambda`` and its ``d p`` alike, so that ``p - x~ = M^-1 grad C^T
lambda`` still holds) times a relaxation ``omega``. Averaging the position corrections over
a node's constraints instead (Macklin et al. 2014) would scale the forces at rest and
change the rest state; it is not done.

Damping: the velocities are multiplied by ``damp`` after each substep; with ``kinetic``
they are zeroed when the kinetic energy falls (at its peak), as dynamic relaxation does.

Examples
--------
>>> import numpy as np
>>> X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> from .constraints import rest_shape
>>> G, V = rest_shape(X, np.array([[0, 1, 2, 3]]))
>>> R = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])
>>> x, v = X @ R.T + 0.5, np.zeros((4, 3))  # rigid motion of the rest shape (mu = lam = 1)
>>> moved = frame(x, v, np.ones((4, 3)), np.ones(4), np.zeros((4, 3)), np.array([[0, 1, 2, 3]]),
...     G, 1.0 / V, 1.0 / V, 2.0, 1e-3, 2, 3, np.arange(1), 0, 1, 1.0, np.zeros(4), 1.0, False,
...     np.zeros(1), np.zeros(1), np.zeros((4, 3)))
>>> bool(moved < 1e-12), bool(np.allclose(x, X @ R.T + 0.5))  # it stays where it is
(True, True)
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

_FLAGS: dict[str, Any] = {"cache": True, "error_model": "numpy", "fastmath": {"contract"}}


@njit(**_FLAGS)
def _gradients(k, c, p, tets, G, gamma, g, F, D):  # pragma: no cover - compiled
    """Constraint ``c`` (0: deviatoric, 1: hydrostatic) of element ``k`` at ``p``: its value,
    with its node gradients written into ``g (4, 3)`` (``F``, ``D``: 3 x 3 scratch)."""
    i0 = tets[k, 0]
    for r in range(3):
        for d in range(3):
            s = 0.0
            for a in range(3):
                s += (p[tets[k, a + 1], r] - p[i0, r]) * G[k, a, d]
            F[r, d] = s
    if c == 0:  # dC/dF = F / C
        C = 0.0
        for r in range(3):
            for d in range(3):
                C += F[r, d] * F[r, d]
        C = np.sqrt(C)
        for r in range(3):
            for d in range(3):
                D[r, d] = F[r, d] / C if C > 0.0 else 0.0
    else:  # dC/dF = cof F, columns f_{j+1} x f_{j+2}
        for j in range(3):
            j1, j2 = (j + 1) % 3, (j + 2) % 3
            D[0, j] = F[1, j1] * F[2, j2] - F[2, j1] * F[1, j2]
            D[1, j] = F[2, j1] * F[0, j2] - F[0, j1] * F[2, j2]
            D[2, j] = F[0, j1] * F[1, j2] - F[1, j1] * F[0, j2]
        C = F[0, 0] * D[0, 0] + F[1, 0] * D[1, 0] + F[2, 0] * D[2, 0] - gamma
    for r in range(3):
        g[0, r] = 0.0
    for a in range(3):
        for r in range(3):
            s = D[r, 0] * G[k, a, 0] + D[r, 1] * G[k, a, 1] + D[r, 2] * G[k, a, 2]
            g[a + 1, r] = s
            g[0, r] -= s
    return C


@njit(**_FLAGS)
def _project(k, c, p, w, tets, G, alpha, gamma, lam, out, scale, g, F, D):  # pragma: no cover
    """Constraint ``c`` of element ``k`` alone: adds ``scale`` times its correction to
    ``out`` and to ``lam[k]``."""
    C = _gradients(k, c, p, tets, G, gamma, g, F, D)
    denom = alpha
    for a in range(4):
        node = tets[k, a]
        for r in range(3):
            denom += w[node, r] * g[a, r] * g[a, r]
    if not denom > 0.0:
        return
    dl = scale * (-C - alpha * lam[k]) / denom
    lam[k] += dl
    for a in range(4):
        node = tets[k, a]
        for r in range(3):
            out[node, r] += w[node, r] * g[a, r] * dl


@njit(**_FLAGS)
def _project_pair(
    k, p, w, tets, G, ad, ah, gamma, lam_d, lam_h, out, scale, gd, gh, F, D
):  # pragma: no cover
    """Both constraints of element ``k`` at once (a 2 x 2 solve): adds ``scale`` times the
    correction to ``out`` and to ``lam_d[k], lam_h[k]``."""
    cd = _gradients(k, 0, p, tets, G, gamma, gd, F, D)
    ch = _gradients(k, 1, p, tets, G, gamma, gh, F, D)
    a11, a12, a22 = ad, 0.0, ah
    for a in range(4):
        node = tets[k, a]
        for r in range(3):
            wr = w[node, r]
            a11 += wr * gd[a, r] * gd[a, r]
            a12 += wr * gd[a, r] * gh[a, r]
            a22 += wr * gh[a, r] * gh[a, r]
    b1 = -cd - ad * lam_d[k]
    b2 = -ch - ah * lam_h[k]
    det = a11 * a22 - a12 * a12
    if not det > 0.0:
        return
    d1 = scale * (a22 * b1 - a12 * b2) / det
    d2 = scale * (a11 * b2 - a12 * b1) / det
    lam_d[k] += d1
    lam_h[k] += d2
    for a in range(4):
        node = tets[k, a]
        for r in range(3):
            out[node, r] += w[node, r] * (gd[a, r] * d1 + gh[a, r] * d2)


@njit(**_FLAGS)
def frame(
    x,
    v,
    w,
    masses,
    a_ext,
    tets,
    G,
    alpha_d,
    alpha_h,
    gamma,
    h,
    substeps,
    iterations,
    order,
    jacobi,
    coupled,
    omega,
    inv_count,
    damp,
    kinetic,
    lam_d,
    lam_h,
    dp,
):  # pragma: no cover - compiled
    """Advance ``x, v`` (overwritten) by ``substeps`` substeps; return ``substeps`` times
    the largest nodal motion ``max |p - x|`` of any one substep: how far the body would move
    in a frame at its fastest speed of the frame (what the rest test reads).

    ``order`` lists the elements by colour (Gauss–Seidel); ``coupled`` solves an element's
    two constraints together (a 2 x 2 system), else one after the other; ``jacobi`` selects
    Jacobi with relaxation ``omega`` and per-node ``inv_count = 1 / (constraints at the
    node)``, unused; ``alpha_d, alpha_h`` are the compliances ``1 / (mu' V), 1 / (lam' V)`` per
    element; ``lam_d, lam_h`` ``(m,)`` and ``dp`` ``(n, 3)`` are work arrays.
    """
    n = x.shape[0]
    m = tets.shape[0]
    p = np.empty_like(x)
    F = np.empty((3, 3))
    D = np.empty((3, 3))
    gd = np.empty((4, 3))
    gh = np.empty((4, 3))
    h2 = h * h
    ke_prev = 0.0
    for r in range(n):
        for c in range(3):
            ke_prev += 0.5 * masses[r] * v[r, c] * v[r, c]
    ke = ke_prev
    moved = 0.0
    for _ in range(substeps):
        for r in range(n):
            for c in range(3):
                if w[r, c] > 0.0:
                    v[r, c] += h * a_ext[r, c]
                p[r, c] = x[r, c] + h * v[r, c]
        for k in range(m):
            lam_d[k] = 0.0
            lam_h[k] = 0.0
        for _it in range(iterations):
            if jacobi:
                dp[:, :] = 0.0
                for k in range(m):
                    if coupled:
                        _project_pair(
                            k,
                            p,
                            w,
                            tets,
                            G,
                            alpha_d[k] / h2,
                            alpha_h[k] / h2,
                            gamma,
                            lam_d,
                            lam_h,
                            dp,
                            omega,
                            gd,
                            gh,
                            F,
                            D,
                        )
                    else:
                        _project(
                            k, 0, p, w, tets, G, alpha_d[k] / h2, gamma, lam_d, dp, omega, gd, F, D
                        )
                        _project(
                            k, 1, p, w, tets, G, alpha_h[k] / h2, gamma, lam_h, dp, omega, gd, F, D
                        )
                for r in range(n):
                    for c in range(3):
                        p[r, c] += dp[r, c]
            else:
                for q in range(order.shape[0]):
                    k = order[q]
                    if coupled:
                        _project_pair(
                            k,
                            p,
                            w,
                            tets,
                            G,
                            alpha_d[k] / h2,
                            alpha_h[k] / h2,
                            gamma,
                            lam_d,
                            lam_h,
                            p,
                            1.0,
                            gd,
                            gh,
                            F,
                            D,
                        )
                    else:
                        _project(
                            k, 0, p, w, tets, G, alpha_d[k] / h2, gamma, lam_d, p, 1.0, gd, F, D
                        )
                        _project(
                            k, 1, p, w, tets, G, alpha_h[k] / h2, gamma, lam_h, p, 1.0, gd, F, D
                        )
        ke = 0.0
        for r in range(n):
            for c in range(3):
                step = p[r, c] - x[r, c]
                moved = max(moved, abs(step))
                vv = step / h * damp
                v[r, c] = vv
                x[r, c] = p[r, c]
                ke += 0.5 * masses[r] * vv * vv
        if kinetic and ke < ke_prev:
            v[:, :] = 0.0
            ke = 0.0
        ke_prev = ke
    return moved * substeps
