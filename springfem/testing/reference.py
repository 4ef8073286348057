"""The references of the conformance check: the core's linear P1 (the small-strain
reference), a scene under a scaled load, a rotation matrix.

Examples
--------
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({"mesh": {"generator": "box", "size": [1, 1, 1],
...     "divisions": [1, 1, 1]}, "material": {"law": "linear", "E": 1.0, "nu": 0.25}})
>>> K = LinearP1(scene).K
>>> K.shape, bool(abs(K - K.T).max() < 1e-15)
((24, 24), True)
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from ..loads import external_forces, lumped_masses
from ..materials import material_matrix
from ..mesh.nodal_average import shape_gradients
from ..scene import Scene


class LinearP1:
    """Linear P1 tets of the scene's small-strain law: the small-strain reference.

    ``f = s f_ext - K (x - X)`` with ``K = sum_e V_e B_e^T C_e B_e``, ``C_e`` the scene's
    small-strain matrix in the element's frame
    (:func:`springfem.materials.material_matrix`: a neo-Hookean or tissue law's tangent at
    ``F = I``). A :class:`~springfem.mechanics.MechanicalSystem`, written on the core alone.

    Parameters
    ----------
    scene
        The scene.

    Attributes
    ----------
    K
        The stiffness ``(3n, 3n)``.
    """

    def __init__(self, scene: Scene):
        mesh = scene.mesh
        self.x0 = np.array(mesh.points, dtype=float)
        self.tets = np.asarray(mesh.tets)
        self.masses = lumped_masses(scene)
        self.fixed_dofs, self._values = scene.dirichlet()
        self._f = external_forces(scene)
        g = shape_gradients(self.x0, self.tets)  # (m, 4, 3)
        m = len(self.tets)
        B4 = np.zeros((m, 6, 4, 3))  # Voigt strain (xx, yy, zz, yz, xz, xy) of u_e
        for i in range(3):
            B4[:, i, :, i] = g[:, :, i]
        for row, (i, j) in zip((3, 4, 5), ((1, 2), (0, 2), (0, 1)), strict=True):
            B4[:, row, :, i], B4[:, row, :, j] = g[:, :, j], g[:, :, i]
        B = B4.reshape(m, 6, 12)
        C = material_matrix(scene.material, np.asarray(scene.frames))
        V = np.abs(mesh.volumes())
        Ke = V[:, None, None] * np.einsum("kai,kab,kbj->kij", B, C, B)
        dofs = (3 * self.tets[:, :, None] + np.arange(3)).reshape(-1, 12)
        n = self.x0.size
        rows, cols = np.repeat(dofs, 12, axis=1).ravel(), np.tile(dofs, (1, 12)).ravel()
        self.K = sp.csr_matrix((Ke.ravel(), (rows, cols)), shape=(n, n))

    def prescribed(self, scale: float) -> np.ndarray:
        return self.x0.ravel()[self.fixed_dofs] + scale * self._values

    def forces(self, x: np.ndarray, v: np.ndarray | None = None, scale: float = 1.0) -> np.ndarray:
        u = (np.asarray(x) - self.x0).ravel()
        return scale * self._f - (self.K @ u).reshape(-1, 3)

    def energy(self, x: np.ndarray, scale: float = 1.0) -> float:
        u = (np.asarray(x) - self.x0).ravel()
        return float(0.5 * u @ (self.K @ u) - scale * self._f.ravel() @ u)

    def stiffness(self, x: np.ndarray, scale: float = 1.0) -> sp.csr_matrix:
        return self.K

    def element_nodes(self) -> np.ndarray:
        return self.tets

    def post_step(self, x: np.ndarray, dt: float) -> None:
        pass


def scaled_scene(scene: Scene, factor: float) -> Scene:
    """``scene`` with every load and prescribed displacement times ``factor``.

    Parameters
    ----------
    scene
        The scene.
    factor
        The load factor.

    Returns
    -------
    Scene
        A copy (the mesh and material shared).
    """
    return replace(
        scene,
        loads=[replace(load, value=factor * np.asarray(load.value)) for load in scene.loads],
        boundaries=[replace(b, value=factor * np.asarray(b.value)) for b in scene.boundaries],
        options=dict(scene.options),
    )


def rotation(rotvec: np.ndarray) -> np.ndarray:
    """The rotation matrix of a rotation vector (Rodrigues).

    Parameters
    ----------
    rotvec
        Axis times angle (rad), ``(3,)``.

    Returns
    -------
    numpy.ndarray
        ``(3, 3)``.

    Examples
    --------
    >>> R = rotation(np.array([0.0, 0.0, np.pi / 2]))
    >>> np.round(R @ [1.0, 0.0, 0.0], 12).tolist()
    [0.0, 1.0, 0.0]
    """
    w = np.asarray(rotvec, dtype=float)
    a = float(np.linalg.norm(w))
    if a == 0.0:
        return np.eye(3)
    k = w / a
    Kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(a) * Kx + (1.0 - np.cos(a)) * (Kx @ Kx)
