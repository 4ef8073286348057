"""Vertex Block Descent on a scene: settings, frames, and the run to rest that is its static
answer (as :mod:`peers.xpbd.solver`'s).

Each frame of ``dt`` is ``substeps`` implicit-Euler substeps of the energy of :mod:`.energy`,
each minimised approximately by ``iterations`` Gauss–Seidel sweeps of per-vertex 3 x 3
Newton steps over a vertex colouring (:mod:`.kernels`). The energy is the scene's law:
``neo-hookean`` scenes get the stable neo-Hookean density of the XPBD peer (the same
``mu', lam', gamma``: :func:`peers.xpbd.constraints.stable_neo_hookean`), so its Newton
answer is :class:`peers.xpbd.StableNeoHookean`'s; ``linear`` scenes get linear elasticity.

**Rest** is judged as XPBD judges it: ``substeps`` times the largest nodal motion in a
substep is at most ``rest_tol`` times the largest displacement, in ``rest_frames`` frames
running. Damping only sets how fast rest comes: ``auto`` is viscous at twice the Rayleigh
estimate of the lowest frequency (:func:`rayleigh_rate`), a number ``c`` (1/s) multiplies the
velocities by ``exp(-c h)`` per substep; ``kd`` is the paper's stiffness-proportional damping
(s). A rest state of the iteration is an equilibrium of the energy (the adaptive guess is
the position itself at rest), whatever the substeps and iterations.

Examples
--------
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({"mesh": {"generator": "box", "size": [0.1, 0.02, 0.02],
...     "divisions": [5, 1, 1]}, "material": {"law": "neo-hookean", "E": 1e4, "nu": 0.3},
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
...     "load": [{"type": "gravity", "value": [0.0, 0.0, -9.81]}]})
>>> out = VBD(scene, VBDSettings(substeps=10)).solve()
>>> out.converged, bool(out.u[:, 2].min() < 0), bool(out.residual < 1e-4)
(True, True, True)
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
from springfem.scene import Scene

from ..xpbd.constraints import deformation_gradients, rest_shape, stable_neo_hookean
from ..xpbd.energy import StableNeoHookean
from .colouring import vertex_colouring
from .energy import LAW_CODES, density, first_piola
from .kernels import _sweep, frame

#: Laws VBD takes, and the energy each becomes.
LAWS = {"neo-hookean": "stable-neo-hookean", "linear": "linear"}
#: Initial guesses of a substep (:mod:`.kernels`).
INITS = ("previous", "inertia", "adaptive")


@dataclass(frozen=True)
class VBDSettings:
    """VBD's own settings.

    Parameters
    ----------
    dt
        Frame length (s).
    substeps, iterations
        Substeps per frame and Gauss–Seidel sweeps per substep.
    init
        The substep's initial guess: ``previous``, ``inertia`` or ``adaptive``.
    kd
        Stiffness-proportional damping (s), Chen et al.'s ``k_d``.
    rho
        Chebyshev spectral-radius estimate (0: no acceleration).
    damping
        ``auto`` or a viscous rate ``c >= 0`` (1/s).
    rest_tol, rest_frames, max_frames
        Rest (module docstring) and the frames at most before giving up.
    """

    dt: float = 1.0 / 60.0
    substeps: int = 40
    iterations: int = 2
    init: Literal["previous", "inertia", "adaptive"] = "adaptive"
    kd: float = 0.0
    rho: float = 0.0
    damping: float | Literal["auto"] = "auto"
    rest_tol: float = 1e-6
    rest_frames: int = 2
    max_frames: int = 2_000

    def __post_init__(self):
        if not (self.dt > 0 and self.substeps >= 1 and self.iterations >= 1):
            raise InputError("vbd needs dt > 0, substeps >= 1 and iterations >= 1")
        if self.init not in INITS:
            raise InputError(f"vbd init {self.init!r} is not one of {', '.join(INITS)}")
        if not (self.kd >= 0 and 0 <= self.rho < 1):
            raise InputError("vbd needs kd >= 0 and 0 <= rho < 1")
        if self.damping != "auto" and not (
            isinstance(self.damping, int | float) and self.damping >= 0
        ):
            raise InputError(f"vbd damping {self.damping!r} is not auto or a rate >= 0")


@dataclass
class RestResult:
    """A run to rest: displacement, whether rest came, frames, substeps, seconds and the
    equilibrium residual of the energy at the end (relative to the load)."""

    u: np.ndarray
    converged: bool
    frames: int
    substeps: int
    wall_time: float
    residual: float
    info: dict = field(default_factory=dict)


def why_not(scene: Scene) -> str | None:
    """Why VBD cannot take ``scene`` (``None``: it can)."""
    law = scene.material.law
    if law not in LAWS:
        return f"model vbd: no {law} law; it takes {', '.join(LAWS)}"
    return None


def rayleigh_rate(scene: Scene) -> float:
    """Twice the Rayleigh estimate ``omega_R`` of the lowest frequency (1/s):
    ``omega_R^2 = u K u / u M u`` for the linear static answer ``u`` under the scene's loads
    (the tangent at rest, the scene's small-strain elasticity, one sparse solve); 0 when
    the scene neither loads nor moves the body."""
    from scipy.sparse.linalg import spsolve

    system = StableNeoHookean(scene)
    K = system.internal_stiffness(system.x0)
    fixed, values = scene.dirichlet()
    n3 = 3 * system.n_points
    free = np.ones(n3, dtype=bool)
    free[fixed] = False
    u = np.zeros(n3)
    u[fixed] = values
    f = external_forces(scene).ravel() - K @ u
    u[free] = spsolve(K[free][:, free].tocsc(), f[free])
    mass = float(np.sum(np.repeat(system.masses, 3)[free] * u[free] ** 2))
    stiff = float(u @ (K @ u))
    return 2.0 * math.sqrt(stiff / mass) if mass > 0 and stiff > 0 else 0.0


class VBD:
    """Vertex Block Descent of a scene (see the module docstring).

    Parameters
    ----------
    scene
        Mesh, isotropic material, supports, loads.
    settings
        :class:`VBDSettings`.
    """

    def __init__(self, scene: Scene, settings: VBDSettings | None = None):
        why = why_not(scene)
        if why is not None:
            raise InputError(why)
        self.scene = scene
        self.settings = settings or VBDSettings()
        self.law = LAWS[scene.material.law]
        mesh = scene.mesh
        self.tets = np.ascontiguousarray(mesh.tets, dtype=np.int64)
        self.x0 = np.array(mesh.points, dtype=float)
        n = self.x0.shape[0]
        self.G, self.V = rest_shape(self.x0, self.tets)
        mu, lam = scene.material.mu, scene.material.lam
        if self.law == "stable-neo-hookean":
            self.mu, self.lam, self.gamma = stable_neo_hookean(mu, lam)
        else:
            self.mu, self.lam, self.gamma = float(mu), float(lam), 1.0
        self.masses = lumped_masses(scene)
        self.fixed_dofs, fixed_values = scene.dirichlet()
        self.free = np.ones((n, 3))
        self.free.reshape(-1)[self.fixed_dofs] = 0.0
        self._x_fixed = self.x0.ravel()[self.fixed_dofs] + fixed_values
        self._follower = has_follower_loads(scene)
        self.colouring = vertex_colouring(self.tets, n)
        d = self.settings.damping
        self.damping_rate = rayleigh_rate(scene) if d == "auto" else float(d)

    @property
    def h(self) -> float:
        """The substep length ``dt / substeps``."""
        return self.settings.dt / self.settings.substeps

    def accelerations(self, x: np.ndarray) -> np.ndarray:
        """External accelerations ``f_ext / m`` ``(n, 3)`` (follower pressure at ``x``)."""
        f = external_forces(self.scene, x=x if self._follower else None)
        return f / self.masses[:, None]

    def start(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions, velocities and previous velocities at the start (at rest)."""
        x = self.x0.copy()
        x.reshape(-1)[self.fixed_dofs] = self._x_fixed
        return x, np.zeros_like(x), np.zeros_like(x)

    def advance(self, x: np.ndarray, v: np.ndarray, v_old: np.ndarray, a: np.ndarray) -> float:
        """One frame in place; ``substeps`` times the largest nodal motion of a substep."""
        s, c = self.settings, self.colouring
        return float(
            frame(
                x, v, v_old, self.masses, self.free, a, self.tets, self.G, self.V, c.order,
                c.colour_ptr, c.inc_ptr, c.inc_elem, c.inc_local, LAW_CODES[self.law], self.mu,
                self.lam, self.gamma, s.kd, self.h, s.substeps, s.iterations, s.rho,
                math.exp(-self.damping_rate * self.h), INITS.index(s.init),
            )
        )  # fmt: skip

    def run(self, frames: int) -> tuple[np.ndarray, np.ndarray]:
        """``frames`` frames of dynamics from rest; positions and velocities at the end."""
        x, v, v_old = self.start()
        a = self.accelerations(x)
        for _ in range(frames):
            if self._follower:
                a = self.accelerations(x)
            self.advance(x, v, v_old, a)
        return x, v

    def solve(self) -> RestResult:
        """Run to rest (module docstring).

        Raises
        ------
        SolverError
            If the positions stop being finite.
        """
        s = self.settings
        t0 = time.perf_counter()
        x, v, v_old = self.start()
        a = self.accelerations(x)
        calm, converged, k = 0, False, 0
        for k in range(1, s.max_frames + 1):
            checkpoint()
            if self._follower:
                a = self.accelerations(x)
            moved = self.advance(x, v, v_old, a)
            if not np.isfinite(x).all():
                raise SolverError(
                    f"vbd: positions not finite after frame {k} (t = {k * s.dt:.4g} s)"
                )
            scale = float(np.abs(x - self.x0).max())
            calm = calm + 1 if moved <= s.rest_tol * max(scale, 1e-300) else 0
            if calm >= s.rest_frames:
                converged = True
                break
        return RestResult(
            u=x - self.x0, converged=converged, frames=k, substeps=k * s.substeps,
            wall_time=time.perf_counter() - t0, residual=self.residual(x),
            info={"settings": asdict(s), "damping_rate": self.damping_rate,
                  "colours": self.colouring.n_colours},
        )  # fmt: skip

    def iteration_pass(self, x: np.ndarray) -> tuple[Callable[[], None], float]:
        """One Gauss–Seidel sweep over every vertex from positions ``x`` (a copy, moved by
        every call; the inertial target ``x``), at the settings' substep: a function to time
        and the bytes it moves per element (each element's shape gradients, volume and
        nodes read once per corner, the incidence, and once per node positions read and
        written, mass, inertial target and supports read)."""
        c = self.colouring
        p, xt = np.array(x, dtype=float), np.array(x, dtype=float)
        h2 = self.h * self.h
        kd_h = self.settings.kd / self.h
        code = LAW_CODES[self.law]

        def go() -> None:
            _sweep(p, xt, xt, self.masses, self.free, self.tets, self.G, self.V, c.order,
                   c.inc_ptr, c.inc_elem, c.inc_local, code, self.mu, self.lam, self.gamma,
                   kd_h, h2)  # fmt: skip

        m, n = self.tets.shape[0], self.x0.shape[0]
        return go, 4 * (72 + 8 + 32 + 16) + (48 + 8 + 24 + 24) * n / m

    def strain_energy(self, x: np.ndarray) -> float:
        """The stored energy ``sum_e V_e psi(F_e)`` of ``x`` (:mod:`.energy`)."""
        F = deformation_gradients(x, self.tets, self.G)
        return float(np.sum(self.V * density(F, self.mu, self.lam, self.gamma, self.law)))

    def internal(self, x: np.ndarray) -> np.ndarray:
        """Internal nodal forces ``-dE/dx`` ``(n, 3)`` of VBD's energy (numpy, from ``F``)."""
        F = deformation_gradients(x, self.tets, self.G)
        P = first_piola(F, self.mu, self.lam, self.gamma, self.law)
        g = np.concatenate([-self.G.sum(axis=1, keepdims=True), self.G], axis=1)
        fe = -self.V[:, None, None] * np.einsum("kcd,kad->kac", P, g)
        f = np.zeros_like(x)
        np.add.at(f, self.tets, fe)
        return f

    def residual(self, x: np.ndarray) -> float:
        """``|f_int + f_ext|`` on the free DOFs over ``|f_ext|`` (max norms)."""
        ext = external_forces(self.scene, x=x if self._follower else None).ravel()
        r = self.internal(x).ravel() + ext
        free = self.free.ravel() > 0
        ref = float(np.abs(ext[free]).max(initial=0.0))
        return float(np.abs(r[free]).max(initial=0.0)) / (ref if ref > 0 else 1.0)


__all__ = ["INITS", "LAWS", "VBD", "RestResult", "VBDSettings", "rayleigh_rate", "why_not"]
