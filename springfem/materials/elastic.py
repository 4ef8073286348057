"""Elastic material matrices: Lamé parameters, isotropic, orthotropic, transverse isotropy.

Anisotropic materials are given in each element's frame (fiber, sheet, normal): ``frames[k, a]``
is local axis ``a`` of element ``k`` as a global unit row vector.

Examples
--------
>>> lam, mu = lame_parameters(1.0, 0.25)
>>> round(lam, 12), round(mu, 12)
(0.4, 0.4)
>>> S = transverse_compliance(3.0, 1.0, 0.3, 0.4, 0.5)
>>> float(1.0 / S[0, 0])  # Young's modulus along the fiber
3.0
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from .tissue import TISSUE_LAWS, tissue_tangent
from .voigt import rotate_to_global

# ----------------------------------------------------------------------- parameters


def lame_parameters(E: float, nu: float) -> tuple[float, float]:
    """Lamé parameters ``(lam, mu)`` of Young's modulus ``E`` and Poisson's ratio ``nu``.

    Parameters
    ----------
    E
        Young's modulus (Pa).
    nu
        Poisson's ratio, ``-1 < nu < 0.5``.

    Returns
    -------
    tuple of float
        ``lam = E nu / ((1 + nu)(1 - 2 nu))`` and ``mu = E / (2 (1 + nu))``.

    Examples
    --------
    >>> lame_parameters(3.0, 0.0)
    (0.0, 1.5)
    """
    return E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), E / (2.0 * (1.0 + nu))


# ----------------------------------------------------------------------- matrices


def lame_matrix(lam: float, mu: float) -> np.ndarray:
    """Isotropic Voigt stiffness ``(6, 6)`` from the Lamé parameters.

    Parameters
    ----------
    lam, mu
        Lamé's first parameter and the shear modulus (Pa).

    Returns
    -------
    numpy.ndarray
        ``lam 1 1^T + 2 mu I`` on the normal block, ``mu`` on the (engineering) shears.

    Examples
    --------
    >>> lame_matrix(1.0, 2.0)[:3, :3]
    array([[5., 1., 1.],
           [1., 5., 1.],
           [1., 1., 5.]])
    """
    D = np.zeros((6, 6))
    D[:3, :3] = lam
    D[[0, 1, 2], [0, 1, 2]] = lam + 2.0 * mu
    D[[3, 4, 5], [3, 4, 5]] = mu
    return D


def isotropic_matrix(E: float, nu: float) -> np.ndarray:
    """Isotropic Voigt stiffness ``(6, 6)`` from Young's modulus and Poisson's ratio.

    Parameters
    ----------
    E, nu
        Young's modulus (Pa) and Poisson's ratio.

    Returns
    -------
    numpy.ndarray
        :func:`lame_matrix` of :func:`lame_parameters`.

    Examples
    --------
    >>> float(np.linalg.inv(isotropic_matrix(2.0, 0.3))[0, 0])  # 1 / E
    0.5
    """
    return lame_matrix(*lame_parameters(E, nu))


def orthotropic_compliance(
    E: tuple[float, float, float],
    nu: tuple[float, float, float],
    G: tuple[float, float, float],
) -> np.ndarray:
    """Compliance ``S`` (6, 6) of an orthotropic material in its own frame.

    Parameters
    ----------
    E
        Young's moduli ``(E_1, E_2, E_3)`` along the three axes.
    nu
        Poisson's ratios ``(nu_12, nu_13, nu_23)``: ``nu_ij`` is the contraction along ``j``
        under tension along ``i`` (``S_ij = -nu_ij / E_i``).
    G
        Shear moduli ``(G_23, G_13, G_12)`` in Voigt order (``yz, xz, xy``).

    Returns
    -------
    numpy.ndarray
        Symmetric ``(6, 6)`` compliance, engineering shear strains.

    Examples
    --------
    >>> S = orthotropic_compliance((1.0, 1.0, 1.0), (0.25, 0.25, 0.25), (0.4, 0.4, 0.4))
    >>> bool(np.allclose(np.linalg.inv(S), isotropic_matrix(1.0, 0.25)))
    True
    """
    (E1, E2, E3), (n12, n13, n23) = E, nu
    S = np.zeros((6, 6))
    S[0, 0], S[1, 1], S[2, 2] = 1.0 / E1, 1.0 / E2, 1.0 / E3
    S[0, 1] = S[1, 0] = -n12 / E1
    S[0, 2] = S[2, 0] = -n13 / E1
    S[1, 2] = S[2, 1] = -n23 / E2
    S[3, 3], S[4, 4], S[5, 5] = (1.0 / g for g in G)
    return S


def transverse_compliance(
    E_fiber: float, E_cross: float, nu_fiber_cross: float, nu_cross: float, G_fiber: float
) -> np.ndarray:
    """Compliance ``S`` (6, 6) of a transversely isotropic material (fiber = axis 0).

    Parameters
    ----------
    E_fiber, E_cross
        Young's moduli along and across the fiber.
    nu_fiber_cross
        Cross contraction under fiber load (``eps_cross = -nu_fiber_cross sigma_f / E_fiber``).
    nu_cross
        Poisson's ratio in the sheet-normal plane; that plane's shear modulus is
        ``E_cross / (2 (1 + nu_cross))`` (isotropy across the fiber).
    G_fiber
        Shear modulus of the two shears containing the fiber (``xz``, ``xy``).

    Returns
    -------
    numpy.ndarray
        The orthotropic compliance with these symmetries.

    Examples
    --------
    >>> S = transverse_compliance(3.0, 1.0, 0.3, 0.4, 0.5)
    >>> float(S[3, 3]), float(S[4, 4])
    (2.8, 2.0)
    """
    G_cross = E_cross / (2.0 * (1.0 + nu_cross))
    return orthotropic_compliance(
        (E_fiber, E_cross, E_cross),
        (nu_fiber_cross, nu_fiber_cross, nu_cross),
        (G_cross, G_fiber, G_fiber),
    )


def transverse_matrix(
    E_fiber: float, E_cross: float, nu_fiber_cross: float, nu_cross: float, G_fiber: float
) -> np.ndarray:
    """Transversely isotropic Voigt stiffness in the fiber frame: ``inv(transverse_compliance)``.

    Parameters
    ----------
    E_fiber, E_cross, nu_fiber_cross, nu_cross, G_fiber
        As in :func:`transverse_compliance`.

    Returns
    -------
    numpy.ndarray
        ``(6, 6)`` stiffness.

    Examples
    --------
    >>> C = transverse_matrix(3.0, 1.0, 0.3, 0.4, 0.5)
    >>> round(float(C[4, 4]), 12)
    0.5
    """
    args = (E_fiber, E_cross, nu_fiber_cross, nu_cross, G_fiber)
    return np.linalg.inv(transverse_compliance(*(float(v) for v in args)))


# ----------------------------------------------------------------------- scene materials

TRANSVERSE_KEYS = ("E_fiber", "E_cross", "nu_fiber_cross", "nu_cross", "G_fiber")


def _param(material: Any, name: str) -> Any:
    if isinstance(material, Mapping):
        return material.get(name)
    return getattr(material, name, None)


def is_transverse(material: Any) -> bool:
    """True for a transversely isotropic material.

    Parameters
    ----------
    material
        A :class:`~springfem.scene.Material` or a mapping.

    Returns
    -------
    bool
        ``law = "transverse-linear"``, or no law and ``E_fiber`` given.

    Examples
    --------
    >>> is_transverse({"E_fiber": 1.0}), is_transverse({"law": "linear"})
    (True, False)
    """
    law = _param(material, "law")
    if law is not None:
        return "transverse" in str(law)
    return _param(material, "E_fiber") is not None


def tissue_matrix(material: Any) -> np.ndarray:
    """Small-strain matrix of a tissue material in its element frame (fiber, sheet, normal).

    The law's closed-form tangent at ``F = I`` (:func:`~springfem.materials.tissue.tissue_tangent`,
    fibre and sheet terms on) with its volumetric penalty ``kappa``; an incompressible
    material takes the bulk modulus of its isotropic equivalent (``E``, ``nu``: 1000 times
    the shear modulus), the penalty a compressible model needs to stand in for it.

    Parameters
    ----------
    material
        A :class:`~springfem.scene.Material` (or mapping) with ``law`` in
        :data:`~springfem.materials.tissue.TISSUE_LAWS` and ``parameters``.

    Returns
    -------
    numpy.ndarray
        ``(6, 6)`` Voigt matrix.

    Examples
    --------
    >>> m = {"law": "guccione", "parameters": {"C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0,
    ...      "kappa": 100.0}}
    >>> float(tissue_matrix(m)[0, 0]), float(tissue_matrix(m)[0, 1])
    (116.0, 100.0)
    """
    params = dict(_param(material, "parameters") or {})
    kappa = float(params.get("kappa", 0.0) or 0.0)
    if kappa <= 0.0:
        E, nu = _param(material, "E"), _param(material, "nu")
        kappa = float(E) / (3.0 * (1.0 - 2.0 * float(nu))) if E is not None else 0.0
    return tissue_tangent(str(_param(material, "law")), params, kappa=kappa)


def material_matrix(material: Any, frames: np.ndarray | None = None) -> np.ndarray:
    """Small-strain Voigt stiffness ``C`` of a material, in the global frame.

    Parameters
    ----------
    material
        Any object or mapping with ``law`` and either isotropic ``E, nu`` (or ``mu, lam``)
        or transverse ``E_fiber, E_cross, nu_fiber_cross, nu_cross, G_fiber``. Neo-Hookean
        materials give their small-strain (isotropic) matrix, tissue laws their orthotropic
        small-strain tangent (:func:`tissue_matrix`).
    frames
        ``(m, 3, 3)`` element frames (rows = axes, fiber first). Needed to rotate a
        transverse material; if given, the result is stacked per element.

    Returns
    -------
    numpy.ndarray
        ``(6, 6)`` without frames, ``(m, 6, 6)`` with frames.

    Raises
    ------
    ValueError
        A parameter the law needs is missing.

    Examples
    --------
    >>> C = material_matrix({"law": "linear", "E": 1.0, "nu": 0.25})
    >>> float(C[0, 1])
    0.4
    """
    law = _param(material, "law")
    if law in TISSUE_LAWS:
        C = tissue_matrix(material)
        return C if frames is None else rotate_to_global(C, frames)
    if is_transverse(material):
        vals = [_param(material, n) for n in TRANSVERSE_KEYS]
        if any(v is None for v in vals):
            missing = [n for n, v in zip(TRANSVERSE_KEYS, vals, strict=True) if v is None]
            raise ValueError(f"transverse material needs {', '.join(missing)}")
        C = transverse_matrix(*vals)
        return C if frames is None else rotate_to_global(C, frames)
    mu, lam = _param(material, "mu"), _param(material, "lam")
    if mu is None or lam is None:
        E, nu = _param(material, "E"), _param(material, "nu")
        if E is None or nu is None:
            raise ValueError("isotropic material needs E and nu (or mu and lam)")
        lam, mu = lame_parameters(E, nu)
    C = lame_matrix(float(lam), float(mu))
    if frames is None:
        return C
    return np.broadcast_to(C, (np.asarray(frames).shape[0], 6, 6)).copy()
