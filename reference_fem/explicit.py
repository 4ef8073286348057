"""Explicit P1 FEM: a fused numba kernel for the internal forces of linear tets.

The competitor the spring model has to beat (DESIGN §4): a P1 element whose gradient is
constant, so one pass over the elements gathers the four vertices, forms

    F = sum_i x_i (x) grad N_i = sum_{a=1..3} (x_a - x_0) (x) grad N_a

(``grad N_0 = -(grad N_1 + grad N_2 + grad N_3)``), evaluates the first Piola stress

    neo-Hookean (coupled):  P = mu (F - F^-T) + lam ln J F^-T,    F^-T = cof(F) / J
    linear:                 P = 2 mu eps + lam tr(eps) I,          eps = sym(F - I)

and scatters ``f_a = -V P grad N_a`` (``f_0 = -(f_1 + f_2 + f_3)``, so each element's net
force is zero by construction). The energies are those of :mod:`reference_fem.hyperelastic`
(``psi = mu/2 (I1 - 3) - mu ln J + lam/2 ln^2 J``) and of small-strain isotropic
elasticity; per element the kernel reads 4 node ids and one row of 10 floats (three shape
gradients and the rest volume).

Parallel scatter without races uses the spring kernel's two strategies (the scatter loops
are written here again since ``reference_fem`` does not import spring internals, DESIGN §2;
the element colouring is the shared :func:`springfem.mesh.element_colouring`), so the two
kernels are compared like for like:

``buffer`` (default, as the spring kernel's)
    Static contiguous chunks of elements, one per numba thread, each adding into its own
    force buffer; the buffers are summed in chunk order. Two parallel regions per call;
    deterministic for a given number of threads, equal to the serial pass to round-off.
``colour``
    Elements greedily coloured so that no two elements of one colour share a node, stored
    colour by colour; within a colour, blocks of elements run in a ``prange``. One parallel
    region (a barrier) per colour, about 30; bit-identical to a serial pass in colour
    order whatever the number of threads.

``ExplicitFem(parallel=False)`` runs one serial pass in mesh order.

Inverted elements (``J <= 0``) get no force from the kernel and are counted; for the
neo-Hookean law :class:`ExplicitFem` then raises a :class:`~springfem.errors.SolverError`
naming the element and the step ("inverted element k at step n") instead of letting NaN
propagate, or (``on_inverted="nan"``) returns NaN at the element's nodes so a Newton line
search can back off.

Examples
--------
>>> from reference_fem.scenes import bench_scene
>>> fem = ExplicitFem(bench_scene(200))
>>> float(abs(fem.internal(fem.x0)).max())  # no force at rest
0.0
>>> fem.n_elements, fem.parallel  # small meshes run serially by default
(324, False)
"""

from __future__ import annotations

import math
from typing import Literal

import numba
import numpy as np
import scipy.sparse as sp
from numba import njit, prange

from springfem.errors import InputError, SolverError
from springfem.loads import external_forces, has_follower_loads, lumped_masses
from springfem.mesh import element_colouring, tet_volumes
from springfem.scene import Scene

from .space import p1_gradients

Law = Literal["neo-hookean", "linear"]
Scatter = Literal["buffer", "colour"]
OnInverted = Literal["raise", "nan", "ignore"]
LAWS = ("neo-hookean", "neo-hookean/coupled", "linear")
_NEO, _LINEAR = 0, 1
#: Elements per parallel block (as in the spring kernel).
BLOCK = 512
#: Below this many elements ``ExplicitFem(parallel=None)`` runs serially (as the spring
#: kernel's default): starting threads costs more than it saves on small meshes, and far more
#: on a busy machine.
PARALLEL_MIN_ELEMENTS = 20_000
#: Row layout of the per-element data: grad N_1, grad N_2, grad N_3, rest volume V.
_NDATA = 10


# --------------------------------------------------------------------------- kernels


@njit(cache=True, fastmath=False)
def _forces_range(lo, hi, x, tets, D, mu, lam, law, out):  # pragma: no cover - compiled
    """Add the forces of elements ``lo..hi`` to ``out``; returns the number with ``J <= 0``."""
    bad = 0
    for k in range(lo, hi):
        i0, i1, i2, i3 = tets[k, 0], tets[k, 1], tets[k, 2], tets[k, 3]
        x0, y0, z0 = x[i0, 0], x[i0, 1], x[i0, 2]
        ax, ay, az = x[i1, 0] - x0, x[i1, 1] - y0, x[i1, 2] - z0
        bx, by, bz = x[i2, 0] - x0, x[i2, 1] - y0, x[i2, 2] - z0
        cx, cy, cz = x[i3, 0] - x0, x[i3, 1] - y0, x[i3, 2] - z0
        g1x, g1y, g1z = D[k, 0], D[k, 1], D[k, 2]
        g2x, g2y, g2z = D[k, 3], D[k, 4], D[k, 5]
        g3x, g3y, g3z = D[k, 6], D[k, 7], D[k, 8]
        V = D[k, 9]
        # F = sum_a e_a (x) grad N_a
        F00 = ax * g1x + bx * g2x + cx * g3x
        F01 = ax * g1y + bx * g2y + cx * g3y
        F02 = ax * g1z + bx * g2z + cx * g3z
        F10 = ay * g1x + by * g2x + cy * g3x
        F11 = ay * g1y + by * g2y + cy * g3y
        F12 = ay * g1z + by * g2z + cy * g3z
        F20 = az * g1x + bz * g2x + cz * g3x
        F21 = az * g1y + bz * g2y + cz * g3y
        F22 = az * g1z + bz * g2z + cz * g3z
        # cofactor matrix: F^-T = cof(F) / J
        C00 = F11 * F22 - F12 * F21
        C01 = F12 * F20 - F10 * F22
        C02 = F10 * F21 - F11 * F20
        J = F00 * C00 + F01 * C01 + F02 * C02
        if J <= 0.0:
            bad += 1
            if law == _NEO:
                continue
        if law == _NEO:
            C10 = F02 * F21 - F01 * F22
            C11 = F00 * F22 - F02 * F20
            C12 = F01 * F20 - F00 * F21
            C20 = F01 * F12 - F02 * F11
            C21 = F02 * F10 - F00 * F12
            C22 = F00 * F11 - F01 * F10
            s = (lam * math.log(J) - mu) / J  # P = mu F + (lam ln J - mu) F^-T
            P00, P01, P02 = mu * F00 + s * C00, mu * F01 + s * C01, mu * F02 + s * C02
            P10, P11, P12 = mu * F10 + s * C10, mu * F11 + s * C11, mu * F12 + s * C12
            P20, P21, P22 = mu * F20 + s * C20, mu * F21 + s * C21, mu * F22 + s * C22
        else:
            tr = lam * ((F00 - 1.0) + (F11 - 1.0) + (F22 - 1.0))
            P00 = 2.0 * mu * (F00 - 1.0) + tr
            P11 = 2.0 * mu * (F11 - 1.0) + tr
            P22 = 2.0 * mu * (F22 - 1.0) + tr
            P01 = P10 = mu * (F01 + F10)
            P02 = P20 = mu * (F02 + F20)
            P12 = P21 = mu * (F12 + F21)
        # f_a = -V P grad N_a
        f1x = -V * (P00 * g1x + P01 * g1y + P02 * g1z)
        f1y = -V * (P10 * g1x + P11 * g1y + P12 * g1z)
        f1z = -V * (P20 * g1x + P21 * g1y + P22 * g1z)
        f2x = -V * (P00 * g2x + P01 * g2y + P02 * g2z)
        f2y = -V * (P10 * g2x + P11 * g2y + P12 * g2z)
        f2z = -V * (P20 * g2x + P21 * g2y + P22 * g2z)
        f3x = -V * (P00 * g3x + P01 * g3y + P02 * g3z)
        f3y = -V * (P10 * g3x + P11 * g3y + P12 * g3z)
        f3z = -V * (P20 * g3x + P21 * g3y + P22 * g3z)
        out[i0, 0] -= f1x + f2x + f3x
        out[i0, 1] -= f1y + f2y + f3y
        out[i0, 2] -= f1z + f2z + f3z
        out[i1, 0] += f1x
        out[i1, 1] += f1y
        out[i1, 2] += f1z
        out[i2, 0] += f2x
        out[i2, 1] += f2y
        out[i2, 2] += f2z
        out[i3, 0] += f3x
        out[i3, 1] += f3y
        out[i3, 2] += f3z
    return bad


@njit(cache=True, fastmath=False)
def _forces_serial(x, tets, D, mu, lam, law, out):  # pragma: no cover - compiled
    out[:] = 0.0
    return _forces_range(0, tets.shape[0], x, tets, D, mu, lam, law, out)


@njit(cache=True, fastmath=False, parallel=True)
def _forces_colour(x, tets, D, mu, lam, law, ptr, out):  # pragma: no cover - compiled
    n = out.shape[0]
    for i in prange(n):
        out[i, 0] = 0.0
        out[i, 1] = 0.0
        out[i, 2] = 0.0
    bad = 0
    for c in range(ptr.shape[0] - 1):
        nblock = (ptr[c + 1] - ptr[c] + BLOCK - 1) // BLOCK
        for b in prange(nblock):  # no two elements of a colour share a node
            lo = ptr[c] + b * BLOCK
            hi = min(lo + BLOCK, ptr[c + 1])
            bad += _forces_range(lo, hi, x, tets, D, mu, lam, law, out)
    return bad


@njit(cache=True, fastmath=False, parallel=True)
def _forces_buffer(x, tets, D, mu, lam, law, ptr, buf, out):  # pragma: no cover - compiled
    nchunk = ptr.shape[0] - 1
    n = out.shape[0]
    bad = 0
    for t in prange(nchunk):  # one buffer per static chunk: deterministic
        b = buf[t]
        b[:] = 0.0
        bad += _forces_range(ptr[t], ptr[t + 1], x, tets, D, mu, lam, law, b)
    for i in prange(n):
        for d in range(3):
            s = 0.0
            for t in range(nchunk):
                s += buf[t, i, d]
            out[i, d] = s
    return bad


@njit(cache=True, fastmath=False)
def _energy_serial(x, tets, D, mu, lam, law):  # pragma: no cover - compiled
    """Total strain energy ``sum V psi(F)`` (``inf`` if a neo-Hookean element has J <= 0)."""
    total = 0.0
    for k in range(tets.shape[0]):
        i0, i1, i2, i3 = tets[k, 0], tets[k, 1], tets[k, 2], tets[k, 3]
        x0, y0, z0 = x[i0, 0], x[i0, 1], x[i0, 2]
        ax, ay, az = x[i1, 0] - x0, x[i1, 1] - y0, x[i1, 2] - z0
        bx, by, bz = x[i2, 0] - x0, x[i2, 1] - y0, x[i2, 2] - z0
        cx, cy, cz = x[i3, 0] - x0, x[i3, 1] - y0, x[i3, 2] - z0
        F00 = ax * D[k, 0] + bx * D[k, 3] + cx * D[k, 6]
        F01 = ax * D[k, 1] + bx * D[k, 4] + cx * D[k, 7]
        F02 = ax * D[k, 2] + bx * D[k, 5] + cx * D[k, 8]
        F10 = ay * D[k, 0] + by * D[k, 3] + cy * D[k, 6]
        F11 = ay * D[k, 1] + by * D[k, 4] + cy * D[k, 7]
        F12 = ay * D[k, 2] + by * D[k, 5] + cy * D[k, 8]
        F20 = az * D[k, 0] + bz * D[k, 3] + cz * D[k, 6]
        F21 = az * D[k, 1] + bz * D[k, 4] + cz * D[k, 7]
        F22 = az * D[k, 2] + bz * D[k, 5] + cz * D[k, 8]
        if law == _NEO:
            J = (
                F00 * (F11 * F22 - F12 * F21)
                - F01 * (F10 * F22 - F12 * F20)
                + F02 * (F10 * F21 - F11 * F20)
            )
            if J <= 0.0:
                return math.inf
            I1 = (
                F00 * F00
                + F01 * F01
                + F02 * F02
                + F10 * F10
                + F11 * F11
                + F12 * F12
                + F20 * F20
                + F21 * F21
                + F22 * F22
            )
            lnJ = math.log(J)
            psi = 0.5 * mu * (I1 - 3.0) - mu * lnJ + 0.5 * lam * lnJ * lnJ
        else:
            e00, e11, e22 = F00 - 1.0, F11 - 1.0, F22 - 1.0
            e01, e02, e12 = 0.5 * (F01 + F10), 0.5 * (F02 + F20), 0.5 * (F12 + F21)
            tr = e00 + e11 + e22
            ee = e00 * e00 + e11 * e11 + e22 * e22 + 2.0 * (e01 * e01 + e02 * e02 + e12 * e12)
            psi = mu * ee + 0.5 * lam * tr * tr
        total += D[k, 9] * psi
    return total


# --------------------------------------------------------------------------- the system


def _parse_law(scene: Scene, law: str) -> int:
    if law not in LAWS:
        raise InputError(f"explicit FEM law {law!r} is not one of {', '.join(LAWS)}")
    mat = scene.material
    if mat.law == "transverse-linear":
        raise InputError(
            "explicit FEM is isotropic (neo-hookean or linear); the scene's material is "
            "transverse-linear"
        )
    if law.startswith("neo-hookean") and mat.law == "neo-hookean" and mat.formulation != "coupled":
        raise InputError(
            "explicit FEM implements the coupled neo-Hookean energy; the scene's material is "
            f"{mat.formulation} (use reference_fem.solve for the uncoupled forms)"
        )
    return _LINEAR if law == "linear" else _NEO


class ExplicitFem:
    """P1 FEM of a scene as a :class:`~springfem.mechanics.system.MechanicalSystem`.

    The solvers of :mod:`springfem.mechanics` (``explicit``, ``explicit_static``,
    ``stable_time_step``, ``static``) drive it as they drive the spring model: lumped masses
    ``rho V / 4``, the scene's Dirichlet conditions and P1 nodal loads
    (:func:`springfem.loads.external_forces`), forces from the fused kernel.

    Parameters
    ----------
    scene
        Mesh, isotropic material (``mu``, ``lam``), boundaries and loads.
    law
        ``neo-hookean`` (the coupled energy of :mod:`reference_fem.hyperelastic`, whatever
        the scene's law) or ``linear`` (small-strain isotropic elasticity).
    parallel
        ``True``: parallel kernel on all numba threads; ``False``: serial, in mesh order;
        ``None`` (default): parallel from :data:`PARALLEL_MIN_ELEMENTS` elements when there
        is more than one thread.
    scatter
        Race-free parallel scatter: ``buffer`` (per-thread buffers) or ``colour`` (element
        colouring), see the module docstring.
    on_inverted
        What a neo-Hookean force evaluation does when elements have ``J <= 0``: ``raise``
        a :class:`~springfem.errors.SolverError` naming the first inverted element and the
        step (counted by :meth:`post_step`), return ``nan`` forces at the inverted elements'
        nodes (lets a Newton line search back off), or ``ignore`` (the inverted elements
        contribute nothing). The linear law is defined for any ``F``; it only counts them.

    Attributes
    ----------
    last_inverted
        Number of elements with ``J <= 0`` at the last force evaluation.
    steps, time
        Time steps and simulated time seen by :meth:`post_step` since construction or
        :meth:`reset`.
    """

    def __init__(
        self,
        scene: Scene,
        law: str = "neo-hookean",
        parallel: bool | None = None,
        on_inverted: OnInverted = "raise",
        scatter: Scatter = "buffer",
    ):
        if on_inverted not in ("raise", "nan", "ignore"):
            raise ValueError(f"on_inverted {on_inverted!r} is not one of raise, nan, ignore")
        if scatter not in ("buffer", "colour"):
            raise ValueError(f"scatter {scatter!r} is not one of buffer, colour")
        self.scene = scene
        self.law = "linear" if law == "linear" else "neo-hookean"
        self._law = _parse_law(scene, law)
        self.on_inverted = on_inverted
        mat = scene.material
        self.mu, self.lam = float(mat.mu), float(mat.lam)
        mesh = scene.mesh
        self.tets = np.ascontiguousarray(mesh.tets, dtype=np.int64)
        self.x0 = np.array(mesh.points, dtype=float)
        self.n_points = self.x0.shape[0]
        G, V = p1_gradients(self.x0, self.tets)
        if np.any(V <= 0):
            k = int(np.flatnonzero(V <= 0)[0])
            raise InputError(f"element {k} has non-positive volume {V[k]:.3g} at rest")
        self.V0 = V
        m = self.tets.shape[0]
        if parallel is None:
            parallel = m >= PARALLEL_MIN_ELEMENTS
        self.parallel = bool(parallel) and numba.get_num_threads() > 1
        data = np.empty((m, _NDATA))
        data[:, :9] = G[:, 1:].reshape(m, 9)
        data[:, 9] = V
        self.scatter = scatter if self.parallel else "serial"
        self._perm = np.arange(m)
        self._ptr = np.array([0, m], dtype=np.int64)
        self._buf = np.zeros((0, 0, 3))
        if self.scatter == "colour":
            colour = element_colouring(self.tets, self.n_points)
            self._perm = np.argsort(colour, kind="stable")
            counts = np.bincount(colour)
            self._ptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        elif self.scatter == "buffer":
            nchunk = numba.get_num_threads()
            self._ptr = np.linspace(0, m, nchunk + 1).round().astype(np.int64)
            self._buf = np.zeros((nchunk, self.n_points, 3))
        self._ktets = np.ascontiguousarray(self.tets[self._perm])
        self._data = np.ascontiguousarray(data[self._perm])
        # MechanicalSystem members
        self.masses = lumped_masses(scene)
        self.fixed_dofs, self._fixed_values = scene.dirichlet()
        self._follower = has_follower_loads(scene)
        self._f_dead = None if self._follower else external_forces(scene)
        self._K_linear: sp.csr_matrix | None = None
        self._assembly = None  # (Space, BlockPattern) for the tangent, built on first use
        self.last_inverted = 0
        self.evaluations = 0
        self.steps = 0
        self.time = 0.0

    @property
    def n_colours(self) -> int:
        """Number of element colours (1 unless ``scatter == "colour"``)."""
        return self._ptr.size - 1 if self.scatter == "colour" else 1

    @property
    def n_elements(self) -> int:
        return self.tets.shape[0]

    def reset(self) -> None:
        """Zero the step and evaluation counters (a new run on the same system)."""
        self.steps, self.time, self.evaluations, self.last_inverted = 0, 0.0, 0, 0

    # -- kernel -------------------------------------------------------------------------

    def kernel(self, x: np.ndarray, out: np.ndarray | None = None) -> tuple[np.ndarray, int]:
        """Raw kernel: internal forces ``(n, 3)`` and the number of elements with ``J <= 0``
        (whose forces are left out for the neo-Hookean law)."""
        x = np.ascontiguousarray(x, dtype=np.float64).reshape(self.n_points, 3)
        if out is None:
            out = np.empty((self.n_points, 3))
        args = (x, self._ktets, self._data, self.mu, self.lam, self._law)
        if self.scatter == "buffer":
            bad = _forces_buffer(*args, self._ptr, self._buf, out)
        elif self.scatter == "colour":
            bad = _forces_colour(*args, self._ptr, out)
        else:
            bad = _forces_serial(*args, out)
        return out, int(bad)

    def inverted_elements(self, x: np.ndarray, count: int | None = None) -> np.ndarray:
        """Ids of the elements with ``J <= 0`` at positions ``x`` (mesh numbering).

        ``count`` (the kernel's count): if round-off makes the volume test find fewer, the
        ``count`` elements with the smallest volume ratio are returned.
        """
        J = tet_volumes(np.asarray(x, dtype=float).reshape(-1, 3), self.tets) / self.V0
        ids = np.flatnonzero(~(J > 0))
        if count is not None and ids.size < count:
            ids = np.sort(np.argsort(J, kind="stable")[:count])
        return ids

    def internal(self, x: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Internal nodal forces ``(n, 3)``; inverted elements handled per ``on_inverted``."""
        self.evaluations += 1
        f, bad = self.kernel(x, out)
        self.last_inverted = bad
        if bad and self._law == _NEO and self.on_inverted != "ignore":
            ids = self.inverted_elements(x, bad)
            if self.on_inverted == "nan":
                f[self.tets[ids].ravel()] = np.nan
                return f
            k = int(ids[0])
            at = np.round(self.x0[self.tets[k]].mean(axis=0), 6).tolist()
            raise SolverError(
                f"explicit P1 FEM ({self.law}): inverted element {k} (J <= 0, rest centre {at}; "
                f"{bad} inverted in all) at step {self.steps + 1} ({self.steps} steps done, "
                f"t = {self.time:.4g} s; force evaluation {self.evaluations})"
            )
        return f

    # -- MechanicalSystem ---------------------------------------------------------------

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

    def strain_energy(self, x: np.ndarray) -> float:
        """``sum_e V_e psi(F_e)`` (``inf`` when a neo-Hookean element is inverted)."""
        x = np.ascontiguousarray(x, dtype=np.float64).reshape(self.n_points, 3)
        return float(_energy_serial(x, self._ktets, self._data, self.mu, self.lam, self._law))

    def energy(self, x: np.ndarray, scale: float = 1.0) -> float | None:
        """Strain energy minus the work of the dead loads; ``None`` with follower loads."""
        if self._follower:
            return None
        x = np.asarray(x, dtype=float).reshape(self.n_points, 3)
        work = scale * float(np.sum(self._f_dead * (x - self.x0)))
        return self.strain_energy(x) - work

    def stiffness(self, x: np.ndarray, scale: float = 1.0) -> sp.csr_matrix | None:
        """Tangent ``K = -d forces / dx`` (``None`` with follower loads).

        Assembled with :mod:`reference_fem.assembly` from the law's tangent
        (:class:`~reference_fem.hyperelastic.NeoHookean`), constant for the linear law.
        """
        if self._follower:
            return None
        from springfem.materials import isotropic_matrix

        from .assembly import BlockPattern, hyperelastic_element_arrays, stiffness_matrix
        from .hyperelastic import NeoHookean
        from .space import Space

        if self._assembly is None:
            space = Space(self.scene.mesh, 1)
            self._assembly = (space, BlockPattern(space.element_nodes, space.n_nodes))
        space, pattern = self._assembly
        if self._law == _LINEAR:
            if self._K_linear is None:
                mat = self.scene.material
                D = isotropic_matrix(mat.E, mat.nu)[None]
                K = stiffness_matrix(space, D, np.zeros(self.n_elements, np.int64), pattern)
                self._K_linear = sp.csr_matrix(K)
            return self._K_linear
        u = np.asarray(x, dtype=float).reshape(-1, 3) - self.x0
        _, Ke = hyperelastic_element_arrays(space, NeoHookean(self.mu, self.lam), u, True)
        return sp.csr_matrix(pattern.matrix(Ke))

    def element_nodes(self) -> np.ndarray:
        return self.tets

    def post_step(self, x: np.ndarray, dt: float) -> None:
        """Count steps and time (for "inverted element k at step n")."""
        self.steps += 1
        self.time += dt
