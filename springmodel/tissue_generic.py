"""The tissue element's energy of any registered law, derived from the law itself.

The tissue element (:mod:`springmodel.tissue_element`) measures the Cauchy–Green tensor in
the element frame, ``m = (C'_00, C'_11, C'_22, C'_01, C'_02, C'_12)``. A law of the table
(:mod:`springfem.materials.laws`) without terms written out for the compiled pass gets its
energy and derivatives in the measures from its own ``local`` (:func:`law_derivatives`):
the element is then P1 of the law, at the cost of numpy over a compiled loop.

Examples
--------
>>> import numpy as np
>>> from springfem.materials.laws import Guccione
>>> m = np.array([[1.21, 1.0, 1.0, 0.0, 0.0, 0.0]])  # a 10 % stretch along the fibre
>>> W, dW, _ = law_derivatives(m, Guccione(C=2.0, b_f=8.0, b_t=2.0, b_fs=4.0), False)
>>> E = 0.105  # E_ff = (1.21 - 1) / 2; W = C/2 (exp(b_f E^2) - 1)
>>> e = np.exp(8.0 * E**2)  # dW/dm_ff = S_ff / 2 = C e b_f E / 2
>>> bool(np.isclose(W[0], e - 1.0)), bool(np.isclose(dW[0, 0], 8.0 * E * e))
(True, True)
"""

from __future__ import annotations

import numpy as np

from springfem.materials.laws import TissueLaw

from .rest_geometry import TORSION_PAIRS

#: ``dC'/dm_a`` of each measure (a diagonal entry, then a symmetric torsion pair).
_DC = np.zeros((6, 3, 3))
for _a in range(3):
    _DC[_a, _a, _a] = 1.0
for _p, (_l, _m) in enumerate(TORSION_PAIRS):
    _DC[3 + _p, _l, _m] = _DC[3 + _p, _m, _l] = 1.0


def law_derivatives(m: np.ndarray, law: TissueLaw, hessian: bool):
    """``W``, ``dW/dm`` and ``d2W/dm2`` per unit volume of a law from its own ``local``.

    ``C'`` is assembled from the measures and factored, ``F' = L^T`` with ``C' = L L^T``
    (any ``F'`` with ``F'^T F' = C'`` serves: a law of ``C`` alone); then ``S = F'^-1 P'``,
    ``dS/dE = F'^-1 (A' - I (x) S) F'^-T`` and, with ``dW/dC = S/2``,
    ``dW/dm_a = S : dC/dm_a / 2`` and ``d2W/dm_a dm_b = dC/dm_a : dS/dE : dC/dm_b / 4``.
    NaN where ``C'`` is not positive definite.

    Parameters
    ----------
    m
        Measures ``(k, 6)`` (:func:`frame_measures`).
    law
        The passive law without its penalty.
    hessian
        Also return ``d2W/dm2`` (else None).

    Returns
    -------
    W, dW, ddW
        ``(k,)``, ``(k, 6)``, ``(k, 6, 6)`` or None.
    """
    c00, c11, c22, c01, c02, c12 = (m[:, i] for i in range(6))
    F = np.zeros((m.shape[0], 3, 3))
    with np.errstate(invalid="ignore", divide="ignore"):
        F[:, 0, 0] = np.sqrt(c00)
        F[:, 0, 1], F[:, 0, 2] = c01 / F[:, 0, 0], c02 / F[:, 0, 0]
        F[:, 1, 1] = np.sqrt(c11 - F[:, 0, 1] ** 2)
        F[:, 1, 2] = (c12 - F[:, 0, 2] * F[:, 0, 1]) / F[:, 1, 1]
        F[:, 2, 2] = np.sqrt(c22 - F[:, 0, 2] ** 2 - F[:, 1, 2] ** 2)
        W, P, A = law.local(F, hessian)
        Fi = np.linalg.inv(np.where(np.isfinite(F), F, np.nan))
        S = np.einsum("kMi,kiJ->kMJ", Fi, P)
        dW = 0.5 * np.einsum("aIJ,kIJ->ka", _DC, S)
        if not hessian:
            return W, dW, None
        A = A - np.einsum("ik,nJL->niJkL", np.eye(3), S)
        CC = np.einsum("nMi,niJkL,nNk->nMJNL", Fi, A, Fi, optimize=True)
    return W, dW, 0.25 * np.einsum("aIJ,kIJKL,bKL->kab", _DC, CC, _DC, optimize=True)
