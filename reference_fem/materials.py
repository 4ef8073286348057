"""The FEM's per-element material matrices, grouped by distinct element frame.

The matrices themselves (Lamé, Voigt, transverse compliance, rotations) are the core's
:mod:`springfem.materials`, shared with the spring calibration. Transversely isotropic
materials have the fiber (axis 0 of each element's frame) as the symmetry axis; uniform
axes give one group, so assembly needs one matrix product per group.

Examples
--------
>>> from springfem.mesh import box_mesh
>>> from springfem.scene import Material
>>> D, group = material_groups(Material("linear", 1.0, 0.25), np.tile(np.eye(3), (6, 1, 1)))
>>> D.shape, group.tolist()
((1, 6, 6), [0, 0, 0, 0, 0, 0])
"""

from __future__ import annotations

import numpy as np

from springfem.errors import InputError
from springfem.materials import (
    TRANSVERSE_KEYS,
    isotropic_matrix,
    rotate_to_global,
    transverse_matrix,
)
from springfem.scene import Material


def _unique_frames(frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distinct frames (to 1e-14) and the index of each element's frame among them."""
    flat = np.round(frames.reshape(len(frames), 9), 14)
    uniq, inverse = np.unique(flat, axis=0, return_inverse=True)
    return uniq.reshape(-1, 3, 3), inverse.ravel()


def material_groups(material: Material, frames: np.ndarray, law: str | None = None):
    """Distinct Voigt matrices and each element's group: ``(D_groups (g, 6, 6), group (m,))``.

    Uniform axes give one group, so assembly can use one matrix product per group.

    Parameters
    ----------
    material
        The scene's material.
    frames
        ``(m, 3, 3)`` element frames; ``frames[k, 0]`` is the fiber.
    law
        ``linear``, ``neo-hookean`` (isotropic) or ``transverse-linear``; default
        ``material.law``.

    Returns
    -------
    D_groups, group
        Global-frame Voigt matrices ``(g, 6, 6)`` and each element's index ``(m,)``.

    Raises
    ------
    InputError
        For a law without a linear matrix, or missing transverse constants.
    """
    law = law or material.law
    m = len(frames)
    if law in ("linear", "neo-hookean"):
        return isotropic_matrix(material.E, material.nu)[None], np.zeros(m, dtype=np.int64)
    if law != "transverse-linear":
        raise InputError(f"law {law!r} has no linear material matrix")
    keys = TRANSVERSE_KEYS
    missing = [k for k in keys if getattr(material, k) is None]
    if missing:
        raise InputError(f"transverse-linear needs material.{', material.'.join(missing)}")
    C_local = transverse_matrix(*(getattr(material, k) for k in keys))
    uniq, group = _unique_frames(np.asarray(frames, dtype=float))
    D = rotate_to_global(C_local, uniq)
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

    Returns
    -------
    ndarray
        Voigt stiffness ``(m, 6, 6)`` (Pa).

    Examples
    --------
    >>> from springfem.scene import Material
    >>> mat = Material("transverse-linear", 1.0, 0.4, E_fiber=3.0, E_cross=1.0,
    ...                nu_fiber_cross=0.3, nu_cross=0.4, G_fiber=0.5)
    >>> D = material_matrix(mat, np.eye(3)[None])
    >>> round(float(np.linalg.inv(D[0])[0, 0]), 12)
    0.333333333333
    """
    D, group = material_groups(material, frames, law)
    return D[group]
