"""Linear elastic material matrices: isotropic and transversely isotropic, in Voigt form.

Voigt order is ``(xx, yy, zz, yz, xz, xy)`` with engineering shear strains, so
``sigma = D @ eps`` and the fourth-order tensor is ``C[i, j, k, l] = D[v(i, j), v(k, l)]``.

Transversely isotropic materials have the fiber (axis 0 of each element's frame) as the
symmetry axis. Their compliance in the local frame (fiber, sheet, normal) is built from
``(E_fiber, E_cross, nu_fiber_cross, nu_cross, G_fiber)``, inverted, and rotated to the
global frame per element.

Examples
--------
>>> import numpy as np
>>> D = isotropic_matrix(1.0, 0.25)
>>> D[0, 0].round(12), D[0, 1].round(12), D[3, 3].round(12)
(np.float64(1.2), np.float64(0.4), np.float64(0.4))
>>> S = transverse_compliance(3.0, 1.0, 0.3, 0.4, 0.5)
>>> float(1.0 / S[0, 0])  # Young's modulus along the fiber
3.0
"""

from __future__ import annotations

import numpy as np

from springmodel.errors import InputError
from springmodel.scene import Material

#: Voigt index of the tensor index pair ``(i, j)``.
VOIGT = np.array([[0, 5, 4], [5, 1, 3], [4, 3, 2]])


def isotropic_matrix(E: float, nu: float) -> np.ndarray:
    """Isotropic stiffness ``D`` (6, 6) from Young's modulus and Poisson's ratio."""
    lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    mu = E / (2.0 * (1.0 + nu))
    D = np.zeros((6, 6))
    D[:3, :3] = lam
    D[[0, 1, 2], [0, 1, 2]] += 2.0 * mu
    D[[3, 4, 5], [3, 4, 5]] = mu
    return D


def transverse_compliance(
    E_fiber: float, E_cross: float, nu_fiber_cross: float, nu_cross: float, G_fiber: float
) -> np.ndarray:
    """Compliance ``S`` (6, 6) in the local frame (fiber, sheet, normal).

    ``nu_fiber_cross`` is the cross contraction under fiber load
    (``eps_cross = -nu_fiber_cross sigma_fiber / E_fiber``); the cross-plane shear modulus
    is ``E_cross / (2 (1 + nu_cross))`` (isotropy in the sheet-normal plane).
    """
    Ef, Ec, nfc, nc, Gf = E_fiber, E_cross, nu_fiber_cross, nu_cross, G_fiber
    S = np.zeros((6, 6))
    S[0, 0] = 1.0 / Ef
    S[1, 1] = S[2, 2] = 1.0 / Ec
    S[0, 1] = S[1, 0] = S[0, 2] = S[2, 0] = -nfc / Ef
    S[1, 2] = S[2, 1] = -nc / Ec
    S[3, 3] = 2.0 * (1.0 + nc) / Ec  # sheet-normal shear
    S[4, 4] = S[5, 5] = 1.0 / Gf  # fiber-normal and fiber-sheet shear
    return S


def voigt_to_tensor(D: np.ndarray) -> np.ndarray:
    """Fourth-order tensor ``(..., 3, 3, 3, 3)`` of a Voigt stiffness ``(..., 6, 6)``."""
    return D[..., VOIGT[:, :, None, None], VOIGT[None, None, :, :]]


def tensor_to_voigt(C: np.ndarray) -> np.ndarray:
    """Voigt stiffness ``(..., 6, 6)`` of a (minor-symmetric) tensor ``(..., 3, 3, 3, 3)``."""
    pairs = [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)]
    i = np.array([p[0] for p in pairs])
    j = np.array([p[1] for p in pairs])
    return C[..., i[:, None], j[:, None], i[None, :], j[None, :]]


def rotate_tensor(C_local: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """Rotate local tensors to the global frame: ``C_ijkl = R_ai R_bj R_ck R_dl C_abcd``.

    ``frames[..., a, :]`` is local axis ``a`` as a global unit row vector.
    """
    C = np.einsum("...ai,...abcd->...ibcd", frames, C_local)
    C = np.einsum("...bj,...ibcd->...ijcd", frames, C)
    C = np.einsum("...ck,...ijcd->...ijkd", frames, C)
    return np.einsum("...dl,...ijkd->...ijkl", frames, C)


def _unique_frames(frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distinct frames (to 1e-14) and the index of each element's frame among them."""
    flat = np.round(frames.reshape(len(frames), 9), 14)
    uniq, inverse = np.unique(flat, axis=0, return_inverse=True)
    return uniq.reshape(-1, 3, 3), inverse.ravel()


def material_groups(material: Material, frames: np.ndarray, law: str | None = None):
    """Distinct Voigt matrices and each element's group: ``(D_groups (g, 6, 6), group (m,))``.

    Uniform axes give one group, so assembly can use one matrix product per group.
    """
    law = law or material.law
    m = len(frames)
    if law in ("linear", "neo-hookean"):
        return isotropic_matrix(material.E, material.nu)[None], np.zeros(m, dtype=np.int64)
    if law != "transverse-linear":
        raise InputError(f"law {law!r} has no linear material matrix")
    keys = ("E_fiber", "E_cross", "nu_fiber_cross", "nu_cross", "G_fiber")
    missing = [k for k in keys if getattr(material, k) is None]
    if missing:
        raise InputError(f"transverse-linear needs material.{', material.'.join(missing)}")
    S = transverse_compliance(*(getattr(material, k) for k in keys))
    C_local = voigt_to_tensor(np.linalg.inv(S))
    uniq, group = _unique_frames(np.asarray(frames, dtype=float))
    D = tensor_to_voigt(rotate_tensor(C_local, uniq))
    return 0.5 * (D + np.swapaxes(D, -1, -2)), group


def material_matrix(material: Material, frames: np.ndarray, law: str | None = None) -> np.ndarray:
    """Per-element Voigt stiffness ``(m, 6, 6)`` in the global frame.

    Parameters
    ----------
    material
        The scene's material.
    frames
        ``(m, 3, 3)`` element frames; ``frames[k, 0]`` is the fiber.
    law
        ``linear`` (isotropic ``E``, ``nu``) or ``transverse-linear``; default
        ``material.law`` (``neo-hookean`` gives its small-strain isotropic matrix).

    Examples
    --------
    >>> from springmodel.scene import Material
    >>> mat = Material("transverse-linear", 1.0, 0.4, E_fiber=3.0, E_cross=1.0,
    ...                nu_fiber_cross=0.3, nu_cross=0.4, G_fiber=0.5)
    >>> D = material_matrix(mat, np.eye(3)[None])
    >>> round(float(np.linalg.inv(D[0])[0, 0]), 12)
    0.333333333333
    """
    D, group = material_groups(material, frames, law)
    return D[group]
