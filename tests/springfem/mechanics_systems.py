"""Independent test systems for the solver tests: springs on the edges of a tet mesh
(exact energy, analytic tangent), written here so the solver tests do not depend on the
spring-model forces; and the bundled stretch-fiber spring model as a fixture."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from springfem.mesh import box_mesh
from springmodel.options import SpringOptions

EDGES = np.array([(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)])


class EdgeSprings:
    """Linear-law springs on mesh edges, geometrically exact (or linearised at rest).

    Spring ``(i, j)``: ``f_i = k (l - L0) d / l`` with ``d = x_j - x_i``, ``f_j = -f_i``;
    energy ``k/2 (l - L0)^2``. Optional relative damping along the spring
    ``c ((v_j - v_i) . e) e``, a dead load ``f_ext * scale``, prescribed displacements
    ``u_presc * scale`` and a circulatory (non-gradient) load ``q * scale * e_z x (x - c)``.
    """

    def __init__(
        self,
        points: np.ndarray,
        tets: np.ndarray,
        fixed_dofs: np.ndarray,
        k: np.ndarray | float = 1.0,
        masses: np.ndarray | None = None,
        f_ext: np.ndarray | None = None,
        u_presc: np.ndarray | None = None,
        edges: np.ndarray | None = None,
        linear: bool = False,
        analytic: bool = True,
        damping: float = 0.0,
        circulation: float = 0.0,
    ):
        self.x0 = np.asarray(points, dtype=float)
        n = self.x0.shape[0]
        self.tets = np.asarray(tets, dtype=np.int64)
        if edges is None:
            e = np.sort(self.tets[:, EDGES].reshape(-1, 2), axis=1)
            edges = np.unique(e, axis=0)
            edges = edges[edges[:, 0] != edges[:, 1]]
        self.i, self.j = edges[:, 0], edges[:, 1]
        self.L0 = np.linalg.norm(self.x0[self.j] - self.x0[self.i], axis=1)
        self.k = np.broadcast_to(np.asarray(k, dtype=float), self.L0.shape).copy()
        self.masses = np.ones(n) if masses is None else np.asarray(masses, dtype=float)
        self.fixed_dofs = np.asarray(fixed_dofs, dtype=np.int64)
        self.f_ext = np.zeros((n, 3)) if f_ext is None else np.asarray(f_ext, dtype=float)
        self.u_presc = np.zeros(self.fixed_dofs.size) if u_presc is None else u_presc
        self.linear = linear
        self.analytic = analytic
        self.damping = damping
        self.circulation = circulation
        self.centre = self.x0.mean(axis=0)
        self.K0 = self._assemble(self.x0)

    def _assemble(self, x: np.ndarray) -> sp.csr_matrix:
        d = x[self.j] - x[self.i]
        l = np.linalg.norm(d, axis=1)
        e = d / l[:, None]
        ee = e[:, :, None] * e[:, None, :]
        ke = self.k[:, None, None] * (ee + (1 - self.L0 / l)[:, None, None] * (np.eye(3) - ee))
        n3 = 3 * self.x0.shape[0]
        r = np.arange(3)
        rows, cols, vals = [], [], []
        for a, b, sgn in ((self.i, self.i, 1), (self.j, self.j, 1), (self.i, self.j, -1),
                          (self.j, self.i, -1)):  # fmt: skip
            shape = (a.size, 3, 3)
            rows.append(np.broadcast_to(3 * a[:, None, None] + r[None, :, None], shape))
            cols.append(np.broadcast_to(3 * b[:, None, None] + r[None, None, :], shape))
            vals.append(sgn * ke)
        return sp.csr_matrix(
            (np.concatenate([v.ravel() for v in vals]),
             (np.concatenate([v.ravel() for v in rows]),
              np.concatenate([v.ravel() for v in cols]))),
            shape=(n3, n3),
        )  # fmt: skip

    def prescribed(self, scale: float) -> np.ndarray:
        return self.x0.reshape(-1)[self.fixed_dofs] + scale * self.u_presc

    def forces(self, x, v=None, scale=1.0):
        x = np.asarray(x, dtype=float).reshape(-1, 3)
        if self.linear:
            f = -(self.K0 @ (x - self.x0).reshape(-1)).reshape(-1, 3)
            e = self.x0[self.j] - self.x0[self.i]
            e = e / np.linalg.norm(e, axis=1)[:, None]
        else:
            d = x[self.j] - x[self.i]
            l = np.linalg.norm(d, axis=1)
            e = d / l[:, None]
            g = (self.k * (l - self.L0))[:, None] * e
            f = np.zeros_like(x)
            np.add.at(f, self.i, g)
            np.add.at(f, self.j, -g)
        if v is not None and self.damping:
            v = np.asarray(v).reshape(-1, 3)
            g = self.damping * np.einsum("ij,ij->i", v[self.j] - v[self.i], e)[:, None] * e
            np.add.at(f, self.i, g)
            np.add.at(f, self.j, -g)
        f += scale * self.f_ext
        if self.circulation:
            r = x - self.centre
            f += scale * self.circulation * np.column_stack([-r[:, 1], r[:, 0], 0 * r[:, 0]])
        return f

    def energy(self, x, scale=1.0):
        if self.circulation:
            return None
        x = np.asarray(x, dtype=float).reshape(-1, 3)
        u = (x - self.x0).reshape(-1)
        work = scale * float(self.f_ext.reshape(-1) @ u)
        if self.linear:
            return 0.5 * float(u @ (self.K0 @ u)) - work
        l = np.linalg.norm(x[self.j] - x[self.i], axis=1)
        return 0.5 * float(np.sum(self.k * (l - self.L0) ** 2)) - work

    def stiffness(self, x, scale=1.0):
        if not self.analytic or self.circulation:
            return None
        return self.K0.copy() if self.linear else self._assemble(np.asarray(x).reshape(-1, 3))

    def element_nodes(self):
        return self.tets

    def post_step(self, x, dt):
        pass


def beam(
    divisions=(6, 2, 2),
    size=(3.0, 1.0, 1.0),
    seed=0,
    load=(0.0, 0.0, 0.0),
    stiff_edges_near=None,
    **kw,
) -> EdgeSprings:
    """An irregular box of edge springs, clamped at x = 0, dead load on the x = max face."""
    rng = np.random.default_rng(seed)
    mesh = box_mesh(size, divisions, split="six")
    h = min(s / d for s, d in zip(size, divisions))
    pts = mesh.points + rng.uniform(-0.15, 0.15, mesh.points.shape) * h  # keeps orientation
    n = pts.shape[0]
    clamp = np.flatnonzero(mesh.points[:, 0] < 1e-9)
    tip = np.flatnonzero(mesh.points[:, 0] > size[0] - 1e-9)
    fixed = (3 * clamp[:, None] + np.arange(3)).ravel()
    f_ext = np.zeros((n, 3))
    f_ext[tip] = np.asarray(load) / tip.size
    vol = np.abs(np.linalg.det(pts[mesh.tets[:, 1:]] - pts[mesh.tets[:, :1]])) / 6
    masses = np.zeros(n)
    np.add.at(masses, mesh.tets, vol[:, None] / 4)
    sys = EdgeSprings(pts, mesh.tets, fixed, masses=masses, f_ext=f_ext, **kw)
    sys.k = (1.0 + 0.3 * rng.uniform(-1, 1, sys.k.size)) / sys.L0
    if stiff_edges_near is not None:  # a weak spot for explicit stability: one stiff tet
        t = mesh.tets[stiff_edges_near]
        on = np.isin(sys.i, t) & np.isin(sys.j, t)
        sys.k[on] *= 30.0
    sys.K0 = sys._assemble(sys.x0)
    return sys


def chain(k1=3.0, k2=2.0, m1=1.5, m2=0.5, masses_only_x=True, **kw) -> EdgeSprings:
    """Node 0 fixed, springs 0-1 and 1-2 along x; only the x motion of nodes 1, 2 is free."""
    pts = np.array([[0.0, 0, 0], [1.0, 0, 0], [2.0, 0, 0]])
    tets = np.array([[0, 1, 1, 1], [1, 2, 2, 2]])  # degenerate "elements": the coupling pattern
    fixed = np.array([0, 1, 2, 4, 5, 7, 8])
    return EdgeSprings(
        pts, tets, fixed, k=np.array([k1, k2]), masses=np.array([1.0, m1, m2]),
        edges=np.array([[0, 1], [1, 2]]), **kw,
    )  # fmt: skip


def oscillator(k=4.0, m=0.25, **kw) -> EdgeSprings:
    """One free DOF: mass m on a spring k (omega = sqrt(k / m))."""
    pts = np.array([[0.0, 0, 0], [1.0, 0, 0]])
    return EdgeSprings(
        pts, np.array([[0, 1, 1, 1]]), np.array([0, 1, 2, 4, 5]), k=k,
        masses=np.array([1.0, m]), edges=np.array([[0, 1]]), **kw,
    )  # fmt: skip


def free_block(sys: EdgeSprings, K: sp.spmatrix) -> tuple[np.ndarray, sp.csr_matrix]:
    free = np.setdiff1d(np.arange(3 * sys.x0.shape[0]), sys.fixed_dofs)
    return free, sp.csr_matrix(K)[free][:, free]


def random_displacement(sys: EdgeSprings, amp: float, seed: int = 1) -> np.ndarray:
    x = sys.x0 + amp * np.random.default_rng(seed).standard_normal(sys.x0.shape)
    x.reshape(-1)[sys.fixed_dofs] = sys.prescribed(1.0)
    return x


def linear_reference(sys: EdgeSprings) -> np.ndarray:
    """Direct sparse solve K_ff u_f = f_f - K_fc u_c of the linearised system."""
    free, Kff = free_block(sys, sys.K0)
    K = sp.csr_matrix(sys.K0)
    u = np.zeros(3 * sys.x0.shape[0])
    u[sys.fixed_dofs] = sys.u_presc
    rhs = sys.f_ext.reshape(-1)[free] - K[free][:, sys.fixed_dofs] @ sys.u_presc
    u[free] = spla.spsolve(Kff.tocsc(), rhs)
    return u


def prescribe_tip(sys: EdgeSprings, value) -> None:
    """Clamp plus a prescribed displacement of the x = max face."""
    tip = np.flatnonzero(sys.x0[:, 0] > sys.x0[:, 0].max() - 0.6)
    tip = tip[np.abs(sys.x0[tip, 0] - sys.x0[tip, 0].max()) < 0.3]
    extra = (3 * tip[:, None] + np.arange(3)).ravel()
    sys.fixed_dofs = np.concatenate([sys.fixed_dofs, extra])
    sys.u_presc = np.concatenate([np.zeros(sys.fixed_dofs.size - extra.size),
                                  np.tile(value, tip.size)])  # fmt: skip


SCENES = Path(__file__).resolve().parents[2] / "studies" / "scenes"


def stretch_fiber_model():
    """The bundled stretch-fiber scene with the energy-consistent torsion (conservative)."""
    from springfem.scene import load_scene
    from springmodel.model import SpringModel

    scene = load_scene(SCENES / "stretch-fiber.toml")
    return SpringModel(scene, replace(SpringOptions.of(scene), torsion="energy"), parallel=False)
