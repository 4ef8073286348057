"""``nnls`` calibration: per-element bounded least squares of the tangent against the material.

Each element's small-strain tangent is linear in its constants, ``A = sum_b k_b B_b``
(:mod:`springmodel.tangent`), so the fit ``min ||A(k) - C||`` (the mismatch norm: Frobenius
of the fourth-order tensor, = Mandel Frobenius) is a small bounded least-squares problem
(81 x nb, scipy's BVLS, columns scaled to unit norm).

**Positive definite by construction.** Plain non-negative least squares at ``nu >= 0.45``
puts the shear into the (large) barycentric volume constant and zeroes two of the three
torsion constants in every six-split element: a zero-energy mode per element. Here the
axial and torsion constants are bounded below by :data:`FLOOR` times the analytic ones
(``(C_ll - b) V / l_l^2`` and ``G_lm V``). The six axial + torsion measures span the six
strains (the axes are orthonormal), so any element that meets the bounds has a positive
definite small-strain stiffness whatever the volume constant; the analytic constants are
feasible, so the fit is never worse than ``analytic``. A material whose analytic axial or
torsion constant is not positive (``C_ll <= b``) is refused with an :class:`InputError`.
Couplings are free in sign; volume constants are non-negative.

Elements with the same rest geometry and material matrix (structured meshes: a handful of
shapes) are solved once.

Examples
--------
>>> FLOOR
0.1
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.optimize import lsq_linear

from springfem.errors import InputError
from springfem.materials import to_mandel

from .tangent import basis_names, tangent_basis

#: Lower bound of the axial and torsion constants, as a fraction of the analytic ones.
FLOOR = 0.1


def _unique_rows(A: np.ndarray, decimals: int = 10) -> tuple[np.ndarray, np.ndarray]:
    """Indices of representative rows and the inverse map, up to relative rounding."""
    scale = np.abs(A).max(axis=0)
    scale[scale == 0] = 1.0
    key = np.round(A / scale, decimals)
    proj = key @ np.random.default_rng(12345).standard_normal((A.shape[1], 2))
    _, first, inverse = np.unique(proj, axis=0, return_index=True, return_inverse=True)
    return first, inverse.ravel()


def nnls_fit(
    geometry: Any,
    C_global: np.ndarray,
    analytic: tuple[np.ndarray, np.ndarray],
    options: Any,
) -> np.ndarray:
    """Bounded least-squares constants ``(m, nb)`` in the order of ``basis_names``.

    Parameters
    ----------
    geometry
        Rest geometry (``zeta0``, ``xi0``, ``V0``).
    C_global
        ``(m, 6, 6)`` material matrices in the global frame.
    analytic
        The analytic axial and torsion constants, ``(m, 3)`` each
        (:func:`springmodel.calibration.analytic_constants`): the floors are
        :data:`FLOOR` times them.
    options
        :class:`~springmodel.options.SpringOptions` (which parts are on, their laws).

    Raises
    ------
    InputError
        The analytic axial or torsion constants are not positive (no positive floor).
    """
    from springfem.materials import voigt_to_tensor

    m = geometry.V0.shape[0]
    names = basis_names(options.torsion, options.volume, options.coupling)
    ka, kt = analytic
    lower = np.full((m, len(names)), 0.0)
    lower[:, :3] = FLOOR * ka
    if options.torsion != "off":
        lower[:, 3:6] = FLOOR * kt
    if not np.all(lower[:, : 6 if options.torsion != "off" else 3] > 0):
        raise InputError(
            "calibration nnls: the material has a non-positive axial or shear stiffness in "
            "an element frame (C_ll <= mean off-diagonal); no positive-definite fit exists"
        )
    lower[:, [i for i, n in enumerate(names) if n.startswith("coupling")]] = -np.inf
    Ct = voigt_to_tensor(np.broadcast_to(np.asarray(C_global, float), (m, 6, 6))).reshape(m, 81)
    Cm = to_mandel(np.broadcast_to(np.asarray(C_global, float), (m, 6, 6))).reshape(m, 36)
    features = np.concatenate(
        [geometry.zeta0.reshape(m, 9), geometry.xi0.reshape(m, 12), geometry.V0[:, None], Cm],
        axis=1,
    )
    first, inverse = _unique_rows(features)
    xs = np.empty((first.size, len(names)))
    for start in range(0, first.size, 4096):  # bounded memory on unstructured meshes
        rep = first[start : start + 4096]
        sub = type(geometry)(*(np.asarray(f)[rep] for f in geometry))
        B = tangent_basis(sub, options.torsion, options.volume, options.coupling)
        A = B.reshape(rep.size, len(names), 81).transpose(0, 2, 1)  # (r, 81, nb)
        scale = np.linalg.norm(A, axis=1)
        scale[scale == 0] = 1.0
        for u, k in enumerate(rep):  # the optimum is invariant under column scaling
            lo = lower[k] * scale[u]
            fit = lsq_linear(A[u] / scale[u], Ct[k], bounds=(lo, np.inf), method="bvls")
            xs[start + u] = np.maximum(fit.x, lo) / scale[u]
    return xs[inverse]
