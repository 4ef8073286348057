"""Material parameters -> spring constants (docs/calibration.rst#calibration).

A spring element's energy is a function of its deformation gradient ``F`` alone and, at
small strain, that of a P1 element with the effective Voigt matrix
``D_k = (1/V) sum_a k_a v_a v_a^T`` (:mod:`springmodel.element_energy`; the Voigt vectors
``v_a`` of the strain tensors ``a_a`` of the rest geometry,
:mod:`springmodel.rest_geometry`). Calibration chooses the seven constants so that ``D_k``
matches the material matrix ``C``:

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
>>> from springfem.materials import material_matrix
>>> from springfem.scene import Material
>>> from springmodel.element_energy import effective_matrix
>>> from springmodel.rest_geometry import RestGeometry
>>> X = np.array([[1.0, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]])  # regular: R = rho I
>>> g = RestGeometry(np.eye(3)[None], X[None], np.array([8 / 3]))
>>> C = material_matrix(Material("linear", 1.0e4, 0.3))[None]
>>> ka, kt, ks = analytic_constants(g, C)
>>> D = effective_matrix(g, ka, kt, ks)  # exact for isotropic material on a regular tet
>>> bool(calibration_mismatch(D, C)[0] < 1e-12)
True
"""

from __future__ import annotations

from typing import Any, Literal, NamedTuple

import numpy as np

from springfem.materials import is_transverse, material_matrix, to_mandel

from .rest_geometry import TORSION_VOIGT, RestGeometry, radial_tensor


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
        ``mean``: ``k_s = b V / rho^2`` with ``rho = tr(R)/3``
        (docs/calibration.rst#analytic-calibration). ``lsq``: the
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
        :class:`~springmodel.options.SpringOptions`: which parts are on (default: the
        specification's).

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
        ka, kt, _ = analytic_constants(geometry, C_local)
        fit = nnls_fit(geometry, C_global, (ka, kt), options)
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
    """The constants of the switched-on parts, in the order of the tangent basis.

    Parameters
    ----------
    k
        Constants by name: ``k_axial`` ``(m, 3)``, ``k_torsion`` ``(m, 3)``, ``k_volume``
        ``(m,)``, ``k_axis_volume`` ``(m,)``, ``k_coupling`` ``(m, 3)``; only those of the
        switched-on parts are read.
    options
        :class:`~springmodel.options.SpringOptions` (``torsion``, ``volume``, ``coupling``).

    Returns
    -------
    ndarray
        ``(m, nb)``: axial, then torsion unless ``off``, then the barycentric or axis-volume
        constant, then coupling (:func:`springmodel.tangent.basis_names`).
    """
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
