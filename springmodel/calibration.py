"""Material parameters -> spring constants (DESIGN §4).

Under the affine deformation of a linear tet (gradient ``F``) every axis vector and every
radial vector maps exactly, ``zeta_l = F zeta_l^0`` and ``xi_j = F xi_j^0``, so the energy of
a spring element is a function of ``F`` alone (:func:`element_energy_from_F`)::

    W_k(F) = sum_l k_l/2 (|F zeta_l^0| - l_l^0)^2                 axial springs (2.35)
           + sum_lm k_lm/2 (c_lm(F) - c_lm^0)^2                     torsion (energy form)
           + k_s/2 (sum_j |F xi_j^0| - L^0)^2                       volume springs (2.76)

Linearising at ``F = I`` every term is ``k_a/2 (a_a : eps)^2`` with a symmetric "strain
tensor" ``a_a`` of the rest geometry (:func:`spring_strain_tensors`):

* axial ``a_l = zeta_l zeta_l^T / l_l`` (``d|zeta_l| = zeta_hat . eps . zeta``),
* torsion ``a_lm = 2 sym(zh_l zh_m^T) - c0 (zh_l zh_l^T + zh_m zh_m^T)`` (``dc_lm = a_lm : eps``),
* volume ``R = sum_j xi_j xi_j^T / |xi_j|`` (``dL = R : eps``),

so the element is a P1 element with the effective Voigt matrix
``D_k = (1/V) sum_a k_a v_a v_a^T`` (:func:`effective_matrix`), ``v_a`` the Voigt vector of
``a_a``. Calibration chooses the seven constants so that ``D_k`` matches the material
matrix ``C``:

``analytic`` (orthonormal axes, ``c0 = 0``). In the element frame the axial springs carry
the normal strains, the torsion springs the three shears (``dc_lm = gamma_lm``), and the
volume spring ``rho tr(eps)`` when ``R = rho I``. Writing the frame-local normal block of
``C`` as ``diag(a) + b 1 1^T`` and the shear block as ``diag(G_lm)``::

    b    = mean of the three off-diagonal normal entries  (= lambda if isotropic)
    k_s  = b V / rho^2,             rho = tr(R) / 3 (mean eigenvalue of R)
    k_l  = (C_ll - b) V / l_l^2     (= 2 mu V / l_l^2 if isotropic)
    k_lm = G_lm V                   (= mu V if isotropic)

This is exact for isotropic material when ``R = rho I`` (e.g. a regular tet), for any
``nu``. For transversely isotropic material the normal block has two different
off-diagonals (``C_01 = C_02 != C_12``), which one volume spring cannot represent: ``b``
is their least-squares value. Where ``R`` is anisotropic (any non-regular tet) the volume
spring also couples normal and shear strains; no constants remove that, and the remaining
mismatch is reported, not hidden. Negative ``C_ll - b`` is clipped to zero.

``analytic-lsq``: the same, but ``k_s = b V tr(R)^2 / ||R||_F^4``, the least-squares fit of
the volume term ``k_s R R`` to ``b V I I``; equal to the above when ``R = rho I`` and about
half of it on the six-tet split, where it cuts the mismatch from 0.58 to 0.41 (nu = 0.3).

``nnls``: per element, bounded least squares of the tangent against ``C`` with axial and
torsion constants kept positive, so that every element is positive definite
(:mod:`springmodel.nnls`). ``exact``: closed-form constants that reproduce the P1 element on
any tet with the axis-volume spring, energy torsion and (anisotropic) Poisson coupling
(:mod:`springmodel.exact`).

The mismatch an element's constants leave (:attr:`Calibrated.mismatch`) is measured on the
small-strain tangent of the parts that are switched on, including the non-symmetric part of
the cosine-type torsion laws, as ``||A_k - C|| / ||C||`` in the Frobenius norm of the
fourth-order tensor (= the Frobenius norm of the Mandel matrices, the "Mandel Frobenius
norm"; :mod:`springmodel.tangent`). :func:`calibration_mismatch` is the same norm on Voigt
matrices of the energy forms.

Examples
--------
>>> import numpy as np
>>> rest_cosines(np.eye(3)[None]).tolist()  # orthonormal axes: every c_lm^0 = 0
[[0.0, 0.0, 0.0]]
"""

from __future__ import annotations

from typing import Any, Literal, NamedTuple

import numpy as np

from springfem.materials import (
    is_transverse,
    material_matrix,
    to_mandel,
    voigt_vector,
)

# Voigt order xx, yy, zz, yz, xz, xy (engineering shear strains).
# Torsion spring pairs (l, m) and the Voigt index of the shear they carry.
TORSION_PAIRS = ((0, 1), (0, 2), (1, 2))
TORSION_VOIGT = (5, 4, 3)


class RestGeometry(NamedTuple):
    """What calibration needs from an element's rest state.

    Attributes
    ----------
    zeta0
        Rest axis vectors, ``(m, 3, 3)``, ``zeta0[k, l]`` for axis ``l``.
    xi0
        Rest radial vectors barycenter -> vertex, ``(m, 4, 3)``.
    V0
        Rest volumes, ``(m,)``.
    """

    zeta0: np.ndarray
    xi0: np.ndarray
    V0: np.ndarray


class Calibrated(NamedTuple):
    """Spring constants of every element and how well they reproduce the material.

    Attributes
    ----------
    k_axial, k_torsion, k_volume, mismatch
        ``(m, 3)`` N/m, ``(m, 3)`` J, ``(m,)`` N/m, ``(m,)`` Mandel ``||A_k - C|| / ||C||``.
    k_axis_volume, k_coupling
        ``(m,)`` Pa and ``(m, 3)`` J, or None when those parts are off.
    """

    k_axial: np.ndarray  # (m, 3)  N/m
    k_torsion: np.ndarray  # (m, 3) J (energy units: U = k/2 (c - c0)^2)
    k_volume: np.ndarray  # (m,)   N/m  barycentric volume springs
    mismatch: np.ndarray  # (m,)   relative Frobenius (Mandel) ||A_k - C|| / ||C||
    k_axis_volume: np.ndarray | None = None  # (m,) Pa  axis-volume spring V0 U(J)
    k_coupling: np.ndarray | None = None  # (m, 3) J  Poisson coupling c_lm s_l s_m


# --------------------------------------------------------------------------- tensors


# --------------------------------------------------------------------------- spring element


def rest_geometry(points: np.ndarray, tets: np.ndarray, G: np.ndarray) -> RestGeometry:
    """Rest axis vectors (``zeta_l = sum_i G[k,i,l] x_i``), radial vectors and volumes."""
    X = np.asarray(points, float)[tets]
    zeta0 = G.transpose(0, 2, 1) @ X
    xi0 = X - X.mean(axis=1, keepdims=True)
    e = X[:, 1:] - X[:, :1]
    V0 = np.linalg.det(e) / 6.0
    return RestGeometry(zeta0, xi0, V0)


def rest_cosines(zeta0: np.ndarray) -> np.ndarray:
    """Rest cosines ``c_lm^0`` for the pairs (0,1), (0,2), (1,2), ``(m, 3)``."""
    u = zeta0 / np.linalg.norm(zeta0, axis=-1, keepdims=True)
    return np.stack([(u[:, a] * u[:, b]).sum(-1) for a, b in TORSION_PAIRS], axis=1)


def radial_tensor(xi0: np.ndarray) -> np.ndarray:
    """``R = sum_j xi_j xi_j^T / |xi_j|``, ``(m, 3, 3)``: ``dL = R : eps`` at small strain."""
    r = np.linalg.norm(xi0, axis=-1)
    return (xi0 / r[..., None]).transpose(0, 2, 1) @ xi0


def spring_strain_tensors(zeta0: np.ndarray, xi0: np.ndarray) -> np.ndarray:
    """Tensors ``a_a`` with ``d(measure_a) = a_a : eps`` at rest, ``(m, 7, 3, 3)``.

    Order: axial 0, 1, 2 (measure ``|zeta_l|``), torsion (0,1), (0,2), (1,2) (measure
    ``c_lm``), volume (measure ``L = sum_j |xi_j|``).
    """
    m = zeta0.shape[0]
    l0 = np.linalg.norm(zeta0, axis=-1)
    u = zeta0 / l0[..., None]
    c0 = rest_cosines(zeta0)
    a = np.empty((m, 7, 3, 3))
    a[:, :3] = u[..., :, None] * zeta0[..., None, :]
    for p, (l, n) in enumerate(TORSION_PAIRS):
        ul, un = u[:, l, :, None], u[:, n, :, None]
        outer = ul * un.transpose(0, 2, 1)
        a[:, 3 + p] = (outer + outer.transpose(0, 2, 1)) - c0[:, p, None, None] * (
            ul * ul.transpose(0, 2, 1) + un * un.transpose(0, 2, 1)
        )
    a[:, 6] = radial_tensor(xi0)
    return a


def _stack_constants(k_axial, k_torsion, k_volume, m: int) -> np.ndarray:
    k = np.empty((m, 7))
    k[:, :3] = np.broadcast_to(np.asarray(k_axial, float), (m, 3))
    k[:, 3:6] = np.broadcast_to(np.asarray(k_torsion, float), (m, 3))
    k[:, 6] = np.broadcast_to(np.asarray(k_volume, float), (m,))
    return k


def effective_matrix(geometry: Any, k_axial, k_torsion, k_volume) -> np.ndarray:
    """Small-strain effective Voigt matrix ``D_k`` of the spring elements, ``(m, 6, 6)``.

    ``D_k = (1/V) sum_a k_a v_a v_a^T`` with ``v_a`` the Voigt vectors of
    :func:`spring_strain_tensors`: the element energy is ``V/2 g^T D_k g`` to second order in
    the engineering strain ``g``. Valid for the energy forms (axial linear/polynomial,
    torsion ``energy``, volume ``gradient``); the torsion force laws ``angle``/``cosine``/
    ``cubic`` linearise to non-symmetric stiffnesses that share its symmetric shear part only
    on the pure-shear modes.

    Parameters
    ----------
    geometry
        Anything with ``zeta0 (m,3,3)``, ``xi0 (m,4,3)``, ``V0 (m,)`` (e.g.
        :class:`RestGeometry` or :class:`~springmodel.elements.SpringElements`).
    k_axial, k_torsion, k_volume
        ``(m, 3)``, ``(m, 3)``, ``(m,)`` or broadcastable; torsion in energy units.

    Returns
    -------
    ndarray
        ``D_k`` ``(m, 6, 6)`` (Pa), engineering-shear Voigt.
    """
    v = voigt_vector(spring_strain_tensors(geometry.zeta0, geometry.xi0))  # (m, 7, 6)
    k = _stack_constants(k_axial, k_torsion, k_volume, v.shape[0])
    return (v * (k / geometry.V0[:, None])[..., None]).transpose(0, 2, 1) @ v


def calibration_mismatch(
    D: np.ndarray, C: np.ndarray, norm: Literal["mandel", "voigt"] = "mandel"
) -> np.ndarray:
    """Relative Frobenius mismatch ``||D - C|| / ||C||`` of Voigt matrices, ``(m,)``.

    Parameters
    ----------
    D, C
        ``(m, 6, 6)`` effective and material Voigt matrices (``C`` may be ``(6, 6)``).
    norm
        ``mandel``: of the fourth-order tensors (frame-independent); ``voigt``: of the
        Voigt matrices as they are (engineering shear; depends on the axes' orientation).

    Returns
    -------
    ndarray
    """
    if norm == "mandel":
        Dm, Cm = to_mandel(np.asarray(D, float)), to_mandel(np.asarray(C, float))
    elif norm == "voigt":
        Dm, Cm = np.asarray(D, float), np.asarray(C, float)
    else:
        raise ValueError(f"norm {norm!r} is not one of mandel, voigt")
    Cm = np.broadcast_to(Cm, Dm.shape)
    return np.linalg.norm(Dm - Cm, axis=(-2, -1)) / np.linalg.norm(Cm, axis=(-2, -1))


def analytic_constants(
    geometry: Any, C_local: np.ndarray, volume: Literal["mean", "lsq"] = "mean"
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Analytic calibration (module docstring) from the frame-local Voigt matrix.

    Parameters
    ----------
    geometry
        Rest geometry (``zeta0``, ``xi0``, ``V0``); axes assumed orthonormal (``c0 = 0``).
    C_local
        ``(m, 6, 6)`` material matrix in each element's frame (fiber = axis 0).
    volume
        ``mean``: ``k_s = b V / rho^2`` with ``rho = tr(R)/3`` (DESIGN §4). ``lsq``: the
        least-squares fit of ``k_s R R`` to ``b V I I`` (Frobenius),
        ``k_s = b V tr(R)^2 / ||R||^4``; both are exact when ``R = rho I``, ``lsq`` is about
        half the ``mean`` value on the six-tet split and leaves a smaller mismatch there.

    Returns
    -------
    k_axial, k_torsion, k_volume
        ``(m, 3)`` (N/m), ``(m, 3)`` (J), ``(m,)`` (N/m).

    Raises
    ------
    ValueError
        If ``volume`` is neither ``mean`` nor ``lsq``.
    """
    V = geometry.V0
    l0 = np.linalg.norm(geometry.zeta0, axis=-1)
    R = radial_tensor(geometry.xi0)
    trace = np.trace(R, axis1=1, axis2=2)
    b = (C_local[:, 0, 1] + C_local[:, 0, 2] + C_local[:, 1, 2]) / 3.0
    b = np.maximum(b, 0.0)
    diag = C_local[:, [0, 1, 2], [0, 1, 2]]
    k_axial = np.maximum(diag - b[:, None], 0.0) * V[:, None] / l0**2
    k_torsion = C_local[:, list(TORSION_VOIGT), list(TORSION_VOIGT)] * V[:, None]
    if volume == "mean":
        k_volume = b * V / (trace / 3.0) ** 2
    elif volume == "lsq":
        k_volume = b * V * trace**2 / np.sum(R * R, axis=(1, 2)) ** 2
    else:
        raise ValueError(f"volume {volume!r} is not one of mean, lsq")
    return k_axial, k_torsion, k_volume


def calibrate(
    geometry: Any,
    frames: np.ndarray,
    material: Any,
    method: Literal["analytic", "analytic-lsq", "nnls", "exact"] = "analytic",
    options: Any = None,
) -> Calibrated:
    """Spring constants of every element, and the mismatch they leave.

    Parameters
    ----------
    geometry
        Rest geometry (``zeta0``, ``xi0``, ``V0``).
    frames
        ``(m, 3, 3)`` element frames (rows = axes).
    material
        See :func:`material_matrix`.
    method
        ``analytic`` (``k_s`` from the mean eigenvalue of ``R``), ``analytic-lsq`` (``k_s``
        by least squares, see :func:`analytic_constants`), ``nnls`` (bounded least squares,
        :mod:`springmodel.nnls`) or ``exact`` (:mod:`springmodel.exact`). With
        ``volume = "axes"`` or ``coupling`` the analytic methods use the exact formulas for
        those parts (they are exact on any tet).
    options
        :class:`~springmodel.options.SpringOptions`: which parts are on (default: the seed's).

    Returns
    -------
    Calibrated
        Constants and the per-element mismatch of the switched-on parts
        (:func:`springmodel.tangent.tangent_mismatch`).
    """
    from .exact import exact_constants
    from .nnls import nnls_fit
    from .options import SpringOptions
    from .tangent import basis_names, element_mismatch

    options = options or SpringOptions()
    m = geometry.V0.shape[0]
    if is_transverse(material):
        C_global = material_matrix(material, frames)
        C_local = material_matrix(material)
    else:  # isotropic: the same in every frame, no per-element copies
        C_global = C_local = material_matrix(material)
    C_local = np.broadcast_to(C_local, (m, 6, 6))
    seed_parts = not options.axis_volume and not options.coupling
    k = exact_constants(geometry, C_local, options.volume, options.coupling)
    if method in ("analytic", "analytic-lsq") and seed_parts:
        volume = "lsq" if method == "analytic-lsq" else "mean"
        k["k_axial"], k["k_torsion"], k["k_volume"] = analytic_constants(geometry, C_local, volume)
    elif method == "nnls":
        fit = nnls_fit(geometry, C_global, C_local, options)
        names = basis_names(options.torsion, options.volume, options.coupling)
        col = {n: fit[:, i] for i, n in enumerate(names)}
        k["k_axial"] = fit[:, :3]
        if options.torsion != "off":
            k["k_torsion"] = fit[:, 3:6]
        k["k_volume"] = col.get("volume", k["k_volume"])
        k["k_axis_volume"] = col.get("axis_volume", k["k_axis_volume"])
        if options.coupling:
            k["k_coupling"] = np.stack([col[f"coupling{p}"] for p in ("01", "02", "12")], 1)
    elif method not in ("analytic", "analytic-lsq", "exact"):
        raise ValueError(
            f"calibration {method!r} is not one of analytic, analytic-lsq, nnls, exact"
        )
    if not options.barycentric_volume:
        k["k_volume"] = np.zeros(m)
    mismatch = element_mismatch(
        RestGeometry(geometry.zeta0, geometry.xi0, geometry.V0),
        constants_of(k, options),
        C_global,
        options,
    )
    return Calibrated(
        k["k_axial"], k["k_torsion"], k["k_volume"], mismatch, k["k_axis_volume"], k["k_coupling"]
    )


def constants_of(k: dict[str, np.ndarray], options: Any) -> np.ndarray:
    """Constants ``(m, nb)`` of the switched-on parts in the order of the tangent basis."""
    cols = [k["k_axial"]]
    if options.torsion != "off":
        cols.append(k["k_torsion"])
    if options.volume is True:
        cols.append(k["k_volume"][:, None])
    elif options.volume == "axes":
        cols.append(k["k_axis_volume"][:, None])
    if options.coupling:
        cols.append(k["k_coupling"])
    return np.concatenate(cols, axis=1)


# --------------------------------------------------------------------------- W_k(F)


def element_energy_from_F(
    F: np.ndarray,
    geometry: Any,
    k_axial,
    k_torsion,
    k_volume,
    axial_coefficients: tuple[float, float] = (0.0, 0.0),
) -> np.ndarray:
    """Energy ``W_k(F)`` of each spring element from its deformation gradient alone, ``(m,)``.

    Energy forms only: axial polynomial ``k (d^2/2 + b2 d^3/(3 l0) + b3 d^4/(4 l0^2))``
    (``b2 = b3 = 0`` is linear), torsion ``k/2 (c - c0)^2``, volume ``k_s/2 dL^2``. Nothing
    here uses intersection points: ``zeta_l = F zeta_l^0`` and ``xi_j = F xi_j^0``.
    """
    m = geometry.V0.shape[0]
    k = _stack_constants(k_axial, k_torsion, k_volume, m)
    b2, b3 = axial_coefficients
    zeta = geometry.zeta0 @ F.transpose(0, 2, 1)
    l0 = np.linalg.norm(geometry.zeta0, axis=-1)
    L = np.linalg.norm(zeta, axis=-1)
    d = L - l0
    W = np.sum(k[:, :3] * (d**2 / 2 + b2 * d**3 / (3 * l0) + b3 * d**4 / (4 * l0**2)), axis=1)
    c = rest_cosines(zeta)
    W += np.sum(0.5 * k[:, 3:6] * (c - rest_cosines(geometry.zeta0)) ** 2, axis=1)
    xi = geometry.xi0 @ F.transpose(0, 2, 1)
    dL = np.linalg.norm(xi, axis=-1).sum(1) - np.linalg.norm(geometry.xi0, axis=-1).sum(1)
    W += 0.5 * k[:, 6] * dL**2
    return W
