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
computed once per visit for both constraints, and the coupled sweep takes the elements in
blocks of one colour (gather, solve each from the block's copy, scatter: the same
arithmetic, but no element waits for the one before). Jacobi computes every correction from the
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
...     G, 1.0 / V, 1.0 / V, 2.0, 1e-3, 2, 3, 0, 1, 1.0, np.array([0, 1]), 1.0, False,
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


#: Elements of one colour per block of the coupled sweep, and the rows of its scratch
#: ``(ROWS * BLOCK,)``: row ``r`` of element ``j`` of the block at ``r * BLOCK + j``.
BLOCK = 16
_E, _G, _W, _LD, _LH, _AD, _AH, _GD, _GH, _D1, _D2 = 0, 9, 18, 30, 31, 32, 33, 34, 46, 58, 59
ROWS = 60


@njit(**_FLAGS)
def _pair_block(
    k0, nb, p, w, tets, G, ad, ah, gamma, lam_d, lam_h, out, scale, S
):  # pragma: no cover - compiled
    """Both constraints of elements ``k0 .. k0 + nb - 1`` (one colour: no shared node), each
    a 2 x 2 solve from one ``F``: adds ``scale`` times the corrections to ``out`` and to
    ``lam_d, lam_h``. Gathers the block into ``S``, solves element by element from ``S``
    alone (independent elements: no chain of dependent operations from one to the next),
    then scatters."""
    for j in range(nb):  # gather: edge vectors p_a - p_0, G, inverse masses, multipliers
        k = k0 + j
        i0 = tets[k, 0]
        for a in range(3):
            ia = tets[k, a + 1]
            for r in range(3):
                S[(_E + 3 * a + r) * BLOCK + j] = p[ia, r] - p[i0, r]
                S[(_G + 3 * a + r) * BLOCK + j] = G[k, a, r]
        for a in range(4):
            ia = tets[k, a]
            for c in range(3):
                S[(_W + 3 * a + c) * BLOCK + j] = w[ia, c]
        S[_LD * BLOCK + j] = lam_d[k]
        S[_LH * BLOCK + j] = lam_h[k]
        S[_AD * BLOCK + j] = ad[k]
        S[_AH * BLOCK + j] = ah[k]
    for j in range(nb):
        # F = sum_a (p_a - p_0) (x) g_a: F[r, d] = f{r}{d}
        e0, e1, e2 = S[_E * BLOCK + j], S[(_E + 1) * BLOCK + j], S[(_E + 2) * BLOCK + j]
        e3, e4, e5 = S[(_E + 3) * BLOCK + j], S[(_E + 4) * BLOCK + j], S[(_E + 5) * BLOCK + j]
        e6, e7, e8 = S[(_E + 6) * BLOCK + j], S[(_E + 7) * BLOCK + j], S[(_E + 8) * BLOCK + j]
        g0, g1, g2 = S[_G * BLOCK + j], S[(_G + 1) * BLOCK + j], S[(_G + 2) * BLOCK + j]
        g3, g4, g5 = S[(_G + 3) * BLOCK + j], S[(_G + 4) * BLOCK + j], S[(_G + 5) * BLOCK + j]
        g6, g7, g8 = S[(_G + 6) * BLOCK + j], S[(_G + 7) * BLOCK + j], S[(_G + 8) * BLOCK + j]
        f00 = e0 * g0 + e3 * g3 + e6 * g6
        f01 = e0 * g1 + e3 * g4 + e6 * g7
        f02 = e0 * g2 + e3 * g5 + e6 * g8
        f10 = e1 * g0 + e4 * g3 + e7 * g6
        f11 = e1 * g1 + e4 * g4 + e7 * g7
        f12 = e1 * g2 + e4 * g5 + e7 * g8
        f20 = e2 * g0 + e5 * g3 + e8 * g6
        f21 = e2 * g1 + e5 * g4 + e8 * g7
        f22 = e2 * g2 + e5 * g5 + e8 * g8
        # deviatoric: C_D = |F|, dC_D/dF = F / C_D
        cd = np.sqrt(f00 * f00 + f01 * f01 + f02 * f02 + f10 * f10 + f11 * f11 + f12 * f12
                     + f20 * f20 + f21 * f21 + f22 * f22)  # fmt: skip
        rc = 1.0 / cd if cd > 0.0 else 0.0
        # hydrostatic: C_H = det F - gamma, dC_H/dF = cof F (columns f_{j+1} x f_{j+2})
        c00, c01, c02 = f11 * f22 - f21 * f12, f12 * f20 - f22 * f10, f10 * f21 - f20 * f11
        c10, c11, c12 = f21 * f02 - f01 * f22, f22 * f00 - f02 * f20, f20 * f01 - f00 * f21
        c20, c21, c22 = f01 * f12 - f11 * f02, f02 * f10 - f12 * f00, f00 * f11 - f10 * f01
        ch = f00 * c00 + f10 * c10 + f20 * c20 - gamma
        # node gradients: node a + 1 dC/dF g_a, node 0 minus their sum
        d0s = d1s = d2s = h0s = h1s = h2s = 0.0
        for a in range(3):
            u0, u1, u2 = (
                S[(_G + 3 * a) * BLOCK + j],
                S[(_G + 3 * a + 1) * BLOCK + j],
                S[(_G + 3 * a + 2) * BLOCK + j],
            )
            d0 = (f00 * u0 + f01 * u1 + f02 * u2) * rc
            d1 = (f10 * u0 + f11 * u1 + f12 * u2) * rc
            d2 = (f20 * u0 + f21 * u1 + f22 * u2) * rc
            h0 = c00 * u0 + c01 * u1 + c02 * u2
            h1 = c10 * u0 + c11 * u1 + c12 * u2
            h2 = c20 * u0 + c21 * u1 + c22 * u2
            S[(_GD + 3 * a + 3) * BLOCK + j] = d0
            S[(_GD + 3 * a + 4) * BLOCK + j] = d1
            S[(_GD + 3 * a + 5) * BLOCK + j] = d2
            S[(_GH + 3 * a + 3) * BLOCK + j] = h0
            S[(_GH + 3 * a + 4) * BLOCK + j] = h1
            S[(_GH + 3 * a + 5) * BLOCK + j] = h2
            d0s -= d0
            d1s -= d1
            d2s -= d2
            h0s -= h0
            h1s -= h1
            h2s -= h2
        S[_GD * BLOCK + j], S[(_GD + 1) * BLOCK + j], S[(_GD + 2) * BLOCK + j] = d0s, d1s, d2s
        S[_GH * BLOCK + j], S[(_GH + 1) * BLOCK + j], S[(_GH + 2) * BLOCK + j] = h0s, h1s, h2s
        a11, a12, a22 = S[_AD * BLOCK + j], 0.0, S[_AH * BLOCK + j]
        for q in range(12):
            wr = S[(_W + q) * BLOCK + j]
            gd, gh = S[(_GD + q) * BLOCK + j], S[(_GH + q) * BLOCK + j]
            a11 += wr * gd * gd
            a12 += wr * gd * gh
            a22 += wr * gh * gh
        b1 = -cd - S[_AD * BLOCK + j] * S[_LD * BLOCK + j]
        b2 = -ch - S[_AH * BLOCK + j] * S[_LH * BLOCK + j]
        det = a11 * a22 - a12 * a12
        if det > 0.0:
            S[_D1 * BLOCK + j] = scale * (a22 * b1 - a12 * b2) / det
            S[_D2 * BLOCK + j] = scale * (a11 * b2 - a12 * b1) / det
        else:
            S[_D1 * BLOCK + j] = 0.0
            S[_D2 * BLOCK + j] = 0.0
    for j in range(nb):  # scatter
        k = k0 + j
        d1, d2 = S[_D1 * BLOCK + j], S[_D2 * BLOCK + j]
        lam_d[k] += d1
        lam_h[k] += d2
        for a in range(4):
            ia = tets[k, a]
            for c in range(3):
                q = 3 * a + c
                out[ia, c] += S[(_W + q) * BLOCK + j] * (
                    S[(_GD + q) * BLOCK + j] * d1 + S[(_GH + q) * BLOCK + j] * d2
                )


@njit(**_FLAGS)
def sweep(
    p, w, tets, G, ad, ah, gamma, lam_d, lam_h, dp, jacobi, coupled, omega, starts, S, g, F, D
):  # pragma: no cover - compiled
    """One iteration over every element in place on ``p``: Gauss–Seidel in the order the
    elements are stored, or Jacobi (every correction from the same ``p``, summed into ``dp``,
    times ``omega``); ``ad, ah`` are the compliances over ``h^2``; ``starts`` the first
    element of every block (:func:`sweep_blocks`), ``S`` ``(ROWS * BLOCK,)``, ``g`` ``(4, 3)``
    and ``F, D`` ``(3, 3)`` scratch. The time of one call is XPBD's projection pass."""
    out, scale = (dp, omega) if jacobi else (p, 1.0)
    if jacobi:
        dp[:, :] = 0.0
    if coupled:
        for b in range(starts.shape[0] - 1):
            _pair_block(starts[b], starts[b + 1] - starts[b], p, w, tets, G, ad, ah, gamma,
                        lam_d, lam_h, out, scale, S)  # fmt: skip
    else:
        for k in range(tets.shape[0]):
            _project(k, 0, p, w, tets, G, ad[k], gamma, lam_d, out, scale, g, F, D)
            _project(k, 1, p, w, tets, G, ah[k], gamma, lam_h, out, scale, g, F, D)
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
    starts,
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
    element's two constraints together (a 2 x 2 system from one ``F``), a block of elements
    of one colour at a time (``starts``, :func:`sweep_blocks`), else one after the other;
    ``jacobi`` selects Jacobi with relaxation ``omega``; ``lam_d, lam_h`` ``(m,)``
    and ``dp`` ``(n, 3)`` are work arrays.
    """
    n = x.shape[0]
    m = tets.shape[0]
    p = np.empty_like(x)
    F = np.empty((3, 3))
    D = np.empty((3, 3))
    g = np.empty((4, 3))
    S = np.empty(ROWS * BLOCK)
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
                  starts, S, g, F, D)  # fmt: skip
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


def sweep_blocks(colours: np.ndarray) -> np.ndarray:
    """The first element of every block of the coupled sweep, and the end: runs of at most
    :data:`BLOCK` elements of one colour, for ``colours`` in sweep order.

    Examples
    --------
    >>> sweep_blocks(np.array([0] * 20 + [1] * 3)).tolist()
    [0, 16, 20, 23]
    """
    edges = [0, *(np.flatnonzero(np.diff(colours)) + 1).tolist(), len(colours)]
    starts = {len(colours)}
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        starts.update(range(lo, hi, BLOCK))
    return np.array(sorted(starts), dtype=np.int64)
