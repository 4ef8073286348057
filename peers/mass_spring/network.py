"""The edge mass–spring network of a scene.

Every edge ``c`` of the tet mesh carries a spring of rest length ``l_c`` with the energy
``k_c / 2 (|x_j - x_i| - l_c)^2`` and, optionally, a dashpot along it with the coefficient
``beta k_c`` (stiffness-proportional damping, ``beta`` in seconds). Stiffness: the volume
form of van Gelder's rule (van Gelder 1998, J. Graphics Tools 3(2), for triangles
``k_c = E sum_{e ∋ c} A_e / |c|^2``), ``k_c = E sum_{e ∋ c} V_e / l_c^2`` over the tets
sharing the edge. A network of central springs obeys the Cauchy relations (Born & Huang
1954): on a periodic lattice its small-strain elasticity tensor is
``C_ijkl = 1/V_cell sum_c k_c l_c^2 n_i n_j n_k n_l``, fully symmetric, so an isotropic
network has ``nu = 1/4`` and no choice of ``k_c`` matches a general isotropic material
(Lloyd, Székely & Harders 2007, IEEE TVCG 13(5), who derive best-fit constants per
element shape). docs/peers.rst#mass-spring reports what this gives on the scenes.

Examples
--------
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({"mesh": {"generator": "box", "size": [1.0, 1.0, 1.0],
...     "divisions": [1, 1, 1]}, "material": {"law": "linear", "E": 1.0, "nu": 0.3},
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}]})
>>> s = MassSpring(scene, calibration="van-gelder")
>>> s.edges.shape[0], round(float(s.k.sum()), 12)  # body diagonal 1/3, faces 6/6, edges 3
(19, 4.333333333333)
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from springfem.errors import InputError
from springfem.loads import external_forces, has_follower_loads, lumped_masses
from springfem.scene import Scene

CALIBRATIONS = ("van-gelder", "tensor-fit")
#: Laws the network takes (their E sets the springs; nu cannot be matched, see above).
LAWS = ("linear", "neo-hookean")
_PAIRS = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))


def why_not(scene: Scene) -> str | None:
    """Why the network cannot take ``scene`` (``None``: it can).

    Parameters
    ----------
    scene
        The scene.

    Returns
    -------
    str or None
    """
    law = scene.material.law
    if law not in LAWS:
        return (
            f"model mass-spring: springs calibrated from E have no {law} law; "
            f"it takes {', '.join(LAWS)}"
        )
    return None


def mesh_edges(tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The unique edges ``(e, 2)`` (sorted node pairs) and, per tet and local edge, the index
    of its edge ``(m, 6)``.

    Parameters
    ----------
    tets
        ``(m, 4)``.

    Returns
    -------
    edges, tet_edges
    """
    tets = np.asarray(tets, dtype=np.int64)
    pairs = np.stack([tets[:, list(p)] for p in _PAIRS], axis=1)  # (m, 6, 2)
    pairs.sort(axis=2)
    edges, inverse = np.unique(pairs.reshape(-1, 2), axis=0, return_inverse=True)
    return edges, inverse.reshape(-1, 6)


def van_gelder_stiffness(points: np.ndarray, tets: np.ndarray, E: float) -> np.ndarray:
    """``k_c = E sum_{e ∋ c} V_e / l_c^2`` per edge of :func:`mesh_edges`.

    Parameters
    ----------
    points, tets
        The mesh at rest.
    E
        Young's modulus.

    Returns
    -------
    ndarray
        ``(e,)``.
    """
    points = np.asarray(points, dtype=float)
    edges, tet_edges = mesh_edges(tets)
    x = points[np.asarray(tets)]
    V = np.abs(np.linalg.det(x[:, 1:] - x[:, :1])) / 6.0
    vol = np.bincount(tet_edges.ravel(), weights=np.repeat(V, 6), minlength=edges.shape[0])
    length2 = np.sum((points[edges[:, 1]] - points[edges[:, 0]]) ** 2, axis=1)
    return E * vol / length2


def tensor_fit_stiffness(points: np.ndarray, tets: np.ndarray, lam: float, mu: float) -> np.ndarray:
    """Per edge, the sum over its tets of the springs that best fit each tet's small-strain
    elasticity.

    Under a uniform strain ``ε`` a tet's six springs store
    ``1/2 ε : (Σ_e a_e n_e⊗n_e⊗n_e⊗n_e) : ε`` with ``a_e = k_e l_e²``, the tet
    ``V/2 ε : C : ε``. The ``a_e`` minimise the Frobenius norm of the difference of the two
    tensors: the normal equations ``Σ_f (n_e·n_f)⁴ a_f = V n_e⁴ : C = V (λ + 2μ)``; where
    that gives a negative spring, a non-negative least-squares fit. It matches the element's
    stiffness in the sense of Lloyd, Székely & Harders 2007 (best-fit constants per element
    shape); no choice matches exactly (the Cauchy relations, docs/peers.rst#mass-spring).
    On a regular tetrahedron at ``ν = 1/4`` it gives ``k = (2√2/25) E l``, ``0.96`` times
    van Gelder's ``E V / l²``.

    Parameters
    ----------
    points, tets
        The mesh at rest.
    lam, mu
        The Lamé constants of the isotropic material fitted.

    Returns
    -------
    ndarray
        ``(e,)`` stiffness per edge of :func:`mesh_edges`.

    Examples
    --------
    >>> s = np.sqrt(2.0)
    >>> tet = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]) / s  # edge 2
    >>> k = tensor_fit_stiffness(tet, np.array([[0, 1, 2, 3]]), 0.4, 0.4)  # E = 1, nu = 1/4
    >>> np.allclose(k, 2 * s / 25 * 2.0)
    True
    """
    from scipy.optimize import nnls

    points = np.asarray(points, dtype=float)
    edges, tet_edges = mesh_edges(tets)
    x = points[np.asarray(tets)]
    V = np.abs(np.linalg.det(x[:, 1:] - x[:, :1])) / 6.0
    d = np.stack([x[:, b] - x[:, a] for a, b in _PAIRS], axis=1)  # (m, 6, 3)
    length2 = np.sum(d * d, axis=2)
    n = d / np.sqrt(length2)[..., None]
    G = np.einsum("mei,mfi->mef", n, n) ** 4
    b = np.repeat((V * (lam + 2 * mu))[:, None], 6, axis=1)
    a = np.linalg.solve(G, b[..., None])[..., 0]
    for t in np.flatnonzero((a < 0).any(axis=1)):
        a[t] = nnls(G[t], b[t])[0]
    k = a / length2
    return np.bincount(tet_edges.ravel(), weights=k.ravel(), minlength=edges.shape[0])


class MassSpring:
    """The edge mass–spring network of a scene (see the module docstring).

    Parameters
    ----------
    scene
        Mesh, material (its ``E`` and density), supports, loads.
    calibration
        ``van-gelder`` (:func:`van_gelder_stiffness`, the default) or ``tensor-fit``
        (:func:`tensor_fit_stiffness`: closer to P1 on cube cells, farther on elongated
        and jittered ones, docs/peers.rst#mass-spring).
    damping
        ``beta`` (s): the dashpot of a spring is ``beta k_c`` along it (0: none).
    """

    def __init__(self, scene: Scene, calibration: str = "van-gelder", damping: float = 0.0):
        why = why_not(scene)
        if why is not None:
            raise InputError(why)
        if calibration not in CALIBRATIONS:
            raise InputError(
                f"mass-spring calibration {calibration!r} is not one of {', '.join(CALIBRATIONS)}"
            )
        if not damping >= 0:
            raise InputError(f"mass-spring damping {damping!r} must be >= 0 (seconds)")
        self.scene = scene
        self.damping = float(damping)
        mesh = scene.mesh
        self.x0 = np.array(mesh.points, dtype=float)
        self.n_points = self.x0.shape[0]
        self.tets = np.ascontiguousarray(mesh.tets, dtype=np.int64)
        self.edges, _ = mesh_edges(self.tets)
        d = self.x0[self.edges[:, 1]] - self.x0[self.edges[:, 0]]
        self.rest_length = np.linalg.norm(d, axis=1)
        mat = scene.material
        self.calibration = calibration
        self.k = (
            van_gelder_stiffness(self.x0, self.tets, mat.E)
            if calibration == "van-gelder"
            else tensor_fit_stiffness(self.x0, self.tets, mat.kappa - 2.0 * mat.mu / 3.0, mat.mu)
        )
        self.masses = lumped_masses(scene)
        self.fixed_dofs, self._fixed_values = scene.dirichlet()
        self._follower = has_follower_loads(scene)
        self._f_dead = None if self._follower else external_forces(scene)
        dofs = (3 * self.edges[:, :, None] + np.arange(3)).reshape(-1, 6)
        self._rows = np.repeat(dofs, 6, axis=1).ravel()
        self._cols = np.tile(dofs, (1, 6)).ravel()

    def _geometry(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x = np.asarray(x, dtype=float).reshape(self.n_points, 3)
        d = x[self.edges[:, 1]] - x[self.edges[:, 0]]
        return d, np.linalg.norm(d, axis=1)

    def internal(self, x: np.ndarray, v: np.ndarray | None = None) -> np.ndarray:
        """Spring (and dashpot, given ``v``) forces ``(n, 3)``."""
        d, L = self._geometry(x)
        n = d / L[:, None]
        t = self.k * (L - self.rest_length)
        if v is not None and self.damping > 0:
            v = np.asarray(v, dtype=float).reshape(self.n_points, 3)
            t = t + self.damping * self.k * np.einsum(
                "ei,ei->e", v[self.edges[:, 1]] - v[self.edges[:, 0]], n
            )
        f = np.zeros((self.n_points, 3))
        np.add.at(f, self.edges[:, 0], t[:, None] * n)
        np.add.at(f, self.edges[:, 1], -t[:, None] * n)
        return f

    def strain_energy(self, x: np.ndarray) -> float:
        """``sum_c k_c / 2 (|x_j - x_i| - l_c)^2``."""
        _, L = self._geometry(x)
        return float(0.5 * np.sum(self.k * (L - self.rest_length) ** 2))

    def prescribed(self, scale: float) -> np.ndarray:
        return self.x0.ravel()[self.fixed_dofs] + scale * self._fixed_values

    def external(self, x: np.ndarray, scale: float = 1.0) -> np.ndarray:
        """External nodal force ``(n, 3)`` times ``scale`` (follower pressure at ``x``)."""
        if self._f_dead is not None:
            return scale * self._f_dead
        return external_forces(self.scene, x=np.asarray(x).reshape(-1, 3), scale=scale)

    def forces(self, x: np.ndarray, v: np.ndarray | None = None, scale: float = 1.0) -> np.ndarray:
        return self.internal(x, v) + self.external(x, scale)

    def energy(self, x: np.ndarray, scale: float = 1.0) -> float | None:
        if self._follower:
            return None
        x = np.asarray(x, dtype=float).reshape(self.n_points, 3)
        return self.strain_energy(x) - scale * float(np.sum(self._f_dead * (x - self.x0)))

    def stiffness(self, x: np.ndarray, scale: float = 1.0) -> sp.csr_matrix | None:
        """``-d forces/dx``: per spring ``k (n n^T + (1 - l/L)(I - n n^T))`` in the blocks
        ``[[K, -K], [-K, K]]`` (``None`` with follower loads)."""
        if self._follower:
            return None
        d, L = self._geometry(x)
        n = d / L[:, None]
        nn = np.einsum("ei,ej->eij", n, n)
        Ks = self.k[:, None, None] * (
            nn + (1.0 - self.rest_length / L)[:, None, None] * (np.eye(3) - nn)
        )
        Ke = np.empty((Ks.shape[0], 2, 3, 2, 3))
        Ke[:, 0, :, 0], Ke[:, 1, :, 1], Ke[:, 0, :, 1], Ke[:, 1, :, 0] = Ks, Ks, -Ks, -Ks
        size = 3 * self.n_points
        K = sp.csr_matrix((Ke.ravel(), (self._rows, self._cols)), shape=(size, size))
        K.sum_duplicates()
        return K

    def element_nodes(self) -> np.ndarray:
        return self.tets

    def post_step(self, x: np.ndarray, dt: float) -> None:
        """Nothing to update."""


__all__ = ["CALIBRATIONS", "LAWS", "MassSpring", "mesh_edges", "van_gelder_stiffness", "why_not"]
