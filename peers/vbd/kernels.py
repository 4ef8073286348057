"""The compiled Vertex Block Descent frame (Chen, Macklin, Yang & Kavan 2024, algorithm 1).

Per substep of length ``h``::

    y = x + h v + h^2 a_ext                       (inertial target)
    x = x + h v + h^2 a~                          (initial guess, see below)
    repeat `iterations` times, colour by colour, for each vertex i of the colour:
        f_i = -m_i/h^2 (x_i - y_i) - sum_e [V_e P_e g_ea + (k_d/h) H_ie (x_i - x_i^t)]
        H_i =  m_i/h^2 I + sum_e (1 + k_d/h) H_ie
        x_i += H_i^-1 f_i                          (one 3 x 3 Newton step)
    (optionally) Chebyshev: x = omega_k (x - x^(k-2)) + x^(k-2)
    v = (x - x^t) / h;  then the viscous damping factor

``H_ie`` is element ``e``'s Hessian block at vertex ``i`` (:mod:`.energy`: positive
definite for both laws, no projection needed); ``k_d`` is the paper's stiffness-proportional
damping. The initial guess (``init``): 0 the previous positions, 1 the inertial target ``y``,
2 the paper's adaptive guess ``a~ = a_ext clamp(a_t . a_ext / |a_ext|^2, 0, 1)`` with the
last substep's acceleration ``a_t`` (at rest ``a_t = 0`` and the guess is ``x``, so a rest
state of the iteration is an equilibrium of the energy whatever the number of iterations).
Chebyshev's semi-iterative acceleration (Wang 2015, with spectral radius estimate ``rho``;
``rho = 0``: off) uses ``omega_1 = 1``, ``omega_2 = 2 / (2 - rho^2)``,
``omega_k = 4 / (4 - rho^2 omega_(k-1))``.

Supported DOFs (``free = 0``) never move: their rows and columns of ``H_i`` are replaced
by the identity and their ``f`` by zero.

Examples
--------
>>> import numpy as np
>>> from ..xpbd.constraints import rest_shape
>>> from .colouring import vertex_colouring
>>> X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> tets = np.array([[0, 1, 2, 3]])
>>> G, V = rest_shape(X, tets)
>>> c = vertex_colouring(tets, 4)
>>> R = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])
>>> x, v = X @ R.T + 0.5, np.zeros((4, 3))  # a rigid motion of the rest shape stays put
>>> moved = frame(x, v, np.zeros((4, 3)), np.ones(4), np.ones((4, 3)), np.zeros((4, 3)), tets,
...     G, V, c.order, c.colour_ptr, c.inc_ptr, c.inc_elem, c.inc_local, 0, 1.0, 2.0, 1.5,
...     0.0, 1e-3, 2, 3, 0.0, 1.0, 2)
>>> bool(moved < 1e-12), bool(np.allclose(x, X @ R.T + 0.5))
(True, True)
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

_FLAGS: dict[str, Any] = {"cache": True, "error_model": "numpy", "fastmath": {"contract"}}


@njit(**_FLAGS)
def _gradient(k, a, G, g):  # pragma: no cover - compiled
    """``g = grad N_a`` of element ``k`` (corner ``a``; ``a = 0``: minus the others' sum)."""
    if a == 0:
        for d in range(3):
            g[d] = -(G[k, 0, d] + G[k, 1, d] + G[k, 2, d])
    else:
        for d in range(3):
            g[d] = G[k, a - 1, d]


@njit(**_FLAGS)
def vertex_terms(q, x, xt, tets, G, V, inc_ptr, inc_elem, inc_local, law, mu, lam, gamma,
                 kd_h, f, H, work):  # fmt: skip  # pragma: no cover - compiled
    """The elastic part of the ``q``-th vertex's step: ``f = -sum_e [V_e P_e g + kd_h H_ie
    (x_i - x_i^t)]`` and ``H = sum_e (1 + kd_h) H_ie`` (written into ``f (3,)``, ``H (3, 3)``;
    ``i`` is the vertex whose incidence starts at ``inc_ptr[q]``; ``work`` is ``(4, 3, 3)``
    scratch)."""
    F = work[0]
    P = work[1]
    He = work[2]
    g = work[3, 0]
    c = work[3, 1]
    for r in range(3):
        f[r] = 0.0
        for s in range(3):
            He[r, s] = 0.0
    for p in range(inc_ptr[q], inc_ptr[q + 1]):
        k = inc_elem[p]
        i0 = tets[k, 0]
        for r in range(3):
            for d in range(3):
                F[r, d] = (
                    (x[tets[k, 1], r] - x[i0, r]) * G[k, 0, d]
                    + (x[tets[k, 2], r] - x[i0, r]) * G[k, 1, d]
                    + (x[tets[k, 3], r] - x[i0, r]) * G[k, 2, d]
                )
        _gradient(k, inc_local[p], G, g)
        gg = g[0] * g[0] + g[1] * g[1] + g[2] * g[2]
        v = V[k]
        if law == 0:  # stable neo-Hookean: P = mu F + lam (J - gamma) cof F
            c0 = F[1, 1] * F[2, 2] - F[2, 1] * F[1, 2]
            c1 = F[2, 1] * F[0, 2] - F[0, 1] * F[2, 2]
            c2 = F[0, 1] * F[1, 2] - F[1, 1] * F[0, 2]
            J = F[0, 0] * c0 + F[1, 0] * c1 + F[2, 0] * c2
            s = lam * (J - gamma)
            for r in range(3):  # cof F g, column j of cof F = f_(j+1) x f_(j+2)
                r1, r2 = (r + 1) % 3, (r + 2) % 3
                acc = 0.0
                for j in range(3):
                    j1, j2 = (j + 1) % 3, (j + 2) % 3
                    acc += (F[r1, j1] * F[r2, j2] - F[r2, j1] * F[r1, j2]) * g[j]
                c[r] = acc
            for r in range(3):
                acc = 0.0
                for d in range(3):
                    acc += F[r, d] * g[d]
                f[r] -= v * (mu * acc + s * c[r])
                for t in range(3):
                    He[r, t] += v * lam * c[r] * c[t]
                He[r, r] += v * mu * gg
        else:  # linear: P = 2 mu eps + lam tr(eps) I
            tr = F[0, 0] + F[1, 1] + F[2, 2] - 3.0
            for r in range(3):
                for d in range(3):
                    P[r, d] = mu * (F[r, d] + F[d, r])
                P[r, r] += lam * tr - 2.0 * mu
            for r in range(3):
                f[r] -= v * (P[r, 0] * g[0] + P[r, 1] * g[1] + P[r, 2] * g[2])
                for t in range(3):
                    He[r, t] += v * (mu + lam) * g[r] * g[t]
                He[r, r] += v * mu * gg
    i = tets[inc_elem[inc_ptr[q]], inc_local[inc_ptr[q]]]
    for r in range(3):
        for t in range(3):
            H[r, t] = (1.0 + kd_h) * He[r, t]
            f[r] -= kd_h * He[r, t] * (x[i, t] - xt[i, t])


@njit(**_FLAGS)
def _sweep(x, xt, y, masses, free, tets, G, V, order, inc_ptr, inc_elem, inc_local, law, mu,
           lam, gamma, kd_h, h2):  # fmt: skip  # pragma: no cover - compiled
    """One Gauss–Seidel pass over the vertices in colour order."""
    f = np.empty(3)
    H = np.empty((3, 3))
    work = np.empty((4, 3, 3))
    for q in range(order.shape[0]):
        i = order[q]
        if free[i, 0] + free[i, 1] + free[i, 2] == 0.0 or inc_ptr[q + 1] == inc_ptr[q]:
            continue
        vertex_terms(q, x, xt, tets, G, V, inc_ptr, inc_elem, inc_local, law, mu, lam, gamma,
                     kd_h, f, H, work)  # fmt: skip
        mh = masses[i] / h2
        for r in range(3):
            f[r] -= mh * (x[i, r] - y[i, r])
            H[r, r] += mh
        for r in range(3):
            if free[i, r] == 0.0:
                f[r] = 0.0
                for t in range(3):
                    H[r, t] = 0.0
                    H[t, r] = 0.0
                H[r, r] = 1.0
        c00 = H[1, 1] * H[2, 2] - H[1, 2] * H[2, 1]
        c01 = H[1, 2] * H[2, 0] - H[1, 0] * H[2, 2]
        c02 = H[1, 0] * H[2, 1] - H[1, 1] * H[2, 0]
        det = H[0, 0] * c00 + H[0, 1] * c01 + H[0, 2] * c02
        if not abs(det) > 1e-300:
            continue
        c10 = H[0, 2] * H[2, 1] - H[0, 1] * H[2, 2]
        c11 = H[0, 0] * H[2, 2] - H[0, 2] * H[2, 0]
        c12 = H[0, 1] * H[2, 0] - H[0, 0] * H[2, 1]
        c20 = H[0, 1] * H[1, 2] - H[0, 2] * H[1, 1]
        c21 = H[0, 2] * H[1, 0] - H[0, 0] * H[1, 2]
        c22 = H[0, 0] * H[1, 1] - H[0, 1] * H[1, 0]
        x[i, 0] += (c00 * f[0] + c10 * f[1] + c20 * f[2]) / det
        x[i, 1] += (c01 * f[0] + c11 * f[1] + c21 * f[2]) / det
        x[i, 2] += (c02 * f[0] + c12 * f[1] + c22 * f[2]) / det


@njit(**_FLAGS)
def frame(x, v, v_old, masses, free, a_ext, tets, G, V, order, colour_ptr, inc_ptr, inc_elem,
          inc_local, law, mu, lam, gamma, kd, h, substeps, iterations, rho, damp,
          init):  # fmt: skip  # pragma: no cover - compiled
    """Advance ``x, v`` (overwritten; ``v_old`` holds the velocity before the last substep,
    for the adaptive guess) by ``substeps`` substeps; return ``substeps`` times the largest
    nodal motion of one substep (what the rest test reads). ``order`` and the incidence
    arrays are :class:`~peers.vbd.colouring.VertexColouring`'s (``colour_ptr`` marks where
    the colours start; the serial sweep follows ``order``)."""
    n = x.shape[0]
    xt = np.empty_like(x)
    y = np.empty_like(x)
    km1 = np.empty_like(x)
    km2 = np.empty_like(x)
    h2 = h * h
    kd_h = kd / h
    moved = 0.0
    for _ in range(substeps):
        for i in range(n):
            aa = 0.0
            ae2 = 0.0
            for r in range(3):
                xt[i, r] = x[i, r]
                y[i, r] = x[i, r] + h * v[i, r] + h2 * a_ext[i, r] * free[i, r]
                aa += (v[i, r] - v_old[i, r]) / h * a_ext[i, r] * free[i, r]
                ae2 += a_ext[i, r] * a_ext[i, r] * free[i, r]
            s = 0.0
            if init == 1:
                s = 1.0
            elif init == 2 and ae2 > 0.0:
                s = min(max(aa / ae2, 0.0), 1.0)
            for r in range(3):
                if init > 0:
                    x[i, r] += h * v[i, r] + h2 * s * a_ext[i, r] * free[i, r]
                km1[i, r] = x[i, r]
        omega = 1.0
        for it in range(iterations):
            _sweep(x, xt, y, masses, free, tets, G, V, order, inc_ptr, inc_elem, inc_local, law,
                   mu, lam, gamma, kd_h, h2)  # fmt: skip
            if rho > 0.0:
                if it == 1:
                    omega = 2.0 / (2.0 - rho * rho)
                elif it > 1:
                    omega = 4.0 / (4.0 - rho * rho * omega)
                for i in range(n):
                    for r in range(3):
                        if it > 0:
                            x[i, r] = omega * (x[i, r] - km2[i, r]) + km2[i, r]
                        km2[i, r] = km1[i, r]
                        km1[i, r] = x[i, r]
        for i in range(n):
            for r in range(3):
                step = x[i, r] - xt[i, r]
                moved = max(moved, abs(step))
                v_old[i, r] = v[i, r]
                v[i, r] = step / h * damp
    return moved * substeps
