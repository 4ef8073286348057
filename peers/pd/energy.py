"""The energies Projective Dynamics minimises, in numpy, and a mechanical system of each (the
Newton answer its rest state is checked against).

``arap``: Projective Dynamics' own energy (Bouaziz et al. 2014), two constraints per tet on
``F`` with their projections: the nearest rotation ``R(F)`` (strain, weight ``2 mu V``) and the
nearest matrix of determinant one ``S(F)`` (volume, weight ``3 lam V``)::

    W = V [mu |F - R(F)|^2 + 3 lam / 2 |F - S(F)|^2],   P = 2 mu (F - R) + 3 lam (F - S)

(the gradient of half a squared distance to a set is ``F`` minus its nearest point). At small
strain ``|F - R|^2 ~ |eps|^2`` and ``|F - S|^2 ~ tr(eps)^2 / 3``: the scene's linear elasticity.
Both projections come from the signed singular values ``F = U diag(s) V^T`` (``det U =
det V = 1``, the last ``s`` negative for an inverted tet): ``R = U V^T``;
``S = U diag(s') V^T`` with ``s'_i = (s_i + sqrt(s_i^2 + 4 k)) / 2`` and ``k`` the root of
``prod s'_i = 1`` (the Lagrange condition ``s'_i - s_i = k / s'_i``; Newton on ``sum ln s'_i``;
far from the set the smallest takes the other root, :func:`unit_determinant`).

``neo-hookean``: the coupled neo-Hookean density of reference_fem's P1-NH,
``psi = mu/2 (I_C - 3) - mu ln J + lam/2 ln^2 J`` (``+inf`` for ``J <= 0``), which the
quasi-Newton form minimises (Liu, Bouaziz & Kavan 2017).

Examples
--------
>>> import numpy as np
>>> F = np.diag([1.2, 0.9, 1.1])[None]
>>> R, S = projections(F)
>>> bool(np.allclose(R, np.eye(3))), round(float(np.linalg.det(S[0])), 12)
(True, 1.0)
"""

from __future__ import annotations

import numpy as np

from springfem.loads import external_forces, has_follower_loads, lumped_masses
from springfem.scene import Scene

from ..xpbd.constraints import deformation_gradients, rest_shape

ENERGIES = ("arap", "neo-hookean")


def signed_svd(F: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``F = U diag(s) V^T`` with rotations ``U, V`` (``(m, 3, 3)`` each) and ``s`` ``(m, 3)``
    (the smallest carries the sign of ``det F``)."""
    U, s, Vt = np.linalg.svd(F)
    dU, dV = np.linalg.det(U), np.linalg.det(Vt)
    U[:, :, 2] *= dU[:, None]
    Vt[:, 2, :] *= dV[:, None]
    s = s.copy()
    s[:, 2] *= dU * dV
    return U, s, Vt


def unit_determinant(s: np.ndarray) -> np.ndarray:
    """The nearest ``s'`` to ``s`` ``(m, 3)`` with ``prod s' = 1`` (module docstring), by
    bisection on ``k``: independent of the compiled Newton of
    :func:`peers.pd.kernels.unit_determinant`. Where even ``k = -min s_i^2 / 4`` leaves
    ``prod s' > 1`` (``s`` far outside), the smallest ``|s_i|`` takes the other root
    ``(s_i - sqrt(s_i^2 + 4 k)) / 2`` (both roots are positive for ``k < 0``), ``k`` in
    ``[-min s_i^2 / 4, 0)``."""
    m = np.argmin(np.abs(s), axis=1)
    sign = np.ones_like(s)
    lo = -0.25 * (s**2).min(axis=1)

    def phi(k):
        sp = 0.5 * (s + sign * np.sqrt(np.maximum(s**2 + 4.0 * k[:, None], 0.0)))
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.log(np.maximum(sp, 0.0)).sum(axis=1)

    outside = phi(lo) > 0
    sign[outside, m[outside]] = -1.0
    hi = np.where(outside, 0.0, 1.0)
    while np.any(~outside & (phi(hi) < 0)):
        hi = np.where(~outside & (phi(hi) < 0), 4.0 * hi, hi)
    for _ in range(64):  # the bracket's width times 2^-64: below the round-off of k
        mid = 0.5 * (lo + hi)
        up = (phi(mid) > 0) != outside  # phi increases on the + branch, falls on the -
        hi, lo = np.where(up, mid, hi), np.where(up, lo, mid)
    k = 0.5 * (lo + hi)
    return 0.5 * (s + sign * np.sqrt(np.maximum(s**2 + 4.0 * k[:, None], 0.0)))


def projections(F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The nearest rotation ``R`` and nearest unit-determinant matrix ``S`` of each ``F``."""
    U, s, Vt = signed_svd(F)
    R = U @ Vt
    S = np.einsum("kij,kj,kjl->kil", U, unit_determinant(s), Vt)
    return R, S


def density(F: np.ndarray, mu: float, lam: float, energy: str) -> np.ndarray:
    """``psi(F)`` ``(m,)`` of ``arap`` or ``neo-hookean`` (module docstring)."""
    if energy == "arap":
        R, S = projections(F)
        return mu * np.sum((F - R) ** 2, axis=(1, 2)) + 1.5 * lam * np.sum(
            (F - S) ** 2, axis=(1, 2)
        )
    J = np.linalg.det(F)
    lnJ = np.log(np.where(J > 0, J, 1.0))
    psi = 0.5 * mu * (np.einsum("kij,kij->k", F, F) - 3.0) - mu * lnJ + 0.5 * lam * lnJ**2
    return np.where(J > 0, psi, np.inf)


def first_piola(F: np.ndarray, mu: float, lam: float, energy: str) -> np.ndarray:
    """``P = dpsi/dF`` ``(m, 3, 3)``."""
    if energy == "arap":
        R, S = projections(F)
        return 2.0 * mu * (F - R) + 3.0 * lam * (F - S)
    J = np.linalg.det(F)
    FinvT = np.linalg.inv(F).transpose(0, 2, 1)
    lnJ = np.log(np.where(J > 0, J, 1.0))
    return mu * (F - FinvT) + (lam * lnJ)[:, None, None] * FinvT


class PDEnergy:
    """P1 tets of a scene with ``arap`` or ``neo-hookean`` energy, lumped masses, the scene's
    loads and supports: a :class:`~springfem.mechanics.MechanicalSystem` without an analytic
    tangent (Newton then takes the core's coloured finite-difference Jacobian).

    Parameters
    ----------
    scene
        Mesh, isotropic material (``mu``, ``lam``), supports, loads.
    energy
        One of :data:`ENERGIES`.
    """

    def __init__(self, scene: Scene, energy: str = "arap"):
        self.scene = scene
        self.energy_name = energy
        self.tets = np.ascontiguousarray(scene.mesh.tets, dtype=np.int64)
        self.x0 = np.array(scene.mesh.points, dtype=float)
        self.n_points = self.x0.shape[0]
        self.G, self.V = rest_shape(self.x0, self.tets)
        self.mu, self.lam = float(scene.material.mu), float(scene.material.lam)
        self.masses = lumped_masses(scene)
        self.fixed_dofs, self._fixed_values = scene.dirichlet()
        self._follower = has_follower_loads(scene)
        self._f_dead = None if self._follower else external_forces(scene)

    def strain_energy(self, x: np.ndarray) -> float:
        """``sum_e V_e psi(F_e)`` (``inf`` when an element is inverted under neo-Hookean)."""
        F = deformation_gradients(x, self.tets, self.G)
        return float(np.sum(self.V * density(F, self.mu, self.lam, self.energy_name)))

    def internal(self, x: np.ndarray) -> np.ndarray:
        """Internal nodal forces ``-dE/dx`` ``(n, 3)``."""
        F = deformation_gradients(x, self.tets, self.G)
        P = first_piola(F, self.mu, self.lam, self.energy_name)
        g = np.concatenate([-self.G.sum(axis=1, keepdims=True), self.G], axis=1)
        fe = -self.V[:, None, None] * np.einsum("kcd,kad->kac", P, g)
        f = np.zeros((self.n_points, 3))
        np.add.at(f, self.tets, fe)
        return f

    def prescribed(self, scale: float) -> np.ndarray:
        return self.x0.ravel()[self.fixed_dofs] + scale * self._fixed_values

    def external(self, x: np.ndarray, scale: float = 1.0) -> np.ndarray:
        """External nodal force ``(n, 3)`` times ``scale``."""
        if self._f_dead is not None:
            return scale * self._f_dead
        return external_forces(self.scene, x=np.asarray(x).reshape(-1, 3), scale=scale)

    def forces(self, x: np.ndarray, v: np.ndarray | None = None, scale: float = 1.0) -> np.ndarray:
        x = np.asarray(x, dtype=float).reshape(self.n_points, 3)
        return self.internal(x) + self.external(x, scale)

    def energy(self, x: np.ndarray, scale: float = 1.0) -> float | None:
        if self._f_dead is None:
            return None
        x = np.asarray(x, dtype=float).reshape(self.n_points, 3)
        return self.strain_energy(x) - scale * float(np.sum(self._f_dead * (x - self.x0)))

    def stiffness(self, x: np.ndarray, scale: float = 1.0) -> None:
        """``None``: no analytic tangent."""
        return None

    def element_nodes(self) -> np.ndarray:
        return self.tets

    def post_step(self, x: np.ndarray, dt: float) -> None:
        """Nothing to update."""


__all__ = ["ENERGIES", "PDEnergy", "density", "first_piola", "projections", "signed_svd",
           "unit_determinant"]  # fmt: skip
