"""Rest data of the spring elements: intersection coefficients, rest measures, constants.

Everything here is computed once, in the rest configuration
(docs/spec.rst#c-k-is-computed-once-at-rest): the intersection
coefficients ``C^k`` (eqs. 2.22–2.25), their axis differences ``G`` (the fast-kernel
identity ``G[k,i,l] = C[k,i,2l] - C[k,i,2l+1] = grad N_i . zeta_l^0``), the rest lengths,
cosines, radial lengths and volumes, and the calibrated spring constants.

Examples
--------
>>> import numpy as np
>>> from springfem.scene import Material
>>> X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> e = build_spring_elements(X, np.array([[0, 1, 2, 3]]), np.eye(3)[None],
...                           material=Material("linear", 1.0e4, 0.3))
>>> e.l0.tolist(), round(float(e.V0[0]), 12)  # axes through the barycenter, V = 1/6
([[0.5, 0.5, 0.5]], 0.166666666667)
>>> round(float(e.k_axial[0, 0]), 1)  # 2 mu V0 / l0^2 with mu = E / (2 (1 + nu))
5128.2
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from springfem.materials import material_matrix

from .calibration import calibrate, constants_of
from .intersections import intersection_coefficients
from .options import SpringOptions
from .rest_geometry import TORSION_PAIRS, rest_cosines, rest_geometry
from .tangent import element_mismatch


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
        ``(m,)`` relative mismatch of the small-strain tangent of the switched-on parts vs
        the material, in the Frobenius norm of the fourth-order tensor (= Mandel Frobenius,
        :mod:`springmodel.tangent`); ``nan`` when no material was given.
    n_points
        Number of mesh nodes (size of the force array).
    k_axis_volume
        Axis-volume stiffness ``kappa`` ``(m,)`` (Pa): energy ``V0 U(J)``.
    k_coupling
        Poisson-coupling constants ``(m, 3)`` (J) for the pairs (0,1), (0,2), (1,2).
    det0
        Rest triple products ``det[zeta_1^0 zeta_2^0 zeta_3^0]`` ``(m,)``: ``J = det / det0``.
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
    k_axis_volume: np.ndarray | None = None
    k_coupling: np.ndarray | None = None
    det0: np.ndarray | None = None

    def __post_init__(self):
        m = self.tets.shape[0]
        if self.k_axis_volume is None:
            self.k_axis_volume = np.zeros(m)
        if self.k_coupling is None:
            self.k_coupling = np.zeros((m, 3))
        if self.det0 is None:
            self.det0 = np.linalg.det(self.zeta0.transpose(0, 2, 1))

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
        pairs = TORSION_PAIRS
        lsum = np.stack([self.l0[:, a] + self.l0[:, b] for a, b in pairs], axis=1)
        return 2.0 * self.k_torsion / lsum

    def with_volume_stiffness(self, k_volume: np.ndarray) -> SpringElements:
        """A copy sharing all arrays except ``k_volume`` (for LMS)."""
        return replace(self, k_volume=np.asarray(k_volume, dtype=float))


def axis_gradients_from(C: np.ndarray) -> np.ndarray:
    """``G[k, i, l] = C[k, i, 2l] - C[k, i, 2l+1]``, ``(m, 4, 3)``.

    Parameters
    ----------
    C
        Intersection coefficients ``(m, 4, 6)``.

    Returns
    -------
    ndarray
        Axis gradients ``(m, 4, 3)``.
    """
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
        See :func:`springfem.materials.material_matrix`; may be ``None`` only when all
        three constants are given explicitly.
    C
        Precomputed intersection coefficients (otherwise ray-cast here).

    Returns
    -------
    SpringElements
        Rest data and constants of the ``m`` elements.

    Raises
    ------
    ValueError
        Without a material unless ``k_axial``, ``k_torsion`` and ``k_volume`` are all given.
    """
    options = options or SpringOptions()
    points = np.asarray(points, dtype=float)
    tets = np.ascontiguousarray(tets, dtype=np.int64)
    frames = np.asarray(frames, dtype=float)
    if C is None:
        C = intersection_coefficients(points, tets, frames)
    C = np.ascontiguousarray(C, dtype=float)
    G = np.ascontiguousarray(axis_gradients_from(C))
    geom = rest_geometry(points, tets, G)
    l0 = np.linalg.norm(geom.zeta0, axis=-1)
    c0 = rest_cosines(geom.zeta0)
    r0 = np.linalg.norm(geom.xi0, axis=-1)
    m = tets.shape[0]

    overrides = (options.k_axial, options.k_torsion, options.k_volume)
    if material is None and any(v is None for v in overrides):
        raise ValueError("a material is needed unless k_axial, k_torsion, k_volume are all given")
    calib = None
    kj, kc = np.zeros(m), np.zeros((m, 3))
    if material is not None and any(v is None for v in overrides):
        calib = calibrate(geom, frames, material, options.calibration, options)
        ka, kt, kv = calib.k_axial, calib.k_torsion, calib.k_volume
        kj, kc = calib.k_axis_volume, calib.k_coupling
    else:
        ka = kt = kv = None
    if options.k_axial is not None:
        ka = np.full((m, 3), float(options.k_axial))
    if options.k_torsion is not None:
        kt = np.full((m, 3), float(options.k_torsion))
    if options.k_volume is not None:  # the volume constant of whichever volume part is on
        kv = np.full(m, float(options.k_volume))
        if options.axis_volume:
            kj = kv.copy()
    if calib is not None and all(v is None for v in overrides):
        mismatch = calib.mismatch
    elif material is not None:
        k = {"k_axial": ka, "k_torsion": kt, "k_volume": kv, "k_axis_volume": kj}
        k["k_coupling"] = kc
        C_global = material_matrix(material, frames)
        mismatch = element_mismatch(geom, constants_of(k, options), C_global, options)
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
        k_axis_volume=np.ascontiguousarray(kj, dtype=float),
        k_coupling=np.ascontiguousarray(kc, dtype=float),
    )
