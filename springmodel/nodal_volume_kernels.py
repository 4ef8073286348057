"""Compiled passes of :class:`springmodel.nodal_volume.NodalVolume`: one loop over the tets.

The same formulas as :func:`springmodel.nodal_volume.tet_volumes_and_gradients` and
:func:`~springmodel.nodal_volume.tet_volume_hessians` (the numpy reference the tests compare
with): with the edges ``a = x1 - x0``, ``b = x2 - x0``, ``c = x3 - x0``, ``V = a . (b x c) /
6``, ``dV/dx1 = b x c / 6``, ``dV/dx2 = c x a / 6``, ``dV/dx3 = a x b / 6``, ``dV/dx0 =
-(their sum)``; the Hessian's edge blocks are ``E(c) / 6`` (``a, b``), ``E(a) / 6`` (``b, c``),
``E(b) / 6`` (``c, a``) with ``E(v)_{ab} = eps_{abg} v_g``. Serial, in element order
(deterministic sums).

Examples
--------
>>> import numpy as np
>>> x = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> out = np.zeros(4)
>>> nodal_volumes(x, np.array([[0, 1, 2, 3]]), out)
>>> out.tolist() == [1 / 24] * 4
True
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, fastmath=False, inline="always")
def _edges(x, i0, i1, i2, i3):  # pragma: no cover - compiled
    """``b x c / 6``, ``c x a / 6``, ``a x b / 6`` and ``a`` of the tet's edges from ``x0``."""
    a0, a1, a2 = x[i1, 0] - x[i0, 0], x[i1, 1] - x[i0, 1], x[i1, 2] - x[i0, 2]
    b0, b1, b2 = x[i2, 0] - x[i0, 0], x[i2, 1] - x[i0, 1], x[i2, 2] - x[i0, 2]
    c0, c1, c2 = x[i3, 0] - x[i0, 0], x[i3, 1] - x[i0, 1], x[i3, 2] - x[i0, 2]
    s = 1.0 / 6.0
    return (
        (b1 * c2 - b2 * c1) * s, (b2 * c0 - b0 * c2) * s, (b0 * c1 - b1 * c0) * s,
        (c1 * a2 - c2 * a1) * s, (c2 * a0 - c0 * a2) * s, (c0 * a1 - c1 * a0) * s,
        (a1 * b2 - a2 * b1) * s, (a2 * b0 - a0 * b2) * s, (a0 * b1 - a1 * b0) * s,
        a0, a1, a2,
    )  # fmt: skip


@njit(cache=True, fastmath=False)
def nodal_volumes(x, tets, out):  # pragma: no cover - compiled; tested against numpy
    """``out[a] += sum_{e ni a} V_e / 4`` (signed volumes)."""
    for e in range(tets.shape[0]):
        i0, i1, i2, i3 = tets[e, 0], tets[e, 1], tets[e, 2], tets[e, 3]
        g10, g11, g12, _, _, _, _, _, _, a0, a1, a2 = _edges(x, i0, i1, i2, i3)
        V = 0.25 * (a0 * g10 + a1 * g11 + a2 * g12)
        out[i0] += V
        out[i1] += V
        out[i2] += V
        out[i3] += V


@njit(cache=True, fastmath=False)
def volume_forces(x, tets, dU, out):  # pragma: no cover - compiled; tested against numpy
    """``out -= pbar_e dV_e/dx`` with ``pbar_e`` the mean of ``dU`` over the tet's nodes."""
    for e in range(tets.shape[0]):
        i0, i1, i2, i3 = tets[e, 0], tets[e, 1], tets[e, 2], tets[e, 3]
        g10, g11, g12, g20, g21, g22, g30, g31, g32, _, _, _ = _edges(x, i0, i1, i2, i3)
        p = 0.25 * (dU[i0] + dU[i1] + dU[i2] + dU[i3])
        out[i1, 0] -= p * g10
        out[i1, 1] -= p * g11
        out[i1, 2] -= p * g12
        out[i2, 0] -= p * g20
        out[i2, 1] -= p * g21
        out[i2, 2] -= p * g22
        out[i3, 0] -= p * g30
        out[i3, 1] -= p * g31
        out[i3, 2] -= p * g32
        out[i0, 0] += p * (g10 + g20 + g30)
        out[i0, 1] += p * (g11 + g21 + g31)
        out[i0, 2] += p * (g12 + g22 + g32)


@njit(cache=True, fastmath=False)
def volume_gradients(x, tets, out):  # pragma: no cover - compiled; tested against numpy
    """``out[e] = dV_e/dx`` ``(m, 4, 3)``."""
    for e in range(tets.shape[0]):
        i0, i1, i2, i3 = tets[e, 0], tets[e, 1], tets[e, 2], tets[e, 3]
        g = _edges(x, i0, i1, i2, i3)
        for al in range(3):
            out[e, 1, al], out[e, 2, al], out[e, 3, al] = g[al], g[3 + al], g[6 + al]
            out[e, 0, al] = -(g[al] + g[3 + al] + g[6 + al])


@njit(cache=True, fastmath=False)
def _cross_matrix(v0, v1, v2, s, E):  # pragma: no cover - compiled
    """``E = s E(v)``, ``E(v)_{ab} = eps_{abg} v_g``."""
    E[0, 0], E[0, 1], E[0, 2] = 0.0, s * v2, -s * v1
    E[1, 0], E[1, 1], E[1, 2] = -s * v2, 0.0, s * v0
    E[2, 0], E[2, 1], E[2, 2] = s * v1, -s * v0, 0.0


@njit(cache=True, fastmath=False)
def add_volume_hessians(x, tets, pbar, emap, data):  # pragma: no cover - compiled
    """``data += sum_e pbar_e d^2V_e/dx^2`` through the element map ``emap`` ``(m, 144)``."""
    He = np.zeros((3, 3, 3, 3))  # edge blocks [p, q, al, be]
    Hn = np.empty((4, 4, 3, 3))
    ed = np.empty((3, 3))
    for e in range(tets.shape[0]):
        i0 = tets[e, 0]
        for r in range(3):
            for al in range(3):
                ed[r, al] = x[tets[e, r + 1], al] - x[i0, al]
        s = pbar[e] / 6.0
        for p, q, r in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
            _cross_matrix(ed[r, 0], ed[r, 1], ed[r, 2], s, He[p, q])
            for al in range(3):
                for be in range(3):
                    He[q, p, al, be] = -He[p, q, al, be]
        for al in range(3):
            for be in range(3):
                tot = 0.0
                for p in range(3):
                    row = 0.0
                    col = 0.0
                    for q in range(3):
                        Hn[p + 1, q + 1, al, be] = He[p, q, al, be]
                        row += He[p, q, al, be]
                        col += He[q, p, al, be]
                    Hn[p + 1, 0, al, be] = -row
                    Hn[0, p + 1, al, be] = -col
                    tot += row
                Hn[0, 0, al, be] = tot
        k = 0
        for i in range(4):
            for al in range(3):
                for j in range(4):
                    for be in range(3):
                        data[emap[e, k]] += Hn[i, j, al, be]
                        k += 1
