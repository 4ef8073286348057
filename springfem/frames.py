"""Frame stepping: a model advanced one display or haptic frame at a time.

A real-time simulator shows a frame every ``1 / rate`` seconds and, within it, takes as
many inner steps (substeps, iterations) as its budget allows. A :class:`FrameStepper` is
that loop for one model at one choice of settings: ``start()`` gives the state at rest,
``frame(x, v, t, scale)`` advances it in place from ``t`` to ``t + frame_dt`` under the load
factor ``scale(t)`` (the scene's time functions, docs/scenes.rst).

A model of the plug-in API (:mod:`springfem.model_api`) offers frames in one of two ways:

- its own method ``frames(scene, frame_dt)`` returning a :class:`FrameStepper` (XPBD, VBD,
  Projective Dynamics: their substeps and iterations are the settings);
- an explicit form (``system(scene)``): :class:`ExplicitFrames` steps it by velocity Verlet
  at ``safety`` times the critical step ``2 / omega_max`` at rest, as many substeps as a
  frame needs (the stability limit fixes the cost; ``safety`` is the only setting).

:func:`frame_stepper` picks the way; :func:`frames_settings` lists the settings a frame-rate
search tries.

Examples
--------
An undamped oscillator released from rest under a constant load swings between 0 and
twice its static displacement:

>>> import numpy as np
>>> from springfem.mechanics.toy import Oscillator
>>> stepper = ExplicitFrames(Oscillator(), frame_dt=0.05)
>>> x, v = stepper.start()
>>> xs = []
>>> for k in range(200):
...     stepper.frame(x, v, 0.05 * k, lambda t: 1.0)
...     xs.append(float(x[0, 0]))
>>> stepper.substeps >= 1, bool(np.isfinite(xs).all())
(True, True)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Protocol, runtime_checkable

import numpy as np

from .mechanics.context import SolveContext
from .mechanics.system import MechanicalSystem
from .mechanics.timestep import stable_time_step

#: The fractions of the critical step an explicit model is tried at in a frame-rate search
#: (largest first: the cheapest frame).
SAFETIES = (0.9, 0.7, 0.5)

ScaleFn = Callable[[float], float]


class LoadHistory:
    """The scene's loads as functions of time (each ``[[load]]``'s ``time``, docs/scenes.rst).

    When every load follows the same time function (or none has one), the history is one
    load factor ``g(t)`` (:meth:`__call__`), which any model's ``scale`` takes. Otherwise
    (gravity always on, a tool's pull ramped and released) a model steps with its internal
    forces at load factor 0 plus :meth:`external`, the sum of each load's force times its
    own factor; :attr:`single` tells which.

    Parameters
    ----------
    scene
        The scene.
    """

    def __init__(self, scene: Any):
        from dataclasses import replace

        from .loads import external_forces

        self.scene = scene
        loads = list(scene.loads)
        fns = [getattr(load, "time", None) for load in loads]
        self.single = all(repr(f) == repr(fns[0]) for f in fns)
        self._fn = fns[0] if fns else None
        self._parts: list[tuple[Any, Any, np.ndarray | None]] = []
        self._rest_force: np.ndarray | None = None
        self._follower: bool | None = None
        if not self.single:
            for load, fn in zip(loads, fns, strict=True):
                sub = replace(scene, loads=[load])
                fixed = None if load.type == "pressure" else external_forces(sub)
                self._parts.append((fn, sub, fixed))

    def __call__(self, t: float) -> float:
        """The common load factor at ``t`` (1 when there is none)."""
        return 1.0 if self._fn is None else float(self._fn(t))

    def left(self, t: float) -> float:
        """The common load factor just before ``t`` (differs from ``self(t)`` at a jump)."""
        return 1.0 if self._fn is None else float(self._fn.left(t))

    def jumps(self) -> set[float]:
        """The times where some load jumps (a release)."""
        fns = [getattr(load, "time", None) for load in self.scene.loads]
        return {float(t) for f in fns if f is not None for t in f.jumps()}

    def external(self, x: np.ndarray, t: float, left: bool = False) -> np.ndarray:
        """``sum_i g_i(t) f_i(x)``: every load at its own factor ``(n, 3)`` (``left``: the
        factors just before ``t``)."""
        from .loads import external_forces

        f = np.zeros_like(x)
        for fn, sub, fixed in self._parts:
            g = 1.0 if fn is None else float(fn.left(t) if left else fn(t))
            if g:
                f += g * (fixed if fixed is not None else external_forces(sub, x=x))
        return f

    def force(self, x: np.ndarray, t: float) -> np.ndarray:
        """The external force at ``x`` and time ``t`` ``(n, 3)``: every load at its factor."""
        if not self.single:
            return self.external(x, t)
        from .loads import external_forces, has_follower_loads

        g = self(t)
        if not g:
            return np.zeros_like(x)
        if self._follower is None:
            self._follower = has_follower_loads(self.scene)
        if self._rest_force is None or self._follower:
            f = external_forces(self.scene, x=x)
            if not self._follower:
                self._rest_force = f
            return g * f
        return g * self._rest_force

    def settles_at(self) -> float:
        """The time after which no load changes (0 without time functions)."""
        fns = [getattr(load, "time", None) for load in self.scene.loads]
        points = [t for f in fns if f is not None for t in f.breakpoints()]
        return max(points, default=0.0)


@runtime_checkable
class FrameStepper(Protocol):
    """One model at one setting, advanced a frame at a time.

    Attributes
    ----------
    frame_dt
        The frame length (s).
    masses
        Lumped nodal masses ``(n,)`` (kinetic energy).
    x0
        Rest positions ``(n, 3)``.
    settings
        What was chosen (substeps, iterations, safety ...), plain values.
    """

    frame_dt: float
    masses: np.ndarray
    x0: np.ndarray
    settings: dict[str, Any]

    def start(self) -> tuple[np.ndarray, np.ndarray]:
        """Positions and velocities at rest (supports in place)."""
        ...

    def frame(self, x: np.ndarray, v: np.ndarray, t: float, scale: ScaleFn) -> None:
        """Advance ``x, v`` in place from ``t`` to ``t + frame_dt``."""
        ...

    def strain_energy(self, x: np.ndarray) -> float | None:
        """The model's own stored energy at ``x`` (``None``: it has none)."""
        ...


class ExplicitFrames:
    """Velocity Verlet frames of a mechanical system (see the module docstring).

    Parameters
    ----------
    system
        The explicit form.
    frame_dt
        Frame length (s).
    safety
        Fraction of the critical step at rest; the substep is ``frame_dt / substeps`` with
        the fewest substeps that keep it at or below ``safety * 2 / omega_max``.
    mass_damping
        Mass-proportional damping rate ``alpha`` (1/s), applied exactly per substep.
    stiffness_damping
        Stiffness-proportional Rayleigh coefficient ``a_K`` (s): a force ``-a_K K_0 v``
        with the tangent at rest ``K_0`` (it lowers the stable step: the substep keeps
        ``h <= safety (sqrt(1 + (a_K w)^2) - a_K w) 2 / w``).
    dt_crit
        The critical step, when already known (else computed: one eigenvalue solve).
    """

    def __init__(
        self,
        system: MechanicalSystem,
        frame_dt: float,
        safety: float = 0.5,
        mass_damping: float = 0.0,
        dt_crit: float | None = None,
        stiffness_damping: float = 0.0,
    ):
        self.system = system
        self.ctx = SolveContext(system)
        self.frame_dt = float(frame_dt)
        self.dt_crit = float(dt_crit) if dt_crit else stable_time_step(system)[0]
        self.K0 = None
        if stiffness_damping:
            w = 2.0 / self.dt_crit
            z = stiffness_damping * w / 2.0  # the damping ratio of the highest mode
            self.dt_crit *= math.sqrt(1.0 + z * z) - z
            K = self.ctx.stiffness(self.ctx.x0, 0.0)  # analytic, else coloured differences
            self.K0 = stiffness_damping * K.tocsr()
        self.substeps = max(1, math.ceil(self.frame_dt / (safety * self.dt_crit) - 1e-9))
        self.h = self.frame_dt / self.substeps
        self.masses = self.ctx.m
        self.x0 = self.ctx.x0
        self.decay = math.exp(-0.5 * mass_damping * self.h) if mass_damping else 1.0
        self.settings = {"safety": safety, "substeps": self.substeps, "dt": self.h}
        self._a: np.ndarray | None = None

    def start(self) -> tuple[np.ndarray, np.ndarray]:
        """Rest positions (fixed DOFs at ``prescribed(0)``) and zero velocities."""
        x = self.x0.copy()
        if self.ctx.fixed.size:
            x.reshape(-1)[self.ctx.fixed] = self.system.prescribed(0.0)
        self._a = None
        return x, np.zeros_like(x)

    def _acc(
        self, x: np.ndarray, v: np.ndarray, s: float, t: float, scale: Any, left: bool = False
    ) -> np.ndarray:
        if isinstance(scale, LoadHistory) and not scale.single:
            f = self.ctx.forces(x, v, 0.0) + scale.external(x, t, left)
        else:
            f = self.ctx.forces(x, v, s)
        if self.K0 is not None:
            f = f - (self.K0 @ v.reshape(-1)).reshape(-1, 3)
        a = f / self.masses[:, None]
        if self.ctx.fixed.size:
            a.reshape(-1)[self.ctx.fixed] = 0.0
        return a

    def frame(self, x: np.ndarray, v: np.ndarray, t: float, scale: ScaleFn) -> None:
        """``substeps`` Verlet steps; fixed DOFs follow ``prescribed(scale(t))`` (a
        :class:`LoadHistory` of several time functions: each load its own factor, the
        supports' displacements in full)."""
        h, fixed = self.h, self.ctx.fixed
        history = scale if isinstance(scale, LoadHistory) else None
        split = history is not None and not history.single
        jumps = history.jumps() if history is not None else set()
        a = self._a if self._a is not None else self._acc(x, v, scale(t), t, scale)
        xf, vf = x.reshape(-1), v.reshape(-1)
        for k in range(1, self.substeps + 1):
            tk = t + k * h
            jump = any(abs(tk - j) <= 1e-9 * max(h, abs(tk)) for j in jumps)
            # at a jump of a load the closing half kick takes the load just before it
            s = 1.0 if split else (history.left(tk) if history and jump else scale(tk))
            if self.decay != 1.0:
                v *= self.decay
            v += 0.5 * h * a
            x += h * v
            if fixed.size:
                p = self.system.prescribed(s)
                vf[fixed] = (p - xf[fixed]) / h
                xf[fixed] = p
            a = self._acc(x, v, s, tk, scale, left=jump)
            v += 0.5 * h * a
            if self.decay != 1.0:
                v *= self.decay
            if jump:  # and the next opening half kick the load just after it
                a = self._acc(x, v, 1.0 if split else scale(tk), tk, scale)
            self.system.post_step(x, h)
        self._a = a

    def strain_energy(self, x: np.ndarray) -> float | None:
        """The system's energy at zero load (its stored energy), ``None`` if it has none."""
        e = self.system.energy(x, 0.0)
        return None if e is None else float(e)


def frame_stepper(model: Any, scene: Any, frame_dt: float, **settings: Any) -> FrameStepper | None:
    """The frames of ``model`` on ``scene`` at ``settings`` (``None``: it has none).

    Parameters
    ----------
    model
        A plug-in model (:class:`springfem.model_api.ModelPlugin`).
    scene
        The scene.
    frame_dt
        Frame length (s).
    **settings
        For a model's own frames: changes of its settings (``with_settings``); for an
        explicit form: ``safety`` and ``dt_crit`` of :class:`ExplicitFrames`.
    """
    own = getattr(model, "frames", None)
    if callable(own):
        if settings:
            model = model.with_settings(**settings)
        return model.frames(scene, frame_dt)
    system = model.system(scene)
    if system is None:
        return None
    a_m, a_k = rayleigh(scene)
    return ExplicitFrames(system, frame_dt, mass_damping=a_m, stiffness_damping=a_k, **settings)


def frames_settings(model: Any) -> list[dict[str, Any]]:
    """The settings a frame-rate search tries for ``model``, cheapest frame first: a model's
    own ``frame_sweep`` (or ``sweep``) reversed to cheapest first is its business; an explicit
    form tries :data:`SAFETIES`."""
    own = getattr(model, "frame_sweep", None)
    if own is not None:
        return [dict(s) for s in own]
    if callable(getattr(model, "frames", None)):
        return [dict(s) for s in getattr(model, "sweep", ())] or [{}]
    return [{"safety": s} for s in SAFETIES]


def scene_damping(scene: Any) -> float:
    """The mass-proportional rate ``a_M`` (1/s) of the scene's Rayleigh damping
    (``[dynamics] damping``), 0 when it sets none."""
    return rayleigh(scene)[0]


def rayleigh(scene: Any) -> tuple[float, float]:
    """``(a_M, a_K)`` of the scene's ``[dynamics] damping`` (``C = a_M M + a_K K_0``)."""
    from .scene.dynamics import DynamicsOptions

    d = DynamicsOptions.of(scene).damping
    return float(d.mass), float(d.stiffness)
