"""LMS adaptive volume stiffness (eq. 2.81), as written and sign-consistent.

Examples
--------
>>> import numpy as np
>>> from springmodel.options import LMSOptions
>>> k0 = np.array([1.0, 1.0])
>>> V0, L0 = np.array([1.0, 1.0]), np.array([1.0, 1.0])
>>> V = np.array([0.9, 1.1])  # one element compressed, one expanded by 10%
>>> lms_update(k0, k0, V, V0, L0, L0, LMSOptions(mu=1.0, rule="spec")).round(12).tolist()
[0.9, 1.1]
>>> lms_update(k0, k0, V, V0, L0, L0, LMSOptions(mu=1.0, rule="abs")).round(12).tolist()
[1.1, 1.1]
"""

from __future__ import annotations

import numpy as np

from ..options import LMSOptions


def lms_update(
    k_s: np.ndarray,
    k_s0: np.ndarray,
    V: np.ndarray,
    V0: np.ndarray,
    sum_xi: np.ndarray,
    sum_xi0: np.ndarray,
    opts: LMSOptions,
) -> np.ndarray:
    """One adaptive-stiffness step (eq. 2.81), on ``k_s / k_s0``, clamped.

    ``rule = "spec"``: ``k/k0 += mu (dV/V0) (L/L0)`` as written (a compressed element gets
    softer); ``rule = "abs"``: ``k/k0 += mu |dV/V0| (L/L0)`` (stiffens with any volume
    error). The ratio is clamped to ``[k_min, k_max]``.

    Parameters
    ----------
    k_s, k_s0
        Current and calibrated volume constants ``(n_tets,)`` (N/m).
    V, V0
        Current and rest volumes ``(n_tets,)`` (m^3).
    sum_xi, sum_xi0
        Current and rest radial sums ``sum_j |xi_j|`` ``(n_tets,)`` (m).
    opts
        Learning rate ``mu``, clamp ``k_min``/``k_max`` and ``rule``.

    Returns
    -------
    ndarray
        New volume constants ``(n_tets,)`` (N/m).

    Raises
    ------
    ValueError
        If ``opts.rule`` is neither ``spec`` nor ``abs``.
    """
    ratio = np.asarray(k_s, float) / k_s0
    dv = (np.asarray(V, float) - V0) / V0
    if opts.rule == "spec":
        drive = dv
    elif opts.rule == "abs":
        drive = np.abs(dv)
    else:
        raise ValueError(f"LMS rule {opts.rule!r} is not one of spec, abs")
    ratio = ratio + opts.mu * drive * (np.asarray(sum_xi, float) / sum_xi0)  # eq. 2.81
    return np.clip(ratio, opts.k_min, opts.k_max) * k_s0
