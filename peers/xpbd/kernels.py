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
answer as this serial sweep), and the element arrays are stored in that order
(:func:`sweep_order`) so that the sweep reads them front to back; an element's ``F`` is
computed once per visit for both constraints. Jacobi computes every correction from the
same ``p`` and adds them all, each (its ``d_lambda`` and its ``d p`` alike, so that
``p - x~ = M^-1 grad C^T lambda`` still holds) times a relaxation ``omega``. Averaging the
position corrections over a node's constraints instead (Macklin et al. 2014) would scale
the forces at rest and change the rest state; it is not done.

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
...     G, 1.0 / V, 1.0 / V, 2.0, 1e-3, 2, 3, 0, 1, 1.0, 1.0, False, np.zeros(1), np.zeros(1),
...     np.zeros((4, 3)))
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
    k, p, w, tets, G, ad, ah, gamma, lam_d, lam_h, out, scale, gd, gh
):  # pragma: no cover - compiled
    """Both constraints of element ``k`` at once (a 2 x 2 solve), from one ``F``: adds
    ``scale`` times the correction to ``out`` and to ``lam_d[k], lam_h[k]`` (``gd, gh``:
    ``(4, 3)`` scratch for the node gradients)."""
    i0, i1, i2, i3 = tets[k, 0], tets[k, 1], tets[k, 2], tets[k, 3]
    # F = sum_a (p_a - p_0) (x) g_a, one row r at a time: F[r, d] = f{r}{d}
    e1, e2, e3 = p[i1, 0] - p[i0, 0], p[i2, 0] - p[i0, 0], p[i3, 0] - p[i0, 0]
    f00 = e1 * G[k, 0, 0] + e2 * G[k, 1, 0] + e3 * G[k, 2, 0]
    f01 = e1 * G[k, 0, 1] + e2 * G[k, 1, 1] + e3 * G[k, 2, 1]
    f02 = e1 * G[k, 0, 2] + e2 * G[k, 1, 2] + e3 * G[k, 2, 2]
    e1, e2, e3 = p[i1, 1] - p[i0, 1], p[i2, 1] - p[i0, 1], p[i3, 1] - p[i0, 1]
    f10 = e1 * G[k, 0, 0] + e2 * G[k, 1, 0] + e3 * G[k, 2, 0]
    f11 = e1 * G[k, 0, 1] + e2 * G[k, 1, 1] + e3 * G[k, 2, 1]
    f12 = e1 * G[k, 0, 2] + e2 * G[k, 1, 2] + e3 * G[k, 2, 2]
    e1, e2, e3 = p[i1, 2] - p[i0, 2], p[i2, 2] - p[i0, 2], p[i3, 2] - p[i0, 2]
    f20 = e1 * G[k, 0, 0] + e2 * G[k, 1, 0] + e3 * G[k, 2, 0]
    f21 = e1 * G[k, 0, 1] + e2 * G[k, 1, 1] + e3 * G[k, 2, 1]
    f22 = e1 * G[k, 0, 2] + e2 * G[k, 1, 2] + e3 * G[k, 2, 2]
    # deviatoric: C_D = |F|, dC_D/dF = F / C_D
    cd = np.sqrt(f00 * f00 + f01 * f01 + f02 * f02 + f10 * f10 + f11 * f11 + f12 * f12
                 + f20 * f20 + f21 * f21 + f22 * f22)  # fmt: skip
    r = 1.0 / cd if cd > 0.0 else 0.0
    # hydrostatic: C_H = det F - gamma, dC_H/dF = cof F (columns f_{j+1} x f_{j+2})
    c00, c01, c02 = f11 * f22 - f21 * f12, f12 * f20 - f22 * f10, f10 * f21 - f20 * f11
    c10, c11, c12 = f21 * f02 - f01 * f22, f22 * f00 - f02 * f20, f20 * f01 - f00 * f21
    c20, c21, c22 = f01 * f12 - f11 * f02, f02 * f10 - f12 * f00, f00 * f11 - f10 * f01
    ch = f00 * c00 + f10 * c10 + f20 * c20 - gamma
    for r_ in range(3):
        gd[0, r_] = 0.0
        gh[0, r_] = 0.0
    for a in range(3):  # node a + 1: dC/dF g_a; node 0: minus their sum
        g0, g1, g2 = G[k, a, 0], G[k, a, 1], G[k, a, 2]
        s0 = (f00 * g0 + f01 * g1 + f02 * g2) * r
        s1 = (f10 * g0 + f11 * g1 + f12 * g2) * r
        s2 = (f20 * g0 + f21 * g1 + f22 * g2) * r
        gd[a + 1, 0], gd[a + 1, 1], gd[a + 1, 2] = s0, s1, s2
        gd[0, 0] -= s0
        gd[0, 1] -= s1
        gd[0, 2] -= s2
        s0 = c00 * g0 + c01 * g1 + c02 * g2
        s1 = c10 * g0 + c11 * g1 + c12 * g2
        s2 = c20 * g0 + c21 * g1 + c22 * g2
        gh[a + 1, 0], gh[a + 1, 1], gh[a + 1, 2] = s0, s1, s2
        gh[0, 0] -= s0
        gh[0, 1] -= s1
        gh[0, 2] -= s2
    a11, a12, a22 = ad, 0.0, ah
    for a in range(4):
        node = tets[k, a]
        for c in range(3):
            wr = w[node, c]
            a11 += wr * gd[a, c] * gd[a, c]
            a12 += wr * gd[a, c] * gh[a, c]
            a22 += wr * gh[a, c] * gh[a, c]
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
        for c in range(3):
            out[node, c] += w[node, c] * (gd[a, c] * d1 + gh[a, c] * d2)


@njit(**_FLAGS)
def sweep(
    p, w, tets, G, ad, ah, gamma, lam_d, lam_h, dp, jacobi, coupled, omega, gd, gh, F, D
):  # pragma: no cover - compiled
    """One iteration over every element in place on ``p``: Gauss–Seidel in the order the
    elements are stored, or Jacobi (every correction from the same ``p``, summed into ``dp``,
    times ``omega``); ``ad, ah`` are the compliances over ``h^2``; ``gd, gh`` ``(4, 3)`` and
    ``F, D`` ``(3, 3)`` scratch. The time of one call is XPBD's projection pass."""
    out, scale = (dp, omega) if jacobi else (p, 1.0)
    if jacobi:
        dp[:, :] = 0.0
    for k in range(tets.shape[0]):
        if coupled:
            _project_pair(k, p, w, tets, G, ad[k], ah[k], gamma, lam_d, lam_h, out, scale,
                          gd, gh)  # fmt: skip
        else:
            _project(k, 0, p, w, tets, G, ad[k], gamma, lam_d, out, scale, gd, F, D)
            _project(k, 1, p, w, tets, G, ah[k], gamma, lam_h, out, scale, gd, F, D)
    if jacobi:
        for r in range(p.shape[0]):
            for c in range(3):
                p[r, c] += dp[r, c]


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
    jacobi,
    coupled,
    omega,
    damp,
    kinetic,
    lam_d,
    lam_h,
    dp,
):  # pragma: no cover - compiled
    """Advance ``x, v`` (overwritten) by ``substeps`` substeps; return ``substeps`` times
    the largest nodal motion ``max |p - x|`` of any one substep: how far the body would move
    in a frame at its fastest speed of the frame (what the rest test reads).

    The elements (``tets``, ``G`` and the compliances ``alpha_d, alpha_h = 1 / (mu' V),
    1 / (lam' V)``) are stored in the order Gauss–Seidel visits them, colour by colour
    (:func:`sweep_order`), so that the sweep reads them contiguously; ``coupled`` solves an
    element's two constraints together (a 2 x 2 system from one ``F``), else one after the
    other; ``jacobi`` selects Jacobi with relaxation ``omega``; ``lam_d, lam_h`` ``(m,)``
    and ``dp`` ``(n, 3)`` are work arrays.
    """
    n = x.shape[0]
    m = tets.shape[0]
    p = np.empty_like(x)
    F = np.empty((3, 3))
    D = np.empty((3, 3))
    gd = np.empty((4, 3))
    gh = np.empty((4, 3))
    h2 = h * h
    ad = alpha_d / h2  # the compliances over h^2, once per frame
    ah = alpha_h / h2
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
            sweep(p, w, tets, G, ad, ah, gamma, lam_d, lam_h, dp, jacobi, coupled, omega,
                  gd, gh, F, D)  # fmt: skip
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


def sweep_order(colours: np.ndarray) -> np.ndarray:
    """The elements colour by colour, each colour in mesh order: the Gauss–Seidel sweep,
    in which :func:`frame` wants the element arrays stored.

    Examples
    --------
    >>> sweep_order(np.array([1, 0, 1, 0])).tolist()
    [1, 3, 0, 2]
    """
    return np.argsort(colours, kind="stable").astype(np.int64)
