"""An example model plug-in: small-strain linear P1 tets in numpy (docs/plugins.rst).

It imports only the core. The system is a :class:`~springfem.mechanics.MechanicalSystem`
(masses, constraints, forces, energy, tangent); :class:`springfem.model_api.SystemModel`
turns it into a model with a static Newton solve and a timed explicit run, and the entry
point ``example-p1 = "springfem_example_model:MODEL"`` of group ``springfem.models`` in
this package's ``pyproject.toml`` makes it known to ``compare``, ``verdict``, sweeps and
the studies.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from springfem.loads import external_forces, lumped_masses
from springfem.model_api import SystemModel


class LinearP1:
    """Linear elastic P1 tets: ``f = f_ext - K (x - X)`` with the isotropic ``K``."""

    def __init__(self, scene):
        mat, mesh = scene.material, scene.mesh
        self.x0 = np.array(mesh.points, dtype=float)
        self.tets = np.asarray(mesh.tets)
        self.masses = lumped_masses(scene)
        self.fixed_dofs, self._values = scene.dirichlet()
        self._f = external_forces(scene)
        E = self.x0[self.tets[:, 1:]] - self.x0[self.tets[:, :1]]  # (m, 3, 3) edge rows
        g = np.linalg.inv(E)  # columns: grad N_1..3
        g = np.concatenate([-g.sum(axis=2, keepdims=True), g], axis=2)  # (m, 3, 4)
        V = np.linalg.det(E) / 6.0
        B = np.zeros((len(V), 6, 12))  # Voigt strain (xx, yy, zz, yz, xz, xy) of u_e
        for a in range(4):
            gx, gy, gz = g[:, 0, a], g[:, 1, a], g[:, 2, a]
            B[:, 0, 3 * a], B[:, 1, 3 * a + 1], B[:, 2, 3 * a + 2] = gx, gy, gz
            B[:, 3, 3 * a + 1], B[:, 3, 3 * a + 2] = gz, gy
            B[:, 4, 3 * a], B[:, 4, 3 * a + 2] = gz, gx
            B[:, 5, 3 * a], B[:, 5, 3 * a + 1] = gy, gx
        mu, lam = float(mat.mu), float(mat.lam)
        D = np.diag([2 * mu] * 3 + [mu] * 3)
        D[:3, :3] += lam
        Ke = V[:, None, None] * np.einsum("kai,ab,kbj->kij", B, D, B)
        dofs = (3 * self.tets[:, :, None] + np.arange(3)).reshape(-1, 12)
        rows, cols = np.repeat(dofs, 12, axis=1), np.tile(dofs, (1, 12))
        n = self.x0.size
        self.K = sp.csr_matrix((Ke.ravel(), (rows.ravel(), cols.ravel())), shape=(n, n))

    def prescribed(self, scale):
        return self.x0.ravel()[self.fixed_dofs] + scale * self._values

    def forces(self, x, v=None, scale=1.0):
        u = (np.asarray(x) - self.x0).ravel()
        return scale * self._f - (self.K @ u).reshape(-1, 3)

    def energy(self, x, scale=1.0):
        u = (np.asarray(x) - self.x0).ravel()
        return 0.5 * u @ (self.K @ u) - scale * float(self._f.ravel() @ u)

    def stiffness(self, x, scale=1.0):
        return self.K

    def element_nodes(self):
        return self.tets

    def post_step(self, x, dt):
        pass


def _applies(scene):
    if scene.material.law != "linear":
        return f"model example-p1: isotropic linear law only (the scene's is {scene.material.law})"
    return None


#: The plug-in (what the entry point names).
MODEL = SystemModel(
    "example-p1", "example plug-in: linear P1 in numpy", LinearP1, applies=_applies, law="linear"
)
