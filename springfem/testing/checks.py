"""The checks of :func:`springfem.testing.check_model`, each a function of the model's
system (or solve) returning a :class:`~springfem.testing.report.Check`, and their
tolerances, each with its reason.

Examples
--------
>>> relative_error(np.array([1.0, 2.0]), np.array([1.0, 2.5]))
0.2
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Literal

import numpy as np
import scipy.sparse as sp

from ..mechanics import explicit, linear_static
from ..mechanics.system import MechanicalSystem, free_dofs
from ..mesh.nodal_average import shape_gradients
from ..scene import Scene
from .reference import LinearP1, rotation, scaled_scene
from .report import Check

Rotation = Literal["finite", "infinitesimal"]
SmallStrain = Literal["exact", "limit"]
Tangent = Literal["exact", "approximate"]

#: The deformed states' largest displacement gradient (its spectral norm over the elements):
#: large enough for the nonlinear terms to show, small enough for every law.
STRAIN = 1e-2
#: A rigid motion's internal force, relative to that of a deformation of :data:`STRAIN`:
#: positions of size ``|x|`` carry a rounding of ``1e-16 |x|``, a strain of
#: ``1e-16 |x| / l`` on elements of size ``l``, about ``1e-12`` of the reference's; the
#: margin covers the kernels' cancellations. A force from a real defect is ``O(1)``.
RIGID_TOL = 1e-8
#: The angle (rad) of the infinitesimal rotation ``x0 + a w x (x0 - c)``: it strains a
#: nonlinear model by ``a^2 / 2`` and a linear one not at all.
ANGLE = 1e-6
#: Its force relative to a deformation of gradient ``ANGLE``: ``O(ANGLE)`` for a
#: finite-strain model, rounding (``1e-16 |x| / (l ANGLE)``) for a linear one; a model that
#: is not invariant under rotation gives ``O(1)``.
ANGLE_TOL = 1e-4
#: Forces whose ``f(x0 + 2u) - 2 f(x0 + u)`` stays below this fraction of ``f(x0 + u)``
#: are linear in the positions: such a model is held to infinitesimal rotations only.
LINEAR_TOL = 1e-6
#: The finite-difference step, relative to the smallest element height ``l`` (a sliver's
#: forces change over its height, not over the mean edge: on a Delaunay block with slivers,
#: ``1e-5`` of the mean edge erred by 9e-6). Central differences err by
#: ``(h / l)^2 f''' l^2 / 6``, ``1e-8`` of the derivative for laws whose stiffness changes
#: over a unit strain; rounding adds ``1e-16 |f| / (h K)``, about
#: ``1e-16 STRAIN (L / l) / 1e-4 = 1e-12 L / l``. Measured on Delaunay blocks with
#: ``L / l`` = 70-110: at most 6e-9 (1e-3: 1e-7, truncation; 1e-5: 2e-8, rounding).
FD_STEP = 1e-4
#: The largest central-difference error allowed, relative to the compared vector's norm.
FD_TOL = 1e-6
#: An ``exact`` small-strain claim: the tangent at rest is linear P1's to rounding.
EXACT_TOL = 1e-8
#: The load factor of the ``limit`` small-strain check: the nonlinear remainder of a
#: finite-strain model is ``O(load)``, far below :data:`LIMIT_TOL`.
LIMIT_LOAD = 1e-4
#: A ``limit`` claim's default: the displacement under the tiny load, divided by the load
#: factor, is linear P1's within 1 % (relative L2 over the nodes).
LIMIT_TOL = 1e-2
#: Explicit steps of the energy check (velocity Verlet at :data:`DT_FRACTION` of the stable
#: step: about a half-period of the softest mode on a few hundred tets).
STEPS = 200
#: The time step of the energy check, as a fraction of the stable step ``2 / omega_max``.
DT_FRACTION = 0.25
#: The total energy's largest excursion relative to the initial strain energy ``W0``.
#: Velocity Verlet's energy oscillates, without drift, by up to ``(omega dt)^2 / 4`` of a
#: mode's share in a linear system: 6.7 % for the stiffest mode at ``omega dt = 0.5``;
#: measured 0.3 % (linear P1) to 3.6 % (nodal-averaged springs, incompressible Guccione,
#: slivers) from the smooth start. The margin is for nonlinear systems; what tells a drift
#: from Verlet's oscillation is the scaling with the step (:data:`ENERGY_SCALING`).
ENERGY_TOL = 0.1
#: Halving the step divides Verlet's excursion by 4 (measured 3.98-4.00); a drift, or an
#: energy that is not the forces' potential, does not fall with ``dt^2``. Below
#: :data:`ENERGY_FLOOR` there is nothing to scale (rounding).
ENERGY_SCALING = 3.0
ENERGY_FLOOR = 1e-9


# -- states -------------------------------------------------------------------------------


class Body:
    """The system's geometry and the states the checks evaluate it at."""

    def __init__(self, system: MechanicalSystem, seed: int):
        self.system = system
        self.x0 = np.asarray(system.x0, dtype=float).reshape(-1, 3)
        self.rng = np.random.default_rng(seed)
        nodes = np.asarray(system.element_nodes())[:, :4]
        pairs = [(a, b) for a in range(nodes.shape[1]) for b in range(a)]
        edges = np.unique(np.sort(np.concatenate([nodes[:, p] for p in pairs]), axis=1), axis=0)
        self.edges = edges
        self.nodes = nodes
        self.grads = shape_gradients(self.x0, nodes)  # (m, 4, 3)
        self.h = 1.0 / float(np.abs(self.grads).max())  # about the smallest height
        self.size = float(np.ptp(self.x0, axis=0).max())
        self.centre = self.x0.mean(axis=0)
        self.free = free_dofs(system)

    def internal(self, x: np.ndarray) -> np.ndarray:
        """Internal forces (load factor 0, no velocity)."""
        return np.asarray(self.system.forces(x, None, 0.0), dtype=float).reshape(-1, 3)

    def strained(self, u: np.ndarray, strain: float) -> np.ndarray:
        """``u`` scaled to the largest displacement gradient ``strain`` (a sliver's too)."""
        G = np.einsum("kai,kaj->kij", u[self.nodes], self.grads)
        return u * (strain / float(np.linalg.norm(G, ord=2, axis=(1, 2)).max()))

    def random(self, strain: float) -> np.ndarray:
        """A random displacement of largest gradient ``strain``."""
        return self.strained(self.rng.standard_normal(self.x0.shape), strain)

    def typical(self, strain: float) -> np.ndarray:
        """A random displacement of largest edge strain ``|u_i - u_j| / |X_i - X_j|``
        ``strain``: the forces of a typical element at ``strain``, whatever the slivers
        (the references of the rigid-motion checks)."""
        u = self.rng.standard_normal(self.x0.shape)
        du = u[self.edges[:, 0]] - u[self.edges[:, 1]]
        X = self.x0[self.edges[:, 0]] - self.x0[self.edges[:, 1]]
        return u * (strain / float((np.linalg.norm(du, axis=1) / np.linalg.norm(X, axis=1)).max()))

    def smooth(self, strain: float) -> np.ndarray:
        """A smooth random displacement vanishing at the fixed DOFs (eight neighbour
        averages of a random field), of largest gradient ``strain``."""
        n = len(self.x0)
        e = self.edges
        A = sp.coo_matrix((np.ones(2 * len(e)), (e.ravel(), e[:, ::-1].ravel())), (n, n))
        A = (A + sp.identity(n)).tocsr()
        A = sp.diags(1.0 / np.asarray(A.sum(axis=1)).ravel()) @ A
        u = self.rng.standard_normal(self.x0.shape)
        fixed = np.asarray(self.system.fixed_dofs, dtype=np.int64)
        for _ in range(8):
            u.reshape(-1)[fixed] = 0.0
            u = A @ u
        u.reshape(-1)[fixed] = 0.0
        return self.strained(u, strain)

    def rotated(self, x: np.ndarray, rotvec: np.ndarray) -> np.ndarray:
        """``x`` rotated by ``rotvec`` about the rest centroid."""
        return (x - self.centre) @ rotation(rotvec).T + self.centre


def relative_error(a: np.ndarray, b: np.ndarray) -> float:
    """``max |a - b| / max |b|`` (``inf`` for a nonzero ``a - b`` against a zero ``b``)."""
    d = float(np.abs(np.asarray(a) - np.asarray(b)).max())
    s = float(np.abs(np.asarray(b)).max())
    return d / s if s > 0 else (0.0 if d == 0 else float("inf"))


def _verdict(name: str, value: float, tol: float, what: str) -> Check:
    ok = bool(value <= tol)
    word = "<=" if ok else ">"
    return Check(name, "passed" if ok else "failed", f"{what} {value:.2g} {word} {tol:.0e}",
                 value, tol)  # fmt: skip


# -- the checks ----------------------------------------------------------------------------

#: The rotation of the finite-difference states and of the finite rotation check (rad).
TILT = np.array([0.3, -0.2, 0.25])
TURN = np.array([0.9, -0.6, 1.3])


def translation(b: Body) -> Check:
    ref = np.abs(b.internal(b.x0 + b.typical(STRAIN))).max()
    f = b.internal(b.x0 + b.size * np.array([0.7, -0.4, 0.5]))
    what = "max |f| under a translation by 0.9 of the body's size / a 1 % strain's ="
    return _verdict("translation", float(np.abs(f).max() / ref), RIGID_TOL, what)


def infinitesimal_rotation(b: Body) -> Check:
    ref = np.abs(b.internal(b.x0 + b.typical(ANGLE))).max()
    w = np.array([0.48, -0.6, 0.64])  # a unit axis off the mesh's axes
    f = b.internal(b.x0 + ANGLE * np.cross(w, b.x0 - b.centre))
    what = f"max |f| under a rotation by {ANGLE:.0e} rad / a strain of {ANGLE:.0e}'s ="
    return _verdict("infinitesimal rotation", float(np.abs(f).max() / ref), ANGLE_TOL, what)


def finite_rotation(b: Body, claim: Rotation | None) -> Check:
    name = "finite rotation"
    if claim is None:
        u = b.random(STRAIN)
        f1 = b.internal(b.x0 + u)
        if relative_error(b.internal(b.x0 + 2 * u), 2 * f1) < LINEAR_TOL:
            why = "the forces are linear in x and the model claims no finite rotation"
            return Check(name, "skipped", why)
        claim = "finite"
    if claim == "infinitesimal":
        return Check(name, "skipped", "the model claims infinitesimal rotations only")
    ref = np.abs(b.internal(b.x0 + b.typical(STRAIN))).max()
    y = b.x0 + b.random(STRAIN)
    fy = b.internal(y)
    R = rotation(TURN)
    rigid = np.abs(b.internal(b.rotated(b.x0, TURN) + 0.3 * b.size)).max() / ref
    objective = relative_error(b.internal(b.rotated(y, TURN)), (fy @ R.T))
    what = (
        f"max |f| under a rotation by {np.linalg.norm(TURN):.2f} rad / a 1 % strain's "
        f"= {rigid:.2g}, |f(Qy) - Q f(y)| / |f(y)| = {objective:.2g}: the larger"
    )
    return _verdict(name, float(max(rigid, objective)), RIGID_TOL, what)


def _directions(b: Body, n_random: int = 3, n_coordinates: int = 6) -> list[np.ndarray]:
    """Unit directions over the free DOFs: random ones, then coordinate ones."""
    out = []
    for _ in range(n_random):
        d = np.zeros(b.x0.size)
        d[b.free] = b.rng.standard_normal(b.free.size)
        out.append(d / np.linalg.norm(d))
    for i in b.rng.choice(b.free, min(n_coordinates, b.free.size), replace=False):
        d = np.zeros(b.x0.size)
        d[i] = 1.0
        out.append(d)
    return out


def _fd_state(b: Body) -> np.ndarray:
    return b.rotated(b.x0 + b.random(STRAIN), TILT)


def _central(error: Callable[[float], float], h: float) -> float:
    """The error of a central difference at step ``h``, or where it fails, the least of it
    at ``h``, ``h / 10`` and ``h / 100``: a right derivative's error falls with the step
    (as ``h^2``, or to rounding once the step no longer straddles a kink of the law, such
    as fibres that carry tension only), a wrong one's does not."""
    e = error(h)
    return e if e <= FD_TOL else min(e, error(h / 10), error(h / 100))


def energy_gradient(b: Body) -> Check:
    name = "energy gradient"
    x = _fd_state(b).ravel()
    if b.system.energy(x.reshape(-1, 3), 1.0) is None:
        return Check(name, "skipped", "no energy (the forces are not a gradient)")
    f = np.asarray(b.system.forces(x.reshape(-1, 3), None, 1.0), dtype=float).ravel()
    scale = float(np.linalg.norm(b.internal(x.reshape(-1, 3))))

    def energy(y: np.ndarray) -> float:
        return float(b.system.energy(y.reshape(-1, 3), 1.0) or 0.0)

    worst = 0.0
    for d in _directions(b):

        def error(h: float, d: np.ndarray = d) -> float:
            g = (energy(x + h * d) - energy(x - h * d)) / (2 * h)
            return abs(g + f @ d) / scale

        worst = max(worst, _central(error, FD_STEP * b.h))
    what = f"|dE/dx + f| (central differences, h = {FD_STEP:.0e} l) / |f_internal| ="
    return _verdict(name, worst, FD_TOL, what)


def tangent(b: Body, claim: Tangent | None) -> Check:
    name = "tangent"
    x = _fd_state(b).ravel()
    K = b.system.stiffness(x.reshape(-1, 3), 1.0)
    if K is None:
        return Check(name, "skipped", "no analytic tangent (the solvers difference the forces)")

    def forces(y: np.ndarray) -> np.ndarray:
        return np.asarray(b.system.forces(y.reshape(-1, 3), None, 1.0), dtype=float).ravel()

    worst = 0.0
    for d in _directions(b):

        def error(h: float, d: np.ndarray = d, Kd: np.ndarray = K @ d) -> float:
            fd = -(forces(x + h * d) - forces(x - h * d)) / (2 * h)
            return float(np.linalg.norm(Kd - fd) / np.linalg.norm(fd))

        worst = max(worst, _central(error, FD_STEP * b.h))
    what = f"|K d + df/dx d| (central differences, h = {FD_STEP:.0e} l) / |df/dx d| ="
    if claim == "approximate":
        return Check(name, "skipped", f"the model claims an approximate tangent: {what} "
                     f"{worst:.2g}", worst)  # fmt: skip
    return _verdict(name, worst, FD_TOL, what)


def _reference(linear: Any, scene: Scene) -> MechanicalSystem:
    if linear is None:
        return LinearP1(scene)
    if isinstance(linear, MechanicalSystem):
        return linear
    if hasattr(linear, "system"):
        return linear.system(scene)
    return linear(scene)


def _tangent_at_rest(system: MechanicalSystem, x0: np.ndarray, d: np.ndarray, h: float):
    K = system.stiffness(x0, 0.0)
    if K is not None:
        return K @ d
    xp, xm = (x0.ravel() + h * d).reshape(-1, 3), (x0.ravel() - h * d).reshape(-1, 3)
    return -(np.asarray(system.forces(xp, None, 0.0)) - system.forces(xm, None, 0.0)).ravel() / (
        2 * h
    )


def small_strain(model: Any, scene: Scene, b: Body | None, claim, tol, linear) -> Check:
    name = "small strain"
    if claim is None:
        return Check(name, "skipped", "the model claims no small-strain limit")
    ref = _reference(linear, scene)
    x0 = np.asarray(ref.x0, dtype=float)
    if claim == "exact":
        if b is None:
            return Check(name, "skipped", "an exact claim needs the model's system")
        if b.x0.shape != x0.shape:
            return Check(name, "failed", f"the system has {len(b.x0)} nodes, the mesh "
                         f"{len(x0)}: its tangent cannot be P1's")  # fmt: skip
        h = FD_STEP * b.h
        fd = b.system.stiffness(b.x0, 0.0) is None
        worst = 0.0
        for _ in range(3):
            d = b.rng.standard_normal(x0.size)
            Kd = _tangent_at_rest(b.system, b.x0, d, h)
            Kref = _tangent_at_rest(ref, x0, d, h)
            worst = max(worst, float(np.linalg.norm(Kd - Kref) / np.linalg.norm(Kref)))
        how = "its central differences" if fd else "K"
        what = f"|K(x0) d - K_P1 d| / |K_P1 d| ({how}, random d) ="
        return _verdict(name, worst, tol or (FD_TOL if fd else EXACT_TOL), what)
    u_ref = linear_static(ref).x - x0
    if not np.abs(u_ref).max() > 0:
        return Check(name, "skipped", "the scene has no load: no displacement to compare")
    u = np.asarray(model.solve(scaled_scene(scene, LIMIT_LOAD)).u).reshape(-1, 3) / LIMIT_LOAD
    if u.shape != u_ref.shape:
        return Check(name, "failed", f"the solution has {len(u)} nodes, the mesh {len(u_ref)}")
    err = float(np.linalg.norm(u - u_ref) / np.linalg.norm(u_ref))
    what = f"|u / s - u_P1| / |u_P1| at the load factor s = {LIMIT_LOAD:.0e} ="
    return _verdict(name, err, tol or LIMIT_TOL, what)


def excursion(b: Body, x: np.ndarray, steps: int, fraction: float, every: int):
    """Relative change of the total energy over ``steps`` Verlet steps from rest at ``x``:
    ``(E(t) - E(0)) / W0``, the largest kinetic energy over ``W0``, the run."""
    traj = explicit(b.system, steps=steps, integrator="verlet", x_init=x, scale=0.0,
                    record_every=every, dt_safety=fraction)  # fmt: skip
    W0 = float(traj.potential[0]) - float(b.system.energy(b.x0, 0.0))  # type: ignore[arg-type]
    total = traj.kinetic + traj.potential
    return (total - total[0]) / W0, float(traj.kinetic.max()) / W0, traj


def explicit_energy(b: Body, steps: int) -> Check:
    name = "explicit energy"
    if b.system.energy(b.x0, 0.0) is None:
        return Check(name, "skipped", "no energy (the forces are not a gradient)")
    x = b.x0 + b.smooth(STRAIN)
    v = b.rng.standard_normal(b.x0.shape)
    damped = relative_error(b.system.forces(x, v, 0.0), b.system.forces(x, None, 0.0)) > 1e-12
    change, moved, traj = excursion(b, x, steps, DT_FRACTION, 2)
    if not moved > 0.05:
        return Check(name, "failed", f"released from a strain energy W0, the body never "
                     f"moved (kinetic energy <= {moved:.2g} W0)")  # fmt: skip
    run = f"{steps} Verlet steps of {traj.dt / (traj.dt_crit or traj.dt):.2f} dt_crit"
    if damped:
        what = f"damped: the largest rise of the total energy over {run} / W0 ="
        return _verdict(name, float(change.max()), ENERGY_TOL, what)
    e1 = float(np.abs(change).max())
    if e1 > ENERGY_TOL or e1 <= ENERGY_FLOOR:
        return _verdict(name, e1, ENERGY_TOL, f"|E(t) - E(0)| / W0 over {run} =")
    e2 = float(np.abs(excursion(b, x, 2 * steps, DT_FRACTION / 2, 4)[0]).max())
    ok = e1 / e2 >= ENERGY_SCALING
    what = (
        f"|E(t) - E(0)| / W0 over {run} = {e1:.2g} <= {ENERGY_TOL:.0e}, falling "
        f"{e1 / e2:.2f}x at half the step ({'>=' if ok else '<'} {ENERGY_SCALING:g})"
    )
    return Check(name, "passed" if ok else "failed", what, e1, ENERGY_TOL)
