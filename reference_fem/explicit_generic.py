"""Explicit P1 FEM forces of any tissue law, in numpy: the fallback of a law with no kernel.

A law registered in :mod:`springfem.materials.laws` without a compiled kernel in
:mod:`reference_fem.explicit_anisotropic` runs here: the same forces, ``f_a = -V P grad N_a``
with the law's own first Piola stress ``P = law.stress(F, frames)``, vectorised over the
elements (slower than a compiled kernel, the same numbers to round-off). The drivers take
the compiled kernels' arguments, so :class:`~reference_fem.explicit.ExplicitFem` calls both
alike; the active tension is read from the parameter vector
(:func:`~reference_fem.explicit_anisotropic.law_parameters`).

Examples
--------
>>> import numpy as np
>>> from springfem.materials.laws import Guccione
>>> law = Guccione(C=2.0, b_f=8.0, b_t=2.0, b_fs=4.0, kappa=50.0)
>>> X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> serial, _ = generic_kernel(law, np.array([[0, 1, 2, 3]]), X, np.eye(3)[None])
>>> out = np.empty((4, 3))
>>> prm = np.array([2.0, 8.0, 2.0, 4.0, 50.0, 0.0])
>>> int(serial(X * [1.1, 1.0, 1.0], None, None, 1, prm, out)), bool(out[1, 0] < 0)
(0, True)
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from springfem.materials.laws import TissueLaw
from springfem.materials.laws.kinematics import det


def generic_kernel(law: TissueLaw, tets: np.ndarray, points: np.ndarray, frames: np.ndarray):
    """``(serial, parallel)`` force drivers of ``law`` on a mesh (both serial, numpy).

    ``serial(x, T, K, m, prm, out)`` and ``parallel(x, T, K, m, prm, ptr, buf, out)``
    overwrite ``out (n, 3)`` with the internal forces and return the number of elements
    with ``J <= 0`` (which get no force); ``T`` and ``K`` are not used.

    Parameters
    ----------
    law
        The tissue law (its ``active_tension`` is replaced by ``prm``'s).
    tets, points
        Mesh at rest (positive volumes).
    frames
        ``(m, 3, 3)`` element frames (rows: fibre, sheet, normal).

    Returns
    -------
    serial, parallel
        The two drivers.
    """
    tets = np.asarray(tets)
    x0 = np.asarray(points, dtype=float)[tets]
    E = x0[:, 1:] - x0[:, :1]
    G = np.linalg.inv(E)  # columns: grad N_1..3
    V = np.linalg.det(E) / 6.0
    R = np.asarray(frames, dtype=float)
    active = len(law.keys()) + 1
    idx = tets.ravel()

    def serial(x, T, K, m, prm, out):
        tissue = replace(law, active_tension=float(prm[active]))
        X = np.asarray(x, dtype=float)[tets]
        F = np.einsum("kac,kad->kcd", X[:, 1:] - X[:, :1], G.transpose(0, 2, 1))
        bad = ~(det(F) > 0)
        P = np.where(bad[:, None, None], 0.0, tissue.stress(F, R))
        f = -V[:, None, None] * np.einsum("kij,kja->kai", P, G)  # f_a, a = 1..3
        fe = np.concatenate([-f.sum(axis=1, keepdims=True), f], axis=1).reshape(-1, 3)
        for d in range(3):
            out[:, d] = np.bincount(idx, weights=fe[:, d], minlength=out.shape[0])
        return int(bad.sum())

    def parallel(x, T, K, m, prm, ptr, buf, out):
        return serial(x, T, K, m, prm, out)

    return serial, parallel
