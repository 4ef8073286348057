"""The energy XPBD's constraints stand for, as a mechanical system: P1 tets with the stable
neo-Hookean density of :mod:`.constraints`, lumped masses, the scene's loads and supports.

Its Newton answer (:func:`springfem.mechanics.static`) is the static equilibrium XPBD reaches
when its iterations converge (docs/peers.rst#xpbd): the target of the convergence checks.
The forces and the consistent tangent are computed from ``F`` in numpy, independently of the
constraint projections of :mod:`.kernels`.

Examples
--------
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({"mesh": {"generator": "box", "size": [0.1, 0.01, 0.01],
...     "divisions": [4, 1, 1]}, "material": {"law": "neo-hookean", "E": 1e4, "nu": 0.3},
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}]})
>>> s = StableNeoHookean(scene)
>>> bool(abs(s.internal(s.x0)).max() < 1e-9), abs(s.strain_energy(s.x0)) < 1e-15
(True, True)
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from springfem.loads import external_forces, has_follower_loads, lumped_masses
from springfem.scene import Scene

from .constraints import (
    cofactor,
    deformation_gradients,
    energy_density,
    first_piola,
    rest_shape,
    stable_neo_hookean,
)

#: Levi-Civita symbol.
_EPS = np.zeros((3, 3, 3))
for _i, _j, _k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
    _EPS[_i, _j, _k], _EPS[_i, _k, _j] = 1.0, -1.0


class StableNeoHookean:
    """P1 stable neo-Hookean of a scene (see the module docstring).

    Parameters
    ----------
    scene
        Mesh, isotropic material (its ``mu``, ``lam``), supports and loads.
    """

    def __init__(self, scene: Scene):
        self.scene = scene
        mesh = scene.mesh
        self.tets = np.ascontiguousarray(mesh.tets, dtype=np.int64)
        self.x0 = np.array(mesh.points, dtype=float)
        self.n_points = self.x0.shape[0]
        self.G, self.V = rest_shape(self.x0, self.tets)
        self.mu, self.lam, self.gamma = stable_neo_hookean(scene.material.mu, scene.material.lam)
        self.masses = lumped_masses(scene)
        self.fixed_dofs, self._fixed_values = scene.dirichlet()
        self._follower = has_follower_loads(scene)
        self._f_dead = None if self._follower else external_forces(scene)
        dofs = (3 * self.tets[:, :, None] + np.arange(3)).reshape(-1, 12)
        self._rows = np.repeat(dofs, 12, axis=1).ravel()
        self._cols = np.tile(dofs, (1, 12)).ravel()

    def _g(self) -> np.ndarray:
        return np.concatenate([-self.G.sum(axis=1, keepdims=True), self.G], axis=1)

    def internal(self, x: np.ndarray) -> np.ndarray:
        """Internal nodal forces ``-dE/dx`` ``(n, 3)``."""
        F = deformation_gradients(x, self.tets, self.G)
        P = first_piola(F, self.mu, self.lam, self.gamma)
        fe = -self.V[:, None, None] * np.einsum("kcd,kad->kac", P, self._g())
        f = np.zeros((self.n_points, 3))
        np.add.at(f, self.tets, fe)
        return f

    def strain_energy(self, x: np.ndarray) -> float:
        """``sum_e V_e psi(F_e)``."""
        F = deformation_gradients(x, self.tets, self.G)
        return float(np.sum(self.V * energy_density(F, self.mu, self.lam, self.gamma)))

    def prescribed(self, scale: float) -> np.ndarray:
        return self.x0.ravel()[self.fixed_dofs] + scale * self._fixed_values

    def external(self, x: np.ndarray, scale: float = 1.0) -> np.ndarray:
        """External nodal force ``(n, 3)`` times ``scale`` (follower pressure at ``x``)."""
        if self._f_dead is not None:
            return scale * self._f_dead
        return external_forces(self.scene, x=np.asarray(x).reshape(-1, 3), scale=scale)

    def forces(self, x: np.ndarray, v: np.ndarray | None = None, scale: float = 1.0) -> np.ndarray:
        x = np.asarray(x, dtype=float).reshape(self.n_points, 3)
        return self.internal(x) + self.external(x, scale)

    def energy(self, x: np.ndarray, scale: float = 1.0) -> float | None:
        if self._follower:
            return None
        x = np.asarray(x, dtype=float).reshape(self.n_points, 3)
        return self.strain_energy(x) - scale * float(np.sum(self._f_dead * (x - self.x0)))

    def tangent_moduli(self, F: np.ndarray) -> np.ndarray:
        """``A_iJkL = dP_iJ / dF_kL`` ``(m, 3, 3, 3, 3)``."""
        J = np.linalg.det(F)
        cof = cofactor(F)
        A = self.mu * np.einsum("ik,jl->ijkl", np.eye(3), np.eye(3))[None]
        A = A + self.lam * np.einsum("mij,mkl->mijkl", cof, cof)
        # d cof_iJ / d F_kL = eps_ikm eps_JLN F_mN
        dcof = np.einsum("ikm,jln,pmn->pijkl", _EPS, _EPS, F)
        return A + (self.lam * (J - self.gamma))[:, None, None, None, None] * dcof

    def stiffness(self, x: np.ndarray, scale: float = 1.0) -> sp.csr_matrix | None:
        """The consistent tangent ``-d forces/dx`` (``None`` with follower loads: the
        solvers then take a finite-difference Jacobian)."""
        return None if self._follower else self.internal_stiffness(x)

    def internal_stiffness(self, x: np.ndarray) -> sp.csr_matrix:
        """``-d internal/dx``: the tangent of the strain energy alone."""
        F = deformation_gradients(x, self.tets, self.G)
        A = self.tangent_moduli(F)
        g = self._g()
        Ke = np.einsum("kaj,kijcl,kbl->kaibc", g, A, g) * self.V[:, None, None, None, None]
        n = 3 * self.n_points
        K = sp.csr_matrix((Ke.reshape(-1, 12, 12).ravel(), (self._rows, self._cols)), (n, n))
        K.sum_duplicates()
        return K

    def element_nodes(self) -> np.ndarray:
        return self.tets

    def post_step(self, x: np.ndarray, dt: float) -> None:
        """Nothing to update."""


__all__ = ["StableNeoHookean"]
