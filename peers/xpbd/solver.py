"""XPBD on a scene: settings, timed frames, and the run to rest that is its static answer.

The static answer (:meth:`XPBD.solve`) runs frames of ``dt`` seconds (``substeps``
substeps of ``iterations`` constraint sweeps each) from rest under the scene's loads until
the body is at rest. **Rest** is judged per frame: ``substeps`` times the largest nodal
motion in any one substep of the frame (how far a node would go in a frame at the frame's
top speed) is at most ``rest_tol`` times the largest displacement from the rest shape, in
``rest_frames`` consecutive frames. Speeds, not frame-end positions, so that motion that
returns within a frame is not taken for rest.

Damping only sets how fast rest comes (at rest the velocity is zero whatever the damping):
``auto`` (the default) is viscous at twice the Rayleigh estimate ``omega_R`` of the lowest
frequency (critical damping of the lowest mode; ``omega_R^2 = u K u / u M u`` for the
linear static answer ``u`` of the stable neo-Hookean tangent at rest, one sparse solve); a
number ``c`` (1/s) multiplies the velocities by ``exp(-c h)`` per substep; ``kinetic``
zeroes them at each kinetic-energy peak (dynamic relaxation's choice, which on slender
bodies stalls: the resets come every few substeps and the lowest mode never gets going).

With converged iterations a substep would be an implicit Euler step of the energy of
:mod:`.constraints`, whose rest state is the static equilibrium; XPBD's rest state is not
quite that, and the error is what docs/peers.rst#xpbd-bias measures.

Supports (the scene's Dirichlet DOFs) have zero inverse mass and their prescribed position
from the first frame. Dead loads enter as accelerations ``f / m``; a follower pressure is
re-evaluated at the start of every frame.

Examples
--------
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({"mesh": {"generator": "box", "size": [0.1, 0.02, 0.02],
...     "divisions": [5, 1, 1]}, "material": {"law": "neo-hookean", "E": 1e4, "nu": 0.3},
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
...     "load": [{"type": "gravity", "value": [0.0, 0.0, -9.81]}]})
>>> out = XPBD(scene, XPBDSettings(substeps=20, iterations=4)).solve()
>>> out.converged, bool(out.u[:, 2].min() < 0)
(True, True)
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from typing import Literal

import numpy as np

from springfem.errors import InputError, SolverError
from springfem.loads import external_forces, has_follower_loads, lumped_masses
from springfem.mechanics.limits import checkpoint
from springfem.mesh import element_colouring
from springfem.scene import Scene

from .constraints import rest_shape, stable_neo_hookean
from .energy import StableNeoHookean
from .kernels import BLOCK, ROWS, frame, sweep, sweep_blocks, sweep_order

Iteration = Literal["gauss-seidel", "jacobi"]
ITERATIONS = ("gauss-seidel", "jacobi")
Coupling = Literal["coupled", "sequential"]
COUPLINGS = ("coupled", "sequential")
#: Laws XPBD takes: their isotropic (mu, lam) set the stable neo-Hookean constraints.
LAWS = ("linear", "neo-hookean")


@dataclass(frozen=True)
class XPBDSettings:
    """XPBD's own settings.

    Parameters
    ----------
    dt
        Frame length (s): 1/60, a game's frame.
    substeps
        Substeps per frame (``h = dt / substeps``).
    iterations
        Constraint sweeps per substep.
    iteration
        ``gauss-seidel`` (over the element colouring) or ``jacobi``.
    coupling
        ``coupled`` (an element's two constraints in one 2 x 2 solve) or ``sequential``.
    omega
        Jacobi's relaxation of the averaged corrections.
    damping
        ``auto``, ``kinetic`` or a viscous rate ``c >= 0`` (1/s).
    rest_tol, rest_frames
        Rest: ``substeps`` times the largest nodal motion in a substep ``<= rest_tol *``
        the largest displacement, in ``rest_frames`` frames running.
    max_frames
        Frames at most before giving up (not converged).
    """

    dt: float = 1.0 / 60.0
    substeps: int = 40
    iterations: int = 2
    iteration: Iteration = "gauss-seidel"
    coupling: Coupling = "coupled"
    omega: float = 1.0
    damping: float | Literal["auto", "kinetic"] = "auto"
    rest_tol: float = 1e-6
    rest_frames: int = 2
    max_frames: int = 1_000

    def __post_init__(self):
        if not (self.dt > 0 and self.substeps >= 1 and self.iterations >= 1):
            raise InputError("xpbd needs dt > 0, substeps >= 1 and iterations >= 1")
        if self.iteration not in ITERATIONS:
            raise InputError(
                f"xpbd iteration {self.iteration!r} is not one of {', '.join(ITERATIONS)}"
            )
        if self.coupling not in COUPLINGS:
            raise InputError(
                f"xpbd coupling {self.coupling!r} is not one of {', '.join(COUPLINGS)}"
            )
        if self.damping not in ("auto", "kinetic") and not (
            isinstance(self.damping, int | float) and self.damping >= 0
        ):
            raise InputError(f"xpbd damping {self.damping!r} is not auto, kinetic or a rate >= 0")


@dataclass
class XPBDResult:
    """What a run to rest gives: displacement, whether rest came, frames, seconds and the
    equilibrium residual of the stable neo-Hookean energy at the end (relative to the load)."""

    u: np.ndarray
    converged: bool
    frames: int
    substeps: int
    wall_time: float
    residual: float
    info: dict = field(default_factory=dict)


def why_not(scene: Scene) -> str | None:
    """Why XPBD cannot take ``scene`` (``None``: it can).

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
            f"model xpbd: isotropic stable neo-Hookean constraints have no {law} law; "
            f"it takes {', '.join(LAWS)}"
        )
    return None


class XPBD:
    """XPBD of a scene (see the module docstring).

    Parameters
    ----------
    scene
        Mesh, isotropic material, supports, loads.
    settings
        :class:`XPBDSettings`.
    """

    def __init__(self, scene: Scene, settings: XPBDSettings | None = None):
        why = why_not(scene)
        if why is not None:
            raise InputError(why)
        self.scene = scene
        self.settings = settings or XPBDSettings()
        mesh = scene.mesh
        self.tets = np.ascontiguousarray(mesh.tets, dtype=np.int64)
        self.x0 = np.array(mesh.points, dtype=float)
        n = self.x0.shape[0]
        self.G, self.V = rest_shape(self.x0, self.tets)
        self.mu, self.lam, self.gamma = stable_neo_hookean(scene.material.mu, scene.material.lam)
        self.alpha_d = 1.0 / (self.mu * self.V)
        self.alpha_h = 1.0 / (self.lam * self.V)
        self.masses = lumped_masses(scene)
        self.fixed_dofs, fixed_values = scene.dirichlet()
        self.w = np.repeat((1.0 / self.masses)[:, None], 3, axis=1)
        self.w.reshape(-1)[self.fixed_dofs] = 0.0
        self._x_fixed = self.x0.ravel()[self.fixed_dofs] + fixed_values
        self._follower = has_follower_loads(scene)
        self.colours = element_colouring(self.tets, n)
        #: The Gauss–Seidel sweep (colour by colour) and the element arrays stored in it.
        self.order = sweep_order(self.colours)
        self.sweep_tets = np.ascontiguousarray(self.tets[self.order])
        self.sweep_G = np.ascontiguousarray(self.G[self.order])
        self.sweep_alpha_d = np.ascontiguousarray(self.alpha_d[self.order])
        self.sweep_alpha_h = np.ascontiguousarray(self.alpha_h[self.order])
        self.sweep_starts = sweep_blocks(self.colours[self.order])
        m = self.tets.shape[0]
        self._lam_d, self._lam_h, self._dp = np.zeros(m), np.zeros(m), np.zeros((n, 3))
        self.damping_rate = self._damping_rate()

    def _damping_rate(self) -> float:
        """The viscous rate (1/s) of the settings: ``2 omega_R`` for ``auto`` (0 when the
        scene neither loads nor moves the body; then no damping)."""
        d = self.settings.damping
        if d == "kinetic":
            return 0.0
        if d != "auto":
            return float(d)
        system = StableNeoHookean(self.scene)
        K = system.internal_stiffness(system.x0)
        n3 = 3 * self.x0.shape[0]
        free = np.ones(n3, dtype=bool)
        free[self.fixed_dofs] = False
        u = np.zeros(n3)
        u[self.fixed_dofs] = self._x_fixed - self.x0.ravel()[self.fixed_dofs]
        f = external_forces(self.scene).ravel() - K @ u
        from scipy.sparse.linalg import spsolve

        u[free] = spsolve(K[free][:, free].tocsc(), f[free])
        mass = float(np.sum(np.repeat(self.masses, 3)[free] * u[free] ** 2))
        stiff = float(u @ (K @ u))
        return 2.0 * math.sqrt(stiff / mass) if mass > 0 and stiff > 0 else 0.0

    @property
    def h(self) -> float:
        """The substep length ``dt / substeps``."""
        return self.settings.dt / self.settings.substeps

    def accelerations(self, x: np.ndarray) -> np.ndarray:
        """External accelerations ``f_ext / m`` ``(n, 3)`` (follower pressure at ``x``)."""
        f = external_forces(self.scene, x=x if self._follower else None)
        return f / self.masses[:, None]

    def start(self) -> tuple[np.ndarray, np.ndarray]:
        """Positions and velocities at the start: rest shape, supports at their place."""
        x = self.x0.copy()
        x.reshape(-1)[self.fixed_dofs] = self._x_fixed
        return x, np.zeros_like(x)

    def advance(self, x: np.ndarray, v: np.ndarray, a_ext: np.ndarray) -> float:
        """One frame in place on ``x, v``; ``substeps`` times the largest nodal motion of
        one substep."""
        s = self.settings
        kinetic = s.damping == "kinetic"
        damp = math.exp(-self.damping_rate * self.h)
        return float(
            frame(
                x, v, self.w, self.masses, a_ext, self.sweep_tets, self.sweep_G,
                self.sweep_alpha_d, self.sweep_alpha_h, self.gamma, self.h, s.substeps,
                s.iterations, s.iteration == "jacobi", s.coupling == "coupled", s.omega,
                self.sweep_starts, damp, kinetic, self._lam_d, self._lam_h, self._dp,
            )
        )  # fmt: skip

    def projection_pass(self, x: np.ndarray) -> tuple[Callable[[], None], float]:
        """One constraint iteration over every element, from positions ``x`` (a copy, moved
        by every call; the multipliers restart every ``iterations`` calls, as a substep's
        do), at the settings' substep: a function to time, and the bytes it moves
        per element (element arrays read, the multipliers read and written, and once per node
        the positions read and written and the inverse masses read).

        Examples
        --------
        >>> from springfem.scene import scene_from_dict
        >>> scene = scene_from_dict({"mesh": {"generator": "box", "size": [1, 1, 1],
        ...     "divisions": [1, 1, 1]}, "material": {"law": "linear", "E": 1.0, "nu": 0.3}})
        >>> solver = XPBD(scene, XPBDSettings(damping=0.0))
        >>> go, per_tet = solver.projection_pass(solver.x0 * 1.01)
        >>> go(); round(per_tet)
        248
        """
        s = self.settings
        p = np.array(x, dtype=float)
        h2 = self.h * self.h
        ad, ah = self.sweep_alpha_d / h2, self.sweep_alpha_h / h2
        m = self.tets.shape[0]
        lam_d, lam_h, dp = np.zeros(m), np.zeros(m), np.zeros_like(p)
        S, g, F, D = np.empty(ROWS * BLOCK), np.empty((4, 3)), np.empty((3, 3)), np.empty((3, 3))
        jacobi, coupled = s.iteration == "jacobi", s.coupling == "coupled"

        calls = [0]

        def go() -> None:
            if calls[0] % s.iterations == 0:  # a substep's start: the multipliers restart
                lam_d[:] = 0.0
                lam_h[:] = 0.0
            calls[0] += 1
            sweep(p, self.w, self.sweep_tets, self.sweep_G, ad, ah, self.gamma, lam_d, lam_h, dp,
                  jacobi, coupled, s.omega, self.sweep_starts, S, g, F, D)  # fmt: skip

        arrays = (self.sweep_tets, self.sweep_G, ad, ah)
        per_element = sum(a.nbytes for a in arrays) / m + 2 * 2 * 8  # + lam_d, lam_h r/w
        return go, per_element + (2 * p.nbytes + self.w.nbytes) / m

    def run(self, frames: int) -> tuple[np.ndarray, np.ndarray]:
        """``frames`` frames of dynamics from rest; the positions and velocities at the end.

        Parameters
        ----------
        frames
            Number of frames of ``dt``.

        Returns
        -------
        x, v
            ``(n, 3)`` each.
        """
        x, v = self.start()
        a = self.accelerations(x)
        for _ in range(frames):
            if self._follower:
                a = self.accelerations(x)
            self.advance(x, v, a)
        return x, v

    def solve(self) -> XPBDResult:
        """Run to rest (the module docstring says how rest is judged).

        Returns
        -------
        XPBDResult

        Raises
        ------
        SolverError
            If the positions stop being finite.
        """
        s = self.settings
        t0 = time.perf_counter()
        x, v = self.start()
        a = self.accelerations(x)
        calm = 0
        converged = False
        k = 0
        for k in range(1, s.max_frames + 1):
            checkpoint()  # a study's time cap, also off the main thread (no watchdog there)
            if self._follower:
                a = self.accelerations(x)
            moved = self.advance(x, v, a)
            if not np.isfinite(x).all():
                raise SolverError(
                    f"xpbd: positions not finite after frame {k} (t = {k * s.dt:.4g} s)"
                )
            scale = float(np.abs(x - self.x0).max())
            calm = calm + 1 if moved <= s.rest_tol * max(scale, 1e-300) else 0
            if calm >= s.rest_frames:
                converged = True
                break
        wall = time.perf_counter() - t0
        return XPBDResult(
            u=x - self.x0, converged=converged, frames=k, substeps=k * s.substeps,
            wall_time=wall, residual=self.residual(x),
            info={"settings": asdict(s), "damping_rate": self.damping_rate},
        )  # fmt: skip

    def residual(self, x: np.ndarray) -> float:
        """``|f_int + f_ext|`` on the free DOFs over ``|f_ext|`` (stable neo-Hookean forces),
        ``max`` norms; the absolute value when there is no load."""
        system = StableNeoHookean(self.scene)
        r = system.forces(x).ravel()
        free = np.ones(r.size, dtype=bool)
        free[self.fixed_dofs] = False
        ref = float(np.abs(system.external(x).ravel()[free]).max(initial=0.0))
        return float(np.abs(r[free]).max(initial=0.0)) / (ref if ref > 0 else 1.0)


__all__ = ["COUPLINGS", "ITERATIONS", "LAWS", "XPBD", "XPBDResult", "XPBDSettings", "why_not"]
