"""Rest data of the spring elements: intersection coefficients, rest measures, constants.

Everything here is computed once, in the rest configuration (DESIGN §3): the intersection
coefficients ``C^k`` (eqs. 2.22–2.25), their axis differences ``G`` (the fast-kernel
identity ``G[k,i,l] = C[k,i,2l] - C[k,i,2l+1] = grad N_i . zeta_l^0``), the rest lengths,
cosines, radial lengths and volumes, and the calibrated spring constants.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from . import calibration as cal
from .intersections import intersection_coefficients
from .options import SpringOptions


@dataclass
class SpringElements:
    """Per-element rest data of the spring model (``m`` elements).

    Attributes
    ----------
    tets
        ``(m, 4)`` node indices.
    C
        ``(m, 4, 6)`` intersection coefficients; column ``2l`` is the hit along ``+axis l``.
    G
        ``(m, 4, 3)`` axis gradients ``C[:, :, 2l] - C[:, :, 2l+1]``: ``zeta_l = sum_i G x_i``.
    zeta0, l0
        Rest axis vectors ``(m, 3, 3)`` and lengths ``(m, 3)`` (eq. 2.30).
    c0, alpha0
        Rest cosines and angles ``(m, 3)`` for the pairs (0,1), (0,2), (1,2) (eq. 2.32).
    xi0, r0, L0
        Rest radial vectors barycenter -> vertex ``(m, 4, 3)``, their lengths ``(m, 4)`` and
        sum ``(m,)`` (eq. 2.76).
    V0
        Rest volumes ``(m,)``.
    k_axial
        Axial constants ``(m, 3)`` (N/m).
    k_torsion
        Torsion constants ``(m, 3)`` in energy units (J): ``U = k/2 (c - c0)^2``. The force
        laws ``angle``/``cosine``/``cubic`` use :attr:`k_torsion_force`.
    k_volume, k_volume0
        Current and calibrated volume constants ``(m,)`` (N/m); LMS changes the first and
        clamps relative to the second.
    mismatch
        ``(m,)`` relative Frobenius mismatch of the effective matrix vs the material
        (``nan`` when no material was given).
    n_points
        Number of mesh nodes (size of the force array).
    """

    tets: np.ndarray
    C: np.ndarray
    G: np.ndarray
    zeta0: np.ndarray
    l0: np.ndarray
    c0: np.ndarray
    alpha0: np.ndarray
    xi0: np.ndarray
    r0: np.ndarray
    L0: np.ndarray
    V0: np.ndarray
    k_axial: np.ndarray
    k_torsion: np.ndarray
    k_volume: np.ndarray
    k_volume0: np.ndarray
    mismatch: np.ndarray
    n_points: int

    @property
    def n_elements(self) -> int:
        return int(self.tets.shape[0])

    @property
    def k_torsion_force(self) -> np.ndarray:
        """Force constants (N) of the non-energy torsion laws, ``(m, 3)``.

        The laws ``angle``/``cosine``/``cubic`` put ``-k dc zeta_hat_m`` on the end of axis
        ``l`` and ``-k dc zeta_hat_l`` on the end of axis ``m``; the energy law puts
        ``-k_E dc (...)/|zeta_l|`` there. ``k = 2 k_E / (l_l + l_m)`` makes the two do the same
        work on the pure shear of the pair (``dc = gamma_lm``), which is the mode the torsion
        springs are calibrated for; with equal axis lengths the two laws linearise alike.
        """
        pairs = cal.TORSION_PAIRS
        lsum = np.stack([self.l0[:, a] + self.l0[:, b] for a, b in pairs], axis=1)
        return 2.0 * self.k_torsion / lsum

    def with_volume_stiffness(self, k_volume: np.ndarray) -> SpringElements:
        """A copy sharing all arrays except ``k_volume`` (for LMS)."""
        return replace(self, k_volume=np.asarray(k_volume, dtype=float))


def axis_gradients_from(C: np.ndarray) -> np.ndarray:
    """``G[k, i, l] = C[k, i, 2l] - C[k, i, 2l+1]``, ``(m, 4, 3)``."""
    return C[:, :, 0::2] - C[:, :, 1::2]


def build_spring_elements(
    points: np.ndarray,
    tets: np.ndarray,
    frames: np.ndarray,
    options: SpringOptions | None = None,
    material: Any = None,
    C: np.ndarray | None = None,
) -> SpringElements:
    """Rest data and calibrated constants of every spring element.

    Parameters
    ----------
    points, tets, frames
        Mesh (rest configuration) and per-element orthonormal frames (rows = axes).
    options
        ``calibration`` picks ``analytic`` or ``nnls``; ``k_axial``, ``k_torsion``,
        ``k_volume`` (scalars) override the calibrated constants.
    material
        See :func:`springmodel.calibration.material_matrix`; may be ``None`` only when all
        three constants are given explicitly.
    C
        Precomputed intersection coefficients (otherwise ray-cast here).
    """
    options = options or SpringOptions()
    points = np.asarray(points, dtype=float)
    tets = np.ascontiguousarray(tets, dtype=np.int64)
    frames = np.asarray(frames, dtype=float)
    if C is None:
        C = intersection_coefficients(points, tets, frames)
    C = np.ascontiguousarray(C, dtype=float)
    G = np.ascontiguousarray(axis_gradients_from(C))
    geom = cal.rest_geometry(points, tets, G)
    l0 = np.linalg.norm(geom.zeta0, axis=-1)
    c0 = cal.rest_cosines(geom.zeta0)
    r0 = np.linalg.norm(geom.xi0, axis=-1)
    m = tets.shape[0]

    overrides = (options.k_axial, options.k_torsion, options.k_volume)
    if material is None and any(v is None for v in overrides):
        raise ValueError("a material is needed unless k_axial, k_torsion, k_volume are all given")
    calib = None
    if material is not None and any(v is None for v in overrides):
        calib = cal.calibrate(geom, frames, material, options.calibration)
        ka, kt, kv = calib.k_axial, calib.k_torsion, calib.k_volume
    else:
        ka = kt = kv = None
    if options.k_axial is not None:
        ka = np.full((m, 3), float(options.k_axial))
    if options.k_torsion is not None:
        kt = np.full((m, 3), float(options.k_torsion))
    if options.k_volume is not None:
        kv = np.full(m, float(options.k_volume))
    if calib is not None and all(v is None for v in overrides):
        mismatch = calib.mismatch
    elif material is not None:
        D = cal.effective_matrix(geom, ka, kt, kv)
        mismatch = cal.calibration_mismatch(D, cal.material_matrix(material, frames))
    else:
        mismatch = np.full(m, np.nan)

    return SpringElements(
        tets=tets,
        C=C,
        G=G,
        zeta0=geom.zeta0,
        l0=l0,
        c0=c0,
        alpha0=np.arccos(np.clip(c0, -1.0, 1.0)),
        xi0=geom.xi0,
        r0=r0,
        L0=r0.sum(axis=1),
        V0=geom.V0,
        k_axial=np.ascontiguousarray(ka, dtype=float),
        k_torsion=np.ascontiguousarray(kt, dtype=float),
        k_volume=np.array(kv, dtype=float),
        k_volume0=np.array(kv, dtype=float),
        mismatch=mismatch,
        n_points=int(points.shape[0]),
    )
