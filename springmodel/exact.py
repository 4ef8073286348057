"""Closed-form ``exact`` calibration: the spring element equals the material's P1 element.

The axis vectors are parallel to the element's frame axes on every tet
(docs/theory.rst#axis-vectors-are-parallel-to-the-frame), so in
the element frame the axial strains are ``s_l = eps_ll``, the energy-torsion measures are
``dc_lm = gamma_lm`` and the axis-volume measure is ``J - 1 = tr eps``. The small-strain
element energy is then ``V/2 g^T D g`` with (frame-local Voigt, normal block ``N``, shears
``G``)::

    N_ll = k_l l_l^2 / V + kappa            N_lm = c_lm / V + kappa        D_shear = k_lm / V

and matching the material's frame-local matrix ``C`` gives, for any tet shape::

    kappa = max(mean(C_01, C_02, C_12), 0)             axis-volume stiffness (Pa)
    k_l   = (C_ll - kappa) V / l_l^2                    axial (N/m)
    c_lm  = (C_lm - kappa) V                            Poisson coupling (J)
    k_lm  = G_lm V                                      energy torsion (J)

Isotropic material: ``kappa = lambda``, ``k_l = 2 mu V / l_l^2``, ``c_lm = 0``, ``k_lm = mu V``
(no coupling needed). Transversely isotropic / orthotropic: the off-diagonals differ and the
couplings take the differences from ``kappa``; the axis-volume term is kept so that the volume
is held at finite strain (coupling alone lets it drift, docs/calibration.rst#exact-calibration).
Exactness needs
``volume = "axes"``, ``torsion = "energy"`` (or ``"shear"``: the same small-strain tangent)
and (anisotropic) ``coupling = true``; with other
parts the same formulas are used (barycentric volume: ``k_s = kappa V / rho^2`` as in the
``analytic`` calibration; no volume: ``kappa = 0``) and the mismatch they leave is reported
(:mod:`springmodel.tangent`). A negative ``C_ll - kappa`` is clipped to zero.

Examples
--------
>>> import numpy as np
>>> from springfem.materials import isotropic_matrix
>>> from springmodel.rest_geometry import RestGeometry
>>> g = RestGeometry(np.eye(3)[None] * 0.5, np.zeros((1, 4, 3)), np.array([1.0]))
>>> k = exact_constants(g, isotropic_matrix(1.0, 0.25)[None], "axes", coupling=True)
>>> round(float(k["k_axis_volume"][0]), 12), bool(np.abs(k["k_coupling"]).max() < 1e-15)
(0.4, True)
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .rest_geometry import TORSION_PAIRS, TORSION_VOIGT, radial_tensor


def exact_constants(
    geometry: Any, C_local: np.ndarray, volume: Any, coupling: bool
) -> dict[str, np.ndarray]:
    """Constants of the ``exact`` calibration (module docstring).

    Parameters
    ----------
    geometry
        Rest geometry (``zeta0``, ``xi0``, ``V0``).
    C_local
        ``(m, 6, 6)`` material matrices in the element frames (fiber = axis 0).
    volume
        The options' ``volume``: ``"axes"``, ``True`` (barycentric) or ``False``.
    coupling
        Poisson-coupling springs on.

    Returns
    -------
    dict
        ``k_axial (m,3)``, ``k_torsion (m,3)``, ``k_volume (m,)`` (barycentric),
        ``k_axis_volume (m,)`` (Pa), ``k_coupling (m,3)``.
    """
    V = geometry.V0
    m = V.shape[0]
    l0 = np.linalg.norm(geometry.zeta0, axis=-1)
    off = np.stack([C_local[:, a, b] for a, b in TORSION_PAIRS], axis=1)  # (m, 3)
    kappa = np.maximum(off.mean(axis=1), 0.0) if volume is not False else np.zeros(m)
    diag = C_local[:, [0, 1, 2], [0, 1, 2]]
    out = {
        "k_axial": np.maximum(diag - kappa[:, None], 0.0) * V[:, None] / l0**2,
        "k_torsion": C_local[:, list(TORSION_VOIGT), list(TORSION_VOIGT)] * V[:, None],
        "k_volume": np.zeros(m),
        "k_axis_volume": kappa if volume == "axes" else np.zeros(m),
        "k_coupling": (off - kappa[:, None]) * V[:, None] if coupling else np.zeros((m, 3)),
    }
    if volume is True:
        rho = np.trace(radial_tensor(geometry.xi0), axis1=1, axis2=2) / 3.0
        out["k_volume"] = kappa * V / rho**2
    return out
