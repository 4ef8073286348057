"""Co-rotational P1 of a scene as a :class:`~springfem.mechanics.MechanicalSystem`.

Linear elasticity in each element's rotated frame (the "large" method of SOFA's
``TetrahedronFEMForceField``; Müller & Gross 2004, Irving et al. 2004 for inversion): forces
from :mod:`corotational.kernel`, lumped masses ``rho V / 4``, the scene's Dirichlet
conditions and P1 loads of the core. Two tangents (``tangent``):

``consistent``
    the exact derivative of the forces, rotation included: with ``S = R^T F`` and
    ``A = R^T dF``, ``dR = R [w]x`` where ``(tr S I - S) w = (A_21 - A_12, A_02 - A_20,
    A_10 - A_01)`` (the skew part of ``A = W S + dS``), then ``d eps = sym(A - W S)``,
    ``dP = dR sigma + R C : d eps``; Newton converges quadratically. For the isotropic law
    the forces are the gradient of ``sum_e V/2 eps : C : eps`` (the energy is isotropic in
    the signed singular values, so ``P = R sigma`` is its first Piola stress) and the
    tangent is symmetric; for the transversely isotropic law they are not a gradient
    (``sigma S`` is not symmetric), and the tangent is not symmetric.
``warped``
    the warped stiffness ``R_e K_e R_e^T`` (the rotation held fixed): symmetric positive
    semi-definite, cheaper, and a quasi-Newton method (linear convergence).

Examples
--------
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({"mesh": {"generator": "box", "size": [0.1, 0.01, 0.01],
...     "divisions": [4, 1, 1]}, "material": {"law": "linear", "E": 1e4, "nu": 0.3},
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}]})
>>> s = Corotational(scene)
>>> bool(abs(s.internal(s.x0)).max() < 1e-12), s.energy(s.x0)  # round-off at rest
(True, 0.0)
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import scipy.sparse as sp

from springfem.errors import InputError
from springfem.loads import external_forces, has_follower_loads, lumped_masses
from springfem.materials import material_matrix
from springfem.materials.tissue import TISSUE_LAWS
from springfem.scene import Scene

from .kernel import (
    VOIGT,
    force_kernel,
    gradients,
    isotropic_d,
    shape_gradients,
    stress,
    tangent_kernel,
)
from .polar import rotations

Tangent = Literal["consistent", "warped"]
TANGENTS = ("consistent", "warped")
#: Material laws co-rotational P1 takes: their small-strain matrix (neo-Hookean: its E, nu).
LAWS = ("linear", "transverse-linear", "neo-hookean")


def why_not(scene: Scene) -> str | None:
    """Why co-rotational P1 cannot solve ``scene`` (``None``: it can).

    Parameters
    ----------
    scene
        The scene.

    Returns
    -------
    str or None
    """
    law = scene.material.law
    if law in TISSUE_LAWS:
        return (
            f"model corotational: linear elasticity in a rotated frame has no {law} law "
            "(its exponential stiffening); it takes linear, transverse-linear, neo-hookean"
        )
    if law not in LAWS:
        return f"model corotational: no {law} law; it takes {', '.join(LAWS)}"
    return None


class Corotational:
    """Co-rotational linear P1 tets of a scene (see the module docstring).

    Parameters
    ----------
    scene
        Mesh, material (isotropic ``E, nu`` or the transverse constants with the scene's
        frames), boundaries and loads.
    tangent
        ``consistent`` or ``warped``.

    Attributes
    ----------
    isotropic
        Whether the law is isotropic (the forces are then an energy's gradient).
    last_inverted
        Elements with ``det F <= 0`` at the last force evaluation (they keep a force: the
        signed rotation pushes them back).
    """

    def __init__(self, scene: Scene, tangent: Tangent = "consistent"):
        why = why_not(scene)
        if why is not None:
            raise InputError(why)
        if tangent not in TANGENTS:
            raise InputError(f"corotational tangent {tangent!r} is not one of consistent, warped")
        self.scene = scene
        self.tangent = tangent
        mesh = scene.mesh
        self.tets = np.ascontiguousarray(mesh.tets, dtype=np.int64)
        self.x0 = np.array(mesh.points, dtype=float)
        self.n_points = self.x0.shape[0]
        self.G, self.V = shape_gradients(self.x0, self.tets)
        if np.any(self.V <= 0):
            k = int(np.flatnonzero(self.V <= 0)[0])
            raise InputError(f"element {k} has non-positive volume {self.V[k]:.3g} at rest")
        mat = scene.material
        self.isotropic = mat.law != "transverse-linear"
        if self.isotropic:
            self.D = isotropic_d(float(mat.mu), float(mat.lam))
        else:
            self.D = np.ascontiguousarray(material_matrix(mat, np.asarray(scene.frames)))
        self._per_element = self.D.shape[0] > 1
        self.masses = lumped_masses(scene)
        self.fixed_dofs, self._fixed_values = scene.dirichlet()
        self._follower = has_follower_loads(scene)
        self._f_dead = None if self._follower else external_forces(scene)
        self._rows, self._cols = self._pattern()
        self.last_inverted = 0
        self.steps = 0
        self.time = 0.0

    @property
    def n_elements(self) -> int:
        return self.tets.shape[0]

    # -- forces --------------------------------------------------------------------------
    def internal(self, x: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Internal nodal forces ``(n, 3)`` (the compiled kernel)."""
        x = np.ascontiguousarray(x, dtype=np.float64).reshape(self.n_points, 3)
        if out is None:
            out = np.empty((self.n_points, 3))
        self.last_inverted = int(
            force_kernel(x, self.tets, self.G, self.V, self.D, self._per_element, out)
        )
        return out

    def prescribed(self, scale: float) -> np.ndarray:
        return self.x0.ravel()[self.fixed_dofs] + scale * self._fixed_values

    def external(self, x: np.ndarray, scale: float = 1.0) -> np.ndarray:
        """External nodal force ``(n, 3)`` times ``scale`` (follower pressure at ``x``)."""
        if self._f_dead is not None:
            return scale * self._f_dead
        return external_forces(self.scene, x=np.asarray(x).reshape(-1, 3), scale=scale)

    def forces(self, x: np.ndarray, v: np.ndarray | None = None, scale: float = 1.0) -> np.ndarray:
        """Internal plus external nodal forces (no viscous damping: ``v`` is not used)."""
        f = self.internal(x)
        f += self.external(x, scale)
        return f

    def strain(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(F, R, eps)`` per element at positions ``x`` (numpy)."""
        F = gradients(x, self.tets, self.G)
        R = rotations(F)
        S = np.einsum("kji,kjl->kil", R, F)
        return F, R, 0.5 * (S + S.transpose(0, 2, 1)) - np.eye(3)

    def strain_energy(self, x: np.ndarray) -> float:
        """``sum_e V_e eps : C : eps / 2`` with ``eps = sym(R^T F) - I``."""
        _, _, eps = self.strain(x)
        return float(0.5 * np.sum(self.V * np.einsum("kij,kij->k", eps, stress(eps, self.D))))

    def energy(self, x: np.ndarray, scale: float = 1.0) -> float | None:
        """Strain energy minus the dead loads' work; ``None`` for the transversely isotropic
        law (its co-rotational forces are not a gradient) and follower loads."""
        if self._follower or not self.isotropic:
            return None
        x = np.asarray(x, dtype=float).reshape(self.n_points, 3)
        return self.strain_energy(x) - scale * float(np.sum(self._f_dead * (x - self.x0)))

    # -- tangent -------------------------------------------------------------------------
    def _pattern(self) -> tuple[np.ndarray, np.ndarray]:
        dofs = (3 * self.tets[:, :, None] + np.arange(3)).reshape(-1, 12)
        rows, cols = np.repeat(dofs, 12, axis=1).ravel(), np.tile(dofs, (1, 12)).ravel()
        n = 3 * self.n_points
        # the CSR pattern once; each tangent sums its element entries into it (bincount)
        keys, self._slot = np.unique(rows * n + cols, return_inverse=True)
        indptr = np.searchsorted(keys // n, np.arange(n + 1))
        self._csr = (keys % n, indptr)
        return rows, cols

    def element_tangents(self, x: np.ndarray, tangent: Tangent | None = None) -> np.ndarray:
        """Element tangents ``-d f_e / d x_e`` ``(m, 12, 12)`` (DOFs ``3 node + component``),
        from the compiled kernel (:func:`corotational.kernel.tangent_kernel`).

        Parameters
        ----------
        x
            Positions ``(n, 3)``.
        tangent
            ``consistent`` or ``warped`` (default: the system's).

        Returns
        -------
        ndarray
        """
        x = np.ascontiguousarray(x, dtype=np.float64).reshape(self.n_points, 3)
        Ke = np.empty((self.n_elements, 12, 12))
        warped = (tangent or self.tangent) == "warped"
        tangent_kernel(x, self.tets, self.G, self.V, self.D, self._per_element, warped, Ke)
        return Ke

    def element_tangents_numpy(self, x: np.ndarray, tangent: Tangent | None = None) -> np.ndarray:
        """The same element tangents in numpy (the kernel's oracle).

        Parameters
        ----------
        x
            Positions ``(n, 3)``.
        tangent
            ``consistent`` or ``warped`` (default: the system's).

        Returns
        -------
        ndarray
        """
        tangent = tangent or self.tangent
        F, R, eps = self.strain(x)
        S = np.einsum("kji,kjl->kil", R, F)
        sig = stress(eps, self.D)
        m = F.shape[0]
        g = np.concatenate([-self.G.sum(axis=1, keepdims=True), self.G], axis=1)  # (m, 4, 3)
        H = np.trace(S, axis1=1, axis2=2)[:, None, None] * np.eye(3) - S
        Ke = np.empty((m, 12, 12))
        for a in range(4):
            for d in range(3):
                # dF = e_d (x) g_a, A = R^T dF = R[d] (x) g_a
                A = np.einsum("ki,kj->kij", R[:, d, :], g[:, a, :])
                if tangent == "consistent":
                    rhs = np.stack(
                        [A[:, 2, 1] - A[:, 1, 2], A[:, 0, 2] - A[:, 2, 0], A[:, 1, 0] - A[:, 0, 1]],
                        axis=1,
                    )
                    w = _solve3(H, rhs)
                    W = np.zeros((m, 3, 3))
                    W[:, 0, 1], W[:, 0, 2], W[:, 1, 2] = -w[:, 2], w[:, 1], -w[:, 0]
                    W[:, 1, 0], W[:, 2, 0], W[:, 2, 1] = w[:, 2], -w[:, 1], w[:, 0]
                    dS = A - np.einsum("kij,kjl->kil", W, S)
                    dsig = stress(0.5 * (dS + dS.transpose(0, 2, 1)), self.D)
                    dP = np.einsum("kij,kjl->kil", R, np.einsum("kij,kjl->kil", W, sig) + dsig)
                else:
                    dsig = stress(0.5 * (A + A.transpose(0, 2, 1)), self.D)
                    dP = np.einsum("kij,kjl->kil", R, dsig)
                # f_b = -V dP g_b  ->  K[:, (b, i), (a, d)] = V (dP g_b)_i
                Ke[:, :, 3 * a + d] = (
                    self.V[:, None, None] * np.einsum("kil,kbl->kbi", dP, g)
                ).reshape(m, 12)
        return Ke

    def stiffness(self, x: np.ndarray, scale: float = 1.0) -> sp.csr_matrix | None:
        """The tangent ``K = -d forces / dx`` (``None`` with follower loads: the solvers
        then take a finite-difference Jacobian)."""
        if self._follower:
            return None
        Ke = self.element_tangents(x)
        n = 3 * self.n_points
        data = np.bincount(self._slot, weights=Ke.ravel(), minlength=self._csr[0].size)
        return sp.csr_matrix((data, *self._csr), shape=(n, n))

    def element_nodes(self) -> np.ndarray:
        return self.tets

    def post_step(self, x: np.ndarray, dt: float) -> None:
        """Count steps and time."""
        self.steps += 1
        self.time += dt


def _solve3(H: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """``H w = rhs`` per element; ``w = 0`` where ``H`` is singular (a flat element whose
    two smallest signed stretches sum to zero: the rotation's derivative is undefined)."""
    det = np.linalg.det(H)
    ok = np.abs(det) > 1e-12 * np.abs(np.trace(H, axis1=1, axis2=2)) ** 3
    w = np.zeros_like(rhs)
    if ok.any():
        w[ok] = np.linalg.solve(H[ok], rhs[ok][..., None])[..., 0]
    return w


__all__ = ["LAWS", "TANGENTS", "VOIGT", "Corotational", "why_not"]
