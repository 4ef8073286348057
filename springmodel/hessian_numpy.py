"""Element Hessians of the conservative spring energies, the vectorised numpy reference.

The axial + torsion (+ axis-volume + coupling) energies depend on the three axis vectors only:
their Hessian is formed in the axes (``[k, l, a, m, b]``) and mapped to the 12 vertex DOFs with
``G`` (``d zeta_l / d x_i = G[k,i,l] I``); the barycentric volume spring acts on the vertices.
The formulas are in :mod:`springmodel.hessian`; the numba backend
(:mod:`springmodel.hessian_numba`) must agree with this module.

Examples
--------
>>> import numpy as np
>>> from springmodel.options import SpringOptions
>>> H = axis_hessian(np.eye(3)[None], np.ones((1, 3)), np.ones((1, 3)), np.zeros((1, 3)),
...                  np.zeros((1, 3)), SpringOptions(torsion="off"))
>>> float(H[0, 0, 0, 0, 0]), float(H[0, 0, 1, 0, 1])
(1.0, 0.0)
"""

from __future__ import annotations

import numpy as np

from springfem.volumetric import volumetric_energy

from .axis_springs import volume_ratio, volume_ratio_gradient
from .options import SpringOptions
from .rest_geometry import TORSION_PAIRS
from .springs.shear import shear_derivatives


def polynomial_coefficients(options: SpringOptions) -> tuple[float, float]:
    """``(b2, b3)`` of the axial law (zero for ``linear``, ``b3 = 0`` for ``quadratic``).

    Parameters
    ----------
    options
        Spring options (``axial``, ``axial_coefficients``).

    Returns
    -------
    tuple of float
        ``(b2, b3)``.
    """
    if options.axial in ("quadratic", "cubic"):
        b2, b3 = options.axial_coefficients
        return float(b2), float(b3) if options.axial == "cubic" else 0.0
    return 0.0, 0.0


def _outer(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return u[..., :, None] * v[..., None, :]


def axis_hessian(
    zeta: np.ndarray,
    l0: np.ndarray,
    k_axial: np.ndarray,
    k_torsion: np.ndarray,
    c0: np.ndarray,
    options: SpringOptions,
) -> np.ndarray:
    """Hessian of the axial + torsion energy in the axis vectors, ``(m, 3, 3, 3, 3)``.

    Parameters
    ----------
    zeta
        Current axes ``(m, 3, 3)``.
    l0, k_axial, k_torsion, c0
        Rest lengths ``(m, 3)``, axial (N/m) and torsion (J) constants ``(m, 3)``, rest
        cosines ``(m, 3)``.
    options
        Spring options (axial law and coefficients, torsion law ``off``, ``energy`` or
        ``shear``).

    Returns
    -------
    ndarray
        ``H[k, l, a, m, b] = d^2 U / d zeta_l[a] d zeta_m[b]``, ``(m, 3, 3, 3, 3)``.
    """
    m = zeta.shape[0]
    eye = np.eye(3)
    L = np.linalg.norm(zeta, axis=-1)  # (m, 3)
    u = zeta / L[..., None]
    uu = _outer(u, u)  # (m, 3, 3, 3)
    H = np.zeros((m, 3, 3, 3, 3))

    # axial: f'' uu^T + f'/L (I - uu^T), eqs. 2.35–2.36
    k = k_axial
    d = L - l0
    b2, b3 = polynomial_coefficients(options)
    f1 = k * (d + b2 * d**2 / l0 + b3 * d**3 / l0**2)
    f2 = k * (1.0 + 2.0 * b2 * d / l0 + 3.0 * b3 * d**2 / l0**2)
    for l in range(3):
        s = (f1[:, l] / L[:, l])[:, None, None]
        H[:, l, :, l, :] = f2[:, l, None, None] * uu[:, l] + s * (eye - uu[:, l])

    # torsion, U = k phi(c): k (phi'' grad c grad c^T + phi' grad^2 c); energy law
    # phi = (c - c0)^2 / 2, shear law phi = delta^2 / 2 (springmodel.springs.shear)
    if options.energy_torsion:
        for p, (l, q) in enumerate(TORSION_PAIRS):
            A, B = L[:, l, None], L[:, q, None]
            ua, ub = u[:, l], u[:, q]
            c = np.einsum("kc,kc->k", ua, ub)
            if options.torsion == "shear":
                d1, d2 = shear_derivatives(c, c0[:, p])
            else:
                d1, d2 = c - c0[:, p], np.ones_like(c)
            dc = d1[:, None, None]
            kt = k_torsion[:, p, None, None]
            kg = kt * d2[:, None, None]
            cc = c[:, None, None]
            ga = (ub - c[:, None] * ua) / A  # dc/da
            gb = (ua - c[:, None] * ub) / B  # dc/db
            Pa, Pb = eye - uu[:, l], eye - uu[:, q]
            A2, B2 = A[..., None], B[..., None]
            haa = -(_outer(ua, ga) + _outer(ga, ua)) / A2 - cc * Pa / A2**2
            hbb = -(_outer(ub, gb) + _outer(gb, ub)) / B2 - cc * Pb / B2**2
            hab = (Pa - uu[:, q] + cc * _outer(ua, ub)) / (A2 * B2)
            H[:, l, :, l, :] += kg * _outer(ga, ga) + kt * dc * haa
            H[:, q, :, q, :] += kg * _outer(gb, gb) + kt * dc * hbb
            Kab = kg * _outer(ga, gb) + kt * dc * hab
            H[:, l, :, q, :] += Kab
            H[:, q, :, l, :] += Kab.transpose(0, 2, 1)
    return H


def volume_hessian(X: np.ndarray, L0: np.ndarray, k_volume: np.ndarray) -> np.ndarray:
    """Hessian of ``k_s/2 (sum_j |x_j - x_b| - L0)^2`` in the vertices, ``(m, 4, 3, 4, 3)``.

    Parameters
    ----------
    X
        Element vertex positions ``(m, 4, 3)``.
    L0, k_volume
        Rest radial sums and volume constants (N/m), each ``(m,)``.

    Returns
    -------
    ndarray
        ``(m, 4, 3, 4, 3)``, index ``[k, i, a, j, b]``.
    """
    xi = X - X.mean(axis=1, keepdims=True)  # restoring sign, barycenter -> vertex
    r = np.linalg.norm(xi, axis=-1)
    xh = xi / r[..., None]
    dL = r.sum(axis=1) - L0
    gL = xh - xh.mean(axis=1, keepdims=True)  # (m, 4, 3)
    Hr = (np.eye(3) - _outer(xh, xh)) / r[..., None, None]  # (m, 4, 3, 3)
    S = Hr.sum(axis=1) / 16.0  # (m, 3, 3)
    H2 = -0.25 * (Hr[:, :, None] + Hr[:, None, :]) + S[:, None, None]  # (m, i, k, a, b)
    H2[:, np.arange(4), np.arange(4)] += Hr
    K = _outer(gL.reshape(-1, 12), gL.reshape(-1, 12)).reshape(-1, 4, 3, 4, 3)
    K += dL[:, None, None, None, None] * H2.transpose(0, 1, 3, 2, 4)
    return k_volume[:, None, None, None, None] * K


def _levi_civita(z: np.ndarray) -> np.ndarray:
    """``E[a, b] = eps_abc z_c``, ``(m, 3, 3)``."""
    E = np.zeros(z.shape[:-1] + (3, 3))
    E[..., 0, 1], E[..., 1, 2], E[..., 2, 0] = z[..., 2], z[..., 0], z[..., 1]
    return E - np.swapaxes(E, -1, -2)


def axis_parts_hessian(
    zeta: np.ndarray,
    l0: np.ndarray,
    k_coupling: np.ndarray,
    kappa_V0: np.ndarray,
    inv_det0: np.ndarray,
    options: SpringOptions,
) -> np.ndarray:
    """Hessian of the axis-volume and coupling energies in the axes, ``(m, 3, 3, 3, 3)``.

    Axis volume ``V0 U(J)``: ``V0 (U'' gJ gJ^T + U' d^2J)`` with ``gJ_0 = zeta_1 x zeta_2 /
    det0`` (cyclic) and, for ``(l, m, n)`` cyclic, ``d^2J / d zeta_l d zeta_m = E(zeta_n) /
    det0`` (``E[a, b] = eps_abc z_c``), its transpose for ``(m, l)``. Coupling
    ``c s_l s_m``: ``c s_m (I - zh_l zh_l^T) / (l_l |zeta_l|)`` on ``(l, l)`` (and ``l <-> m``),
    ``c zh_l zh_m^T / (l_l l_m)`` on ``(l, m)``.

    Parameters
    ----------
    zeta, l0
        Current axes ``(m, 3, 3)`` and rest lengths ``(m, 3)``.
    k_coupling
        Coupling constants ``(m, 3)`` (J) for the pairs (0,1), (0,2), (1,2).
    kappa_V0, inv_det0
        ``kappa V0`` (J) and ``1 / det0``, each ``(m,)``.
    options
        Spring options (``axis_volume``, ``volumetric``, ``coupling``).

    Returns
    -------
    ndarray
        ``(m, 3, 3, 3, 3)``, index order as in :func:`axis_hessian`.
    """
    m = zeta.shape[0]
    H = np.zeros((m, 3, 3, 3, 3))
    if options.axis_volume:
        J = volume_ratio(zeta, 1.0 / inv_det0)
        gJ = volume_ratio_gradient(zeta, 1.0 / inv_det0)
        _, dU, d2U = volumetric_energy(J, kappa_V0, options.volumetric)  # times V0
        H += d2U[:, None, None, None, None] * _outer(gJ.reshape(m, 9), gJ.reshape(m, 9)).reshape(
            m, 3, 3, 3, 3
        )
        for l, q, n in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
            E = (dU * inv_det0)[:, None, None] * _levi_civita(zeta[:, n])
            H[:, l, :, q, :] += E
            H[:, q, :, l, :] += np.swapaxes(E, -1, -2)
    if options.coupling:
        L = np.linalg.norm(zeta, axis=-1)
        u = zeta / L[..., None]
        s = L / l0 - 1.0
        P = np.eye(3) - _outer(u, u)  # (m, 3, 3, 3)
        for p, (l, q) in enumerate(TORSION_PAIRS):
            c = k_coupling[:, p]
            H[:, l, :, l, :] += (c * s[:, q] / (l0[:, l] * L[:, l]))[:, None, None] * P[:, l]
            H[:, q, :, q, :] += (c * s[:, l] / (l0[:, q] * L[:, q]))[:, None, None] * P[:, q]
            cross = (c / (l0[:, l] * l0[:, q]))[:, None, None] * _outer(u[:, l], u[:, q])
            H[:, l, :, q, :] += cross
            H[:, q, :, l, :] += np.swapaxes(cross, -1, -2)
    return H


def _element_matrices_numpy(
    x: np.ndarray,
    tets: np.ndarray,
    G: np.ndarray,
    l0: np.ndarray,
    ka: np.ndarray,
    kt: np.ndarray,
    c0: np.ndarray,
    kv: np.ndarray,
    L0: np.ndarray,
    options: SpringOptions,
    axis_parts: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """Vectorised reference for the element matrices ``(m, 12, 12)``.

    ``axis_parts = (k_coupling (m,3), kappa V0 (m,), 1/det0 (m,))`` of the axis-volume and
    coupling springs, used where ``options`` switches them on.
    """
    X = x[tets]  # (m, 4, 3)
    m = X.shape[0]
    zeta = np.einsum("kil,kic->klc", G, X)  # zeta_l = sum_i G[k,i,l] x_i
    H = axis_hessian(zeta, l0, ka, kt, c0, options)
    if axis_parts is not None and (options.axis_volume or options.coupling):
        H += axis_parts_hessian(zeta, l0, *axis_parts, options)
    H = H.reshape(m, 3, 27)  # [k, l, (a, q, b)]
    # K[i,a,j,b] = sum_{l,q} G[i,l] H[l,a,q,b] G[j,q]
    T = (G @ H).reshape(m, 4, 3, 3, 3)  # [k, i, a, q, b]
    T = T.transpose(0, 1, 2, 4, 3).reshape(m, 36, 3)  # [k, (i, a, b), q]
    K = (T @ G.transpose(0, 2, 1)).reshape(m, 4, 3, 3, 4)  # [k, i, a, b, j]
    K = K.transpose(0, 1, 2, 4, 3)  # [k, i, a, j, b]
    if options.barycentric_volume:
        K = K + volume_hessian(X, L0, kv)
    K = K.reshape(m, 12, 12)
    return 0.5 * (K + K.transpose(0, 2, 1))  # exact symmetry despite rounding
