"""Explicit P1 FEM force kernels specialised per law and precision, on a blocked layout.

The same layout and drivers as the spring kernels (the core's :mod:`springfem.blocks`), so
the two models are optimised alike: blocks of :data:`BLOCK` elements, connectivity
``T (nb, 4 B)`` int32, constants
``K (nb, 10 B)`` lane-major (``grad N_1..3``, 9 values, and the rest volume; ``grad N_0 =
-(grad N_1 + grad N_2 + grad N_3)`` is not stored), the edge vectors ``x_a - x_0`` gathered
in float64, one branch-free loop over a block's lanes (``error_model='numpy'``, FMA
contraction allowed), a scalar scatter. Per element::

    F = sum_a (x_a - x_0) (x) grad N_a,    f_a = -V P(F) grad N_a,  f_0 = -(f_1 + f_2 + f_3)

    neo-Hookean (coupled): P = mu F + (lam ln J - mu) cof(F) / J
    linear:                P = 2 mu eps + lam tr(eps) I,   eps = sym(F - I)

The neo-Hookean block runs three lane loops: ``J`` (vectorised), ``(lam ln J - mu) / J``
(scalar: no vector ``log`` without SVML), the stress and forces (vectorised). Elements with
``J <= 0`` are counted; the neo-Hookean law gives them no force.

Precision: ``float64``; ``mixed`` (constants stored in float32, float64 arithmetic);
``float32`` (float32 constants and arithmetic, forces summed in float64).

Threads (rule in :mod:`reference_fem.explicit`: parallel from ``PARALLEL_MIN_ELEMENTS``
elements). Measured with ``springfem bench forces --tets 200000`` (210,912 tets, 7
interleaved rounds, 2 shared CPUs, load average 2.6-3.5): two threads against one, wall,
neo-Hookean 0.64x (float64), 0.73x (mixed), 0.68x (float32), linear 0.84x / 0.88x / 0.67x;
serial/parallel CPU time 0.82-0.97: the threads add 3-22 % work (not broken down
further) and lose the rest to the busy cores. At a quieter moment the issue measured
1.46x at 49k tets.

Examples
--------
>>> serial, _ = fem_kernel("linear", "float64")
>>> T, K = fem_layout(np.array([[0, 1, 2, 3]]), np.eye(4)[:, 1:], "float64")
>>> out = np.empty((4, 3))
>>> int(serial(np.eye(4)[:, 1:] * 1.1, T, K, 1, 1.0, 1.0, out)), bool(abs(out.sum(0)).max() < 1e-15)
(0, True)
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np

from springfem.blocks import BLOCK, block_drivers, block_layout, compile_named

_NO_VELOCITY = np.zeros((1, 3))  # the drivers pass velocities; the FEM forces need none
PRECISIONS = ("float64", "mixed", "float32")
_FLAGS = {"error_model": "numpy", "fastmath": {"contract"}}
#: Bytes per element the kernel reads: 10 constants and 4 int32 node ids.
NCOL = 10


def fem_layout(tets: np.ndarray, points: np.ndarray, precision: str):
    """Blocked connectivity ``(nb, 4 B)`` int32 and constants ``(nb, 10 B)`` at rest ``points``.

    Parameters
    ----------
    tets, points
        Mesh (``m >= 1`` tets with positive volume).
    precision
        Storage is float32 for ``mixed`` and ``float32``.

    Returns
    -------
    tuple of ndarray
    """
    x = np.asarray(points, dtype=float)[tets]
    E = x[:, 1:] - x[:, :1]
    Ginv = np.linalg.inv(E)  # columns: grad N_1..3
    V = np.linalg.det(E) / 6.0
    cols = np.concatenate([Ginv.transpose(0, 2, 1).reshape(-1, 9), V[:, None]], axis=1).T
    return block_layout(tets, cols, np.float64 if precision == "float64" else np.float32)


def _block_run(law: str, at):
    """The law's block loop ``run(lo, hi, x, w, T, K, m, mu, lam, out) -> n_inverted``
    (``w`` unused: the drivers of :func:`springfem.blocks.block_drivers` pass velocities).

    It captures only numbers (numba compiles them as constants: the law branch folds away),
    which keeps it disk-cacheable; it calls no helpers (written out: with helpers the loop
    was not vectorised, and numba's IR inlining of cached helpers gave a wrong build once).
    """
    B = BLOCK
    one, zero, two = at(1.0), at(0.0), at(2.0)
    neo = law == "neo-hookean"

    def run(lo, hi, x, w, T, K, m, mu_, lam_, out):
        X = np.empty(9 * B, at)
        S = np.empty(B, at)
        Jb = np.empty(B, at)
        Fo = np.empty(12 * B, at)
        mu, lam = at(mu_), at(lam_)
        bad = 0
        for blk in range(lo, hi):
            Tb = T[blk]
            Kb = K[blk]
            for j in range(B):
                i0 = Tb[j]
                for k in range(3):
                    i = Tb[(k + 1) * B + j]
                    for d in range(3):
                        X[(3 * k + d) * B + j] = at(x[i, d] - x[i0, d])
            if neo:
                for j in range(B):  # J, vectorised
                    ax, ay, az = X[j], X[B + j], X[2 * B + j]
                    bx, by, bz = X[3 * B + j], X[4 * B + j], X[5 * B + j]
                    cx, cy, cz = X[6 * B + j], X[7 * B + j], X[8 * B + j]
                    g1 = (at(Kb[j]), at(Kb[B + j]), at(Kb[2 * B + j]))
                    g2 = (at(Kb[3 * B + j]), at(Kb[4 * B + j]), at(Kb[5 * B + j]))
                    g3 = (at(Kb[6 * B + j]), at(Kb[7 * B + j]), at(Kb[8 * B + j]))
                    F = (  # F = sum_a (x_a - x_0) (x) grad N_a, row-major
                        ax * g1[0] + bx * g2[0] + cx * g3[0],
                        ax * g1[1] + bx * g2[1] + cx * g3[1],
                        ax * g1[2] + bx * g2[2] + cx * g3[2],
                        ay * g1[0] + by * g2[0] + cy * g3[0],
                        ay * g1[1] + by * g2[1] + cy * g3[1],
                        ay * g1[2] + by * g2[2] + cy * g3[2],
                        az * g1[0] + bz * g2[0] + cz * g3[0],
                        az * g1[1] + bz * g2[1] + cz * g3[1],
                        az * g1[2] + bz * g2[2] + cz * g3[2],
                    )
                    c0 = F[4] * F[8] - F[5] * F[7]  # first row of cof(F)
                    c = (c0, F[5] * F[6] - F[3] * F[8], F[3] * F[7] - F[4] * F[6])
                    S[j] = F[0] * c[0] + F[1] * c[1] + F[2] * c[2]
                for j in range(B):  # scalar: log
                    J = S[j]
                    S[j] = (lam * math.log(J) - mu) / J if J > zero else zero
            for j in range(B):  # stress and forces, vectorised
                ax, ay, az = X[j], X[B + j], X[2 * B + j]
                bx, by, bz = X[3 * B + j], X[4 * B + j], X[5 * B + j]
                cx, cy, cz = X[6 * B + j], X[7 * B + j], X[8 * B + j]
                g1 = (at(Kb[j]), at(Kb[B + j]), at(Kb[2 * B + j]))
                g2 = (at(Kb[3 * B + j]), at(Kb[4 * B + j]), at(Kb[5 * B + j]))
                g3 = (at(Kb[6 * B + j]), at(Kb[7 * B + j]), at(Kb[8 * B + j]))
                F = (  # F = sum_a (x_a - x_0) (x) grad N_a, row-major
                    ax * g1[0] + bx * g2[0] + cx * g3[0],
                    ax * g1[1] + bx * g2[1] + cx * g3[1],
                    ax * g1[2] + bx * g2[2] + cx * g3[2],
                    ay * g1[0] + by * g2[0] + cy * g3[0],
                    ay * g1[1] + by * g2[1] + cy * g3[1],
                    ay * g1[2] + by * g2[2] + cy * g3[2],
                    az * g1[0] + bz * g2[0] + cz * g3[0],
                    az * g1[1] + bz * g2[1] + cz * g3[1],
                    az * g1[2] + bz * g2[2] + cz * g3[2],
                )
                c0 = F[4] * F[8] - F[5] * F[7]  # first row of cof(F)
                c = (c0, F[5] * F[6] - F[3] * F[8], F[3] * F[7] - F[4] * F[6])
                V = at(Kb[9 * B + j])
                J = F[0] * c[0] + F[1] * c[1] + F[2] * c[2]
                Jb[j] = J
                if neo:
                    s = S[j]
                    V = V if J > zero else zero
                    P = (
                        mu * F[0] + s * c[0],
                        mu * F[1] + s * c[1],
                        mu * F[2] + s * c[2],
                        mu * F[3] + s * (F[2] * F[7] - F[1] * F[8]),
                        mu * F[4] + s * (F[0] * F[8] - F[2] * F[6]),
                        mu * F[5] + s * (F[1] * F[6] - F[0] * F[7]),
                        mu * F[6] + s * (F[1] * F[5] - F[2] * F[4]),
                        mu * F[7] + s * (F[2] * F[3] - F[0] * F[5]),
                        mu * F[8] + s * (F[0] * F[4] - F[1] * F[3]),
                    )
                else:
                    tr = lam * ((F[0] - one) + (F[4] - one) + (F[8] - one))
                    s01, s02, s12 = mu * (F[1] + F[3]), mu * (F[2] + F[6]), mu * (F[5] + F[7])
                    P = (
                        two * mu * (F[0] - one) + tr,
                        s01,
                        s02,
                        s01,
                        two * mu * (F[4] - one) + tr,
                        s12,
                        s02,
                        s12,
                        two * mu * (F[8] - one) + tr,
                    )
                for r in range(3):  # f_a = -V P grad N_a (a = 1..3), f_0 = -(f_1 + f_2 + f_3)
                    f1 = -V * (P[3 * r] * g1[0] + P[3 * r + 1] * g1[1] + P[3 * r + 2] * g1[2])
                    f2 = -V * (P[3 * r] * g2[0] + P[3 * r + 1] * g2[1] + P[3 * r + 2] * g2[2])
                    f3 = -V * (P[3 * r] * g3[0] + P[3 * r + 1] * g3[1] + P[3 * r + 2] * g3[2])
                    Fo[(3 + r) * B + j] = f1
                    Fo[(6 + r) * B + j] = f2
                    Fo[(9 + r) * B + j] = f3
                    Fo[r * B + j] = -(f1 + f2 + f3)
            nv = min(B, m - blk * B)
            for j in range(nv):
                bad += 1 if Jb[j] <= zero else 0
                for k in range(4):
                    i = Tb[k * B + j]
                    out[i, 0] += Fo[(3 * k) * B + j]
                    out[i, 1] += Fo[(3 * k + 1) * B + j]
                    out[i, 2] += Fo[(3 * k + 2) * B + j]
        return bad

    return compile_named(run, f"fem_run_{law.replace('-', '_')}_{np.dtype(at).name}")


@cache
def fem_kernel(law: str, precision: str = "float64"):
    """``(serial, parallel)`` force drivers of ``law`` at ``precision`` (compiled on first call).

    ``serial(x, T, K, m, mu, lam, out)`` and ``parallel(x, T, K, m, mu, lam, ptr, buf, out)``
    overwrite ``out (n, 3)`` with the internal forces and return the number of elements with
    ``J <= 0``.

    Parameters
    ----------
    law
        ``neo-hookean`` or ``linear``.
    precision
        ``float64``, ``mixed`` (float32 constants, float64 arithmetic) or ``float32``.

    Returns
    -------
    serial, parallel
        The two drivers.

    Raises
    ------
    ValueError
        For an unknown law or precision.
    """
    if law not in ("neo-hookean", "linear"):
        raise ValueError(f"law {law!r} is not one of neo-hookean, linear")
    if precision not in PRECISIONS:
        raise ValueError(f"precision {precision!r} is not one of {', '.join(PRECISIONS)}")
    run = _block_run(law, np.float32 if precision == "float32" else np.float64)
    serial_w, parallel_w = block_drivers(run)

    def serial(x, T, K, m, mu, lam, out):
        return serial_w(x, _NO_VELOCITY, T, K, m, mu, lam, out)

    def parallel(x, T, K, m, mu, lam, ptr, buf, out):
        return parallel_w(x, _NO_VELOCITY, T, K, m, mu, lam, ptr, buf, out)

    return serial, parallel
