"""Projective Dynamics on a scene: local/global iterations of its ARAP-like energy (Bouaziz et
al. 2014) or quasi-Newton iterations of neo-Hookean (Liu, Bouaziz & Kavan 2017), frames,
and the run to rest that is its static answer (as :mod:`peers.vbd.solver`'s).

Each frame of ``dt`` is ``substeps`` implicit-Euler substeps; a substep minimises
``|x - y|_M^2 / (2 h^2) + E(x)`` (``y = x + h v + h^2 a_ext``) approximately by
``iterations`` iterations from the guess of :mod:`peers.vbd.kernels` (``init``):

- ``arap`` (local/global): the local step projects every ``F`` (:mod:`.kernels`), the global
  step solves ``(M / h^2 + L) x = M y / h^2 + b`` with ``L = sum_e w_e G_e^T G_e``,
  ``w_e = (2 mu + 3 lam) V_e``, the same matrix for x, y and z, factorised once
  (:func:`scipy.sparse.linalg.splu` on the free nodes) and reused by every iteration and step;
- ``neo-hookean`` (quasi-Newton): L-BFGS (``history`` pairs) with ``M / h^2 + L`` as the
  initial Hessian (the same factorisation) and a backtracking Armijo line search on the
  substep's objective (``+inf`` for an inverted element), the memory cleared every substep.

A rest state is an equilibrium of the energy whatever the iterations: at rest the guess is
the position itself, where the local/global surrogate and the true objective share their
gradient (zero there) and the L-BFGS gradient is zero. Rest and damping as VBD's.

Examples
--------
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({"mesh": {"generator": "box", "size": [0.1, 0.02, 0.02],
...     "divisions": [5, 1, 1]}, "material": {"law": "neo-hookean", "E": 1e4, "nu": 0.3},
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
...     "load": [{"type": "gravity", "value": [0.0, 0.0, -9.81]}]})
>>> out = PD(scene, PDSettings(substeps=10)).solve()
>>> out.converged, bool(out.u[:, 2].min() < 0), bool(out.residual < 1e-4)
(True, True, True)
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, replace
from typing import Literal

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from springfem.errors import InputError, SolverError
from springfem.loads import external_forces, has_follower_loads
from springfem.mechanics.limits import checkpoint
from springfem.scene import Scene

from ..vbd.solver import INITS, RestResult, rayleigh_rate
from .energy import ENERGIES, PDEnergy
from .kernels import local_step, neo_hookean

#: Laws PD takes (their isotropic ``mu, lam`` set its energy).
LAWS = ("linear", "neo-hookean")


@dataclass(frozen=True)
class PDSettings:
    """PD's own settings.

    Parameters
    ----------
    energy
        ``arap`` (local/global) or ``neo-hookean`` (quasi-Newton).
    dt, substeps, iterations
        Frame length (s), substeps per frame, iterations per substep.
    init
        The substep's initial guess (as :class:`peers.vbd.VBDSettings`).
    history
        L-BFGS pairs kept (``neo-hookean``).
    damping, rest_tol, rest_frames, max_frames
        As :class:`peers.vbd.VBDSettings`.
    """

    energy: Literal["arap", "neo-hookean"] = "arap"
    dt: float = 1.0 / 60.0
    substeps: int = 40
    iterations: int = 2
    init: Literal["previous", "inertia", "adaptive"] = "adaptive"
    history: int = 5
    damping: float | Literal["auto"] = "auto"
    rest_tol: float = 1e-6
    rest_frames: int = 2
    max_frames: int = 2_000

    def __post_init__(self):
        if self.energy not in ENERGIES:
            raise InputError(f"pd energy {self.energy!r} is not one of {', '.join(ENERGIES)}")
        if not (self.dt > 0 and self.substeps >= 1 and self.iterations >= 1 and self.history >= 1):
            raise InputError("pd needs dt > 0 and substeps, iterations, history >= 1")
        if self.init not in INITS:
            raise InputError(f"pd init {self.init!r} is not one of {', '.join(INITS)}")
        if self.damping != "auto" and not (
            isinstance(self.damping, int | float) and self.damping >= 0
        ):
            raise InputError(f"pd damping {self.damping!r} is not auto or a rate >= 0")


def why_not(scene: Scene, energy: str = "arap") -> str | None:
    """Why PD with ``energy`` cannot take ``scene`` (``None``: it can): its ARAP-like energy
    takes the isotropic laws' ``mu, lam``, its neo-Hookean form only neo-Hookean scenes."""
    law = scene.material.law
    laws = LAWS if energy == "arap" else ("neo-hookean",)
    if law not in laws:
        name = "pd" if energy == "arap" else "pd-nh"
        return f"model {name}: no {law} law; it takes {', '.join(laws)}"
    return None


def laplacian(tets: np.ndarray, G: np.ndarray, w: np.ndarray, n: int) -> sp.csc_matrix:
    """``L_ab = sum_e w_e g_a . g_b`` ``(n, n)`` (``g_a = grad N_a`` of element ``e``)."""
    g = np.concatenate([-G.sum(axis=1, keepdims=True), G], axis=1)
    Le = w[:, None, None] * np.einsum("kad,kbd->kab", g, g)
    rows = np.repeat(tets, 4, axis=1).ravel()
    cols = np.tile(tets, (1, 4)).ravel()
    return sp.csc_matrix((Le.ravel(), (rows, cols)), shape=(n, n))


class PD:
    """Projective Dynamics of a scene (see the module docstring).

    Parameters
    ----------
    scene
        Mesh, isotropic material, supports, loads.
    settings
        :class:`PDSettings`.
    """

    def __init__(self, scene: Scene, settings: PDSettings | None = None):
        s = settings or PDSettings()
        why = why_not(scene, s.energy)
        if why is not None:
            raise InputError(why)
        self.scene = scene
        self.settings = s
        self.law = s.energy
        self.energy = PDEnergy(scene, s.energy)
        e = self.energy
        self.x0, self.tets, self.G, self.V, self.masses = e.x0, e.tets, e.G, e.V, e.masses
        n = self.x0.shape[0]
        self.fixed_dofs = e.fixed_dofs
        self.free = np.ones((n, 3))
        self.free.reshape(-1)[self.fixed_dofs] = 0.0
        self._x_fixed = e.prescribed(1.0)
        self._follower = has_follower_loads(scene)
        w = (2.0 * e.mu + 3.0 * e.lam) * self.V
        self.A = (laplacian(self.tets, self.G, w, n) + sp.diags(self.masses / self.h**2)).tocsc()
        self._factors: dict[bytes, tuple[np.ndarray, np.ndarray, object]] = {}
        self._coupling: dict[int, np.ndarray] = {}
        self._scratch = np.zeros((n, 3))
        self.damping_rate = rayleigh_rate(scene) if s.damping == "auto" else float(s.damping)

    @property
    def h(self) -> float:
        """The substep length ``dt / substeps``."""
        return self.settings.dt / self.settings.substeps

    def _factor(self, r: int) -> tuple[np.ndarray, np.ndarray, object]:
        """Free and fixed nodes of coordinate ``r`` and the factorisation of ``A_ff``."""
        free = self.free[:, r] > 0
        key = free.tobytes()
        if key not in self._factors:
            f_idx, c_idx = np.flatnonzero(free), np.flatnonzero(~free)
            self._factors[key] = (f_idx, c_idx, splu(self.A[f_idx][:, f_idx].tocsc()))
        return self._factors[key]

    def solve_global(self, rhs: np.ndarray, x: np.ndarray) -> None:
        """``x_f = A_ff^-1 (rhs_f - A_fc x_c)`` per coordinate, in place (``x_c``, the
        supports' prescribed positions, kept: ``A_fc x_c`` is computed once)."""
        for r in range(3):
            f_idx, c_idx, lu = self._factor(r)
            if r not in self._coupling:
                self._coupling[r] = self.A[f_idx][:, c_idx] @ x[c_idx, r]
            x[f_idx, r] = lu.solve(rhs[f_idx, r] - self._coupling[r])  # type: ignore[attr-defined]

    def precondition(self, g: np.ndarray) -> np.ndarray:
        """``A^-1 g`` on the free DOFs (zero on the fixed ones)."""
        out = np.zeros_like(g)
        for r in range(3):
            f_idx, _, lu = self._factor(r)
            out[f_idx, r] = lu.solve(g[f_idx, r])  # type: ignore[attr-defined]
        return out

    def accelerations(self, x: np.ndarray) -> np.ndarray:
        """External accelerations ``f_ext / m`` ``(n, 3)``."""
        f = external_forces(self.scene, x=x if self._follower else None)
        return f / self.masses[:, None]

    def start(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions, velocities and previous velocities at the start (at rest)."""
        x = self.x0.copy()
        x.reshape(-1)[self.fixed_dofs] = self._x_fixed
        return x, np.zeros_like(x), np.zeros_like(x)

    def _objective(self, x: np.ndarray, y: np.ndarray) -> float:
        """The substep's objective (neo-Hookean; compiled, :func:`.kernels.neo_hookean`)."""
        e, m = self.energy, self.masses[:, None]
        work = neo_hookean(x, self.tets, self.G, self.V, e.mu, e.lam, self._scratch, False)
        return 0.5 * float(np.sum(m * (x - y) ** 2)) / self.h**2 + work

    def _gradient(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        e = self.energy
        g = self.masses[:, None] * (x - y) / self.h**2
        neo_hookean(x, self.tets, self.G, self.V, e.mu, e.lam, g, True)
        return g * self.free

    def _local_global(self, x: np.ndarray, y: np.ndarray) -> None:
        e = self.energy
        for _ in range(self.settings.iterations):
            b = self.masses[:, None] * y / self.h**2
            local_step(x, self.tets, self.G, self.V, e.mu, e.lam, b)
            self.solve_global(b, x)

    def _quasi_newton(self, x: np.ndarray, y: np.ndarray) -> None:
        s_hist: list[np.ndarray] = []
        y_hist: list[np.ndarray] = []
        g = self._gradient(x, y)
        phi = self._objective(x, y)
        for _ in range(self.settings.iterations):
            q = g.copy()
            alphas = []
            for si, yi in zip(reversed(s_hist), reversed(y_hist), strict=True):
                a = float(np.sum(si * q)) / float(np.sum(yi * si))
                alphas.append(a)
                q -= a * yi
            d = self.precondition(q)
            for si, yi, a in zip(s_hist, y_hist, reversed(alphas), strict=True):
                d += si * (a - float(np.sum(yi * d)) / float(np.sum(yi * si)))
            d = -d
            slope = float(np.sum(g * d))
            if not slope < 0:
                s_hist.clear()
                y_hist.clear()
                d = -self.precondition(g)
                slope = float(np.sum(g * d))
                if not slope < 0:
                    return
            t = 1.0
            for _ls in range(30):
                x_new = x + t * d
                phi_new = self._objective(x_new, y)
                if phi_new <= phi + 1e-4 * t * slope:
                    break
                t *= 0.5
            else:
                return
            g_new = self._gradient(x_new, y)
            sv, yv = x_new - x, g_new - g
            if float(np.sum(sv * yv)) > 0:
                s_hist.append(sv)
                y_hist.append(yv)
                if len(s_hist) > self.settings.history:
                    s_hist.pop(0)
                    y_hist.pop(0)
            x[...] = x_new
            g, phi = g_new, phi_new

    def advance(self, x: np.ndarray, v: np.ndarray, v_old: np.ndarray, a: np.ndarray) -> float:
        """One frame in place; ``substeps`` times the largest nodal motion of a substep."""
        s = self.settings
        h = self.h
        a = a * self.free
        damp = math.exp(-self.damping_rate * h)
        moved = 0.0
        for _ in range(s.substeps):
            xt = x.copy()
            y = x + h * v + h * h * a
            if s.init == "inertia":
                x[...] = y
            elif s.init == "adaptive":
                acc = (v - v_old) / h
                ae2 = np.sum(a * a, axis=1)
                w = np.where(ae2 > 0, np.sum(acc * a, axis=1) / np.where(ae2 > 0, ae2, 1.0), 0.0)
                x += h * v + h * h * np.clip(w, 0.0, 1.0)[:, None] * a
            if s.energy == "arap":
                self._local_global(x, y)
            else:
                self._quasi_newton(x, y)
            step = x - xt
            moved = max(moved, float(np.abs(step).max()))
            v_old[...] = v
            v[...] = step / h * damp
        return moved * s.substeps

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
                    f"pd: positions not finite after frame {k} (t = {k * s.dt:.4g} s)"
                )
            scale = float(np.abs(x - self.x0).max())
            calm = calm + 1 if moved <= s.rest_tol * max(scale, 1e-300) else 0
            if calm >= s.rest_frames:
                converged = True
                break
        return RestResult(
            u=x - self.x0, converged=converged, frames=k, substeps=k * s.substeps,
            wall_time=time.perf_counter() - t0, residual=self.residual(x),
            info={"settings": asdict(s), "damping_rate": self.damping_rate},
        )  # fmt: skip

    def iteration_pass(self, x: np.ndarray) -> tuple[Callable[[], None], float]:
        """One iteration from positions ``x`` (a copy, moved by every call; the inertial
        target ``x``): local step and global solve (``arap``), or an L-BFGS step (its
        memory cleared every call): a function to time and the bytes its element pass
        moves per element (shape gradients, volume, nodes read, and once per node the
        positions read and the right-hand side written)."""
        p, y = np.array(x, dtype=float), np.array(x, dtype=float)
        one = replace(self.settings, iterations=1)
        stepper = PD.__new__(PD)
        stepper.__dict__.update(self.__dict__)
        stepper.settings = one

        def go() -> None:
            if one.energy == "arap":
                stepper._local_global(p, y)
            else:
                stepper._quasi_newton(p, y)

        m, n = self.tets.shape[0], self.x0.shape[0]
        return go, 72 + 8 + 32 + 48 * n / m

    def strain_energy(self, x: np.ndarray) -> float:
        """The stored energy of ``x`` (:class:`peers.pd.energy.PDEnergy`)."""
        return self.energy.strain_energy(x)

    def residual(self, x: np.ndarray) -> float:
        """``|f_int + f_ext|`` on the free DOFs over ``|f_ext|`` (max norms)."""
        ext = self.energy.external(x).ravel()
        r = self.energy.internal(x).ravel() + ext
        free = self.free.ravel() > 0
        ref = float(np.abs(ext[free]).max(initial=0.0))
        return float(np.abs(r[free]).max(initial=0.0)) / (ref if ref > 0 else 1.0)


__all__ = ["LAWS", "PD", "PDSettings", "laplacian", "why_not"]
