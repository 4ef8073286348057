"""Small-strain tangents of the finite-strain tissue laws, as 6x6 Voigt matrices.

The FEM reference (``reference_fem.laws``) implements the Guccione and Holzapfel–Ogden
laws at finite strain; the spring calibration needs what they reduce to at ``F = I``: the
orthotropic matrix ``D = d^2 W / d eps^2`` in the element's (fiber, sheet, normal) frame,
Voigt order ``ff, ss, nn, sn, fn, fs`` with engineering shear strains. These are the
closed-form second derivatives at the reference state:

- Guccione, ``W = C/2 (e^Q - 1)``: ``W ~ C/2 Q`` so
  ``D = diag(C b_f, C b_t, C b_t, C b_t / 2, C b_fs / 2, C b_fs / 2)``.
- Holzapfel–Ogden with the isochoric ``I1bar`` in its isotropic term: the isotropic term is
  a neo-Hookean deviatoric part with shear modulus ``a``; ``a_f/(2 b_f)(e^{b_f(I4f-1)^2}-1)``
  adds ``4 a_f`` to ``D_ff`` (``I4f - 1 = 2 E_ff``) and the sheet term ``4 a_s`` to
  ``D_ss``, both only in tension (``tension=False`` gives the compression side, where the
  terms are off); ``a_fs/(2 b_fs)(e^{b_fs I8^2}-1)`` adds ``a_fs`` to the fs shear
  (``I8 = 2 E_fs``).
- The volumetric penalty ``U(J)`` (any of the ``volumetric`` choices, ``U''(1) = kappa``)
  adds ``kappa`` to every entry of the normal block.

Examples
--------
>>> D = guccione_tangent(C=2.0, b_f=8.0, b_t=2.0, b_fs=4.0)
>>> np.diag(D).tolist()
[16.0, 4.0, 4.0, 2.0, 4.0, 4.0]
>>> float(tissue_tangent("holzapfel-ogden", dict(a=1.0, b=1.0, a_f=2.0, b_f=1.0, a_s=0.0,
...     b_s=1.0, a_fs=0.0, b_fs=1.0), kappa=10.0)[0, 0])
19.333333333333336
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

GUCCIONE_KEYS = ("C", "b_f", "b_t", "b_fs")
HOLZAPFEL_OGDEN_KEYS = ("a", "b", "a_f", "b_f", "a_s", "b_s", "a_fs", "b_fs")
#: Parameter names of each finite-strain tissue law.
TISSUE_LAWS = {"guccione": GUCCIONE_KEYS, "holzapfel-ogden": HOLZAPFEL_OGDEN_KEYS}


def _volumetric(D: np.ndarray, kappa: float) -> np.ndarray:
    D[:3, :3] += kappa
    return D


def guccione_tangent(
    C: float, b_f: float, b_t: float, b_fs: float, kappa: float = 0.0
) -> np.ndarray:
    """Small-strain Voigt tangent ``(6, 6)`` of the Guccione law in its element frame.

    Parameters
    ----------
    C, b_f, b_t, b_fs
        Guccione's parameters (``C`` a stress, the ``b`` dimensionless).
    kappa
        Bulk modulus of the volumetric penalty (0: none).

    Returns
    -------
    numpy.ndarray
        ``D`` with ``sigma = D eps`` (Voigt ``ff, ss, nn, sn, fn, fs``).
    """
    D = np.diag([C * b_f, C * b_t, C * b_t, C * b_t / 2, C * b_fs / 2, C * b_fs / 2])
    return _volumetric(D.astype(float), kappa)


def holzapfel_ogden_tangent(
    a: float,
    b: float,
    a_f: float,
    b_f: float,
    a_s: float,
    b_s: float,
    a_fs: float,
    b_fs: float,
    kappa: float = 0.0,
    tension: bool = True,
) -> np.ndarray:
    """Small-strain Voigt tangent ``(6, 6)`` of the Holzapfel–Ogden law in its frame.

    Parameters
    ----------
    a, b, a_f, b_f, a_s, b_s, a_fs, b_fs
        Holzapfel & Ogden (2009) parameters; the ``b`` do not enter at small strain.
    kappa
        Bulk modulus of the volumetric penalty (0: none).
    tension
        ``True``: the fibre and sheet terms are on (the tangent for a stretch along them);
        ``False``: off (the tangent in compression, and the FEM's at exactly ``F = I``).

    Returns
    -------
    numpy.ndarray
        ``D`` with ``sigma = D eps`` (Voigt ``ff, ss, nn, sn, fn, fs``).
    """
    D = np.zeros((6, 6))
    D[:3, :3] = 2.0 * a * (np.eye(3) - 1.0 / 3.0)
    D[3:, 3:] = a * np.eye(3)
    if tension:
        D[0, 0] += 4.0 * a_f
        D[1, 1] += 4.0 * a_s
    D[5, 5] += a_fs
    return _volumetric(D, kappa)


def tissue_tangent(
    law: str, parameters: Mapping[str, float], kappa: float = 0.0, tension: bool = True
) -> np.ndarray:
    """Small-strain Voigt tangent of a tissue law by name, in the element frame.

    Parameters
    ----------
    law
        ``guccione`` or ``holzapfel-ogden``.
    parameters
        The law's parameters (:data:`TISSUE_LAWS`); other keys are ignored.
    kappa
        Bulk modulus of the volumetric penalty (0: none).
    tension
        Holzapfel–Ogden only: fibre and sheet terms on (see
        :func:`holzapfel_ogden_tangent`).

    Returns
    -------
    numpy.ndarray
        ``(6, 6)``; rotate it to the global frame with
        :func:`springfem.materials.rotate_to_global`.
    """
    if law not in TISSUE_LAWS:
        raise ValueError(f"law {law!r} is not one of {', '.join(TISSUE_LAWS)}")
    missing = [k for k in TISSUE_LAWS[law] if k not in parameters]
    if missing:
        raise ValueError(f"{law} needs {', '.join(missing)}")
    values = {k: float(parameters[k]) for k in TISSUE_LAWS[law]}
    if law == "guccione":
        return guccione_tangent(**values, kappa=kappa)
    return holzapfel_ogden_tangent(**values, kappa=kappa, tension=tension)
