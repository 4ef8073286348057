"""A plug-in model (:class:`springfem.model_api.ModelPlugin`) for a peer whose static answer
is a run of its own frames to rest: Vertex Block Descent and Projective Dynamics.

A subclass names its settings dataclass, its solver (``Solver(scene, settings)`` with
``solve() -> RestResult``-like and ``run(frames) -> (x, v)``), its ``why_not(scene)``, its
law and a label; the sweep (substeps x iterations) is shared.

Examples
--------
>>> SWEEP[0], len(SWEEP)
({'substeps': 40, 'iterations': 2}, 6)
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Mapping
from dataclasses import asdict, replace
from typing import Any, ClassVar

import numpy as np

from springfem.errors import InputError, SolverError
from springfem.mechanics.limits import Deadline
from springfem.mechanics.system import MechanicalSystem
from springfem.model_api import ModelSolution, model_result
from springfem.scene import Scene

#: Substeps x iterations, most telling first (a quick study takes the first few): the
#: default and 80 substeps, the rest of the substep series at 2 iterations, then 1 and 4
#: iterations at the default 40 substeps.
SWEEP: tuple[Mapping[str, Any], ...] = tuple(
    {"substeps": n, "iterations": k} for n, k in ((40, 2), (80, 2), (20, 2), (10, 2), (40, 1),
                                                 (40, 4))
)  # fmt: skip


#: Substeps x iterations a frame-rate search tries, cheapest frame first
#: (:func:`springfem.frames.frames_settings`).
FRAME_SWEEP: tuple[Mapping[str, Any], ...] = tuple(
    {"substeps": n, "iterations": k}
    for n, k in sorted(((n, k) for n in (1, 2, 5, 10, 20, 40, 80, 160) for k in (1, 2)),
                       key=lambda nk: (nk[0] * nk[1], nk[1]))
)  # fmt: skip


class PeerFrames:
    """A peer's own frames (:class:`springfem.frames.FrameStepper`): its solver's ``start``
    and ``advance`` at ``dt = frame_dt``, damped at the scene's mass-proportional rate; the
    loads are scaled by the load factor at the frame's end (each load by its own factor
    when they differ, :class:`springfem.frames.LoadHistory`) at the frame's middle: one
    load a frame, so a release on a frame's boundary lands there.

    Parameters
    ----------
    solver
        The peer's solver (``start()``, ``advance(*state, a_ext)``, ``accelerations(x)``,
        ``masses``, ``x0``, ``settings``).
    scene
        The scene (the stored energy: the solver's ``strain_energy`` or, for a stable
        neo-Hookean peer, :class:`peers.xpbd.StableNeoHookean`'s).
    """

    def __init__(self, solver: Any, scene: Scene):
        self.solver = solver
        self.frame_dt = float(solver.settings.dt)
        self.masses = solver.masses
        self.x0 = solver.x0
        self.settings = {"substeps": solver.settings.substeps,
                         "iterations": solver.settings.iterations}  # fmt: skip
        energy = getattr(solver, "strain_energy", None)
        if energy is None and getattr(solver, "law", "stable-neo-hookean") == "stable-neo-hookean":
            from .xpbd import StableNeoHookean

            energy = StableNeoHookean(scene).strain_energy
        self._energy = energy
        self._state: tuple[np.ndarray, ...] = ()
        self._a: np.ndarray | None = None

    @classmethod
    def of(cls, model: Any, scene: Scene, frame_dt: float) -> PeerFrames:
        """The frames of plug-in ``model`` (its ``_settings``, ``Solver``/``_solver``)."""
        from springfem.frames import scene_damping

        why = model.applies(scene)
        if why is not None:
            raise InputError(why)
        s = replace(model._settings, dt=frame_dt, damping=scene_damping(scene))
        from .xpbd.solver import XPBD

        solver_type: Any = getattr(type(model), "Solver", XPBD)
        return cls(solver_type(scene, s), scene)

    def start(self) -> tuple[np.ndarray, np.ndarray]:
        self._state = tuple(self.solver.start())
        self._a = self.solver.accelerations(self._state[0])
        return self._state[0], self._state[1]

    def frame(self, x: np.ndarray, v: np.ndarray, t: float, scale: Any) -> None:
        from springfem.frames import LoadHistory

        solver, t1 = self.solver, t + 0.5 * self.frame_dt
        state = (x, v, *self._state[2:])
        if isinstance(scale, LoadHistory) and not scale.single:
            solver.advance(*state, scale.external(x, t1) / self.masses[:, None])
            return
        if getattr(solver, "_follower", False) or self._a is None:
            self._a = solver.accelerations(x)
        solver.advance(*state, self._a * scale(t1))

    def strain_energy(self, x: np.ndarray) -> float | None:
        return None if self._energy is None else float(self._energy(x))


class RestModel:
    """A peer solved by frames to rest, as a plug-in model.

    Parameters
    ----------
    name, label
        See :class:`~springfem.model_api.ModelPlugin` (label ``None``: :meth:`make_label`).
    default
        Weighed by the studies without being named.
    **settings
        Fields of the subclass's settings dataclass.
    """

    Settings: ClassVar[Callable[..., Any]]
    Solver: ClassVar[Callable[..., Any]]
    #: ``why_not(scene)``: why the peer cannot take a scene (``None``: it can).
    why_not: ClassVar[staticmethod[[Scene], str | None]]
    #: What it solves (the verdict's ``law vs reference``; a solver's ``law`` attribute,
    #: where it has one, names the result's law on a scene).
    law: str = ""
    #: The default name.
    default_name: ClassVar[str] = ""

    def __init__(self, name: str | None = None, label: str | None = None, default: bool = True,
                 **settings: Any):  # fmt: skip
        self.name = name or self.default_name
        self._settings = type(self).Settings(**settings)
        self.settings: Mapping[str, Any] = asdict(self._settings)
        self.label = label or self.make_label()
        self.default = default
        self.sweep: tuple[Mapping[str, Any], ...] = SWEEP
        self.frame_sweep = FRAME_SWEEP

    def make_label(self) -> str:
        """The label of the current settings."""
        return self.name

    def with_settings(self, **settings: Any) -> RestModel:
        """The same model with some settings changed (its label follows them)."""
        return type(self)(self.name, None, self.default, **{**self.settings, **settings})

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name!r}, settings={dict(self.settings)!r})"

    def applies(self, scene: Scene) -> str | None:
        return type(self).why_not(scene)

    def system(self, scene: Scene) -> MechanicalSystem | None:
        """``None``: the peer moves positions by its own iterations, not by forces."""
        return None

    def frames(self, scene: Scene, frame_dt: float) -> PeerFrames:
        """The peer's own frames of ``frame_dt`` (:class:`PeerFrames`)."""
        return PeerFrames.of(self, scene, frame_dt)

    @property
    def setting_step(self) -> float:
        """The substep of its settings, ``dt / substeps`` (s)."""
        return float(self._settings.dt / self._settings.substeps)

    def release_run(self, scene: Scene, **run: Any) -> dict[str, Any]:
        """Released from its rest state, its own undamped substeps:
        :func:`peers.rest_release.release_run` (``t_end``, ``safety``, ``samples``,
        ``probe``)."""
        from .rest_release import release_run

        return release_run(self, scene, **run)

    def step_timer(self, scene: Scene, safety: float) -> Callable[[int, Callable[[], None]], None]:
        """``(steps, tick)`` running its substeps from rest:
        :func:`peers.rest_release.step_timer`."""
        from .rest_release import step_timer

        return step_timer(self, scene, safety)

    def kernel_pass(self, scene: Scene) -> tuple[Callable[[], object], float]:
        """One iteration over every element at a deformed state (its settings, undamped):
        a function to time and the bytes it moves per element (the solver's
        ``iteration_pass``; ``springfem bench forces``)."""
        solver = type(self).Solver(scene, replace(self._settings, damping=0.0))
        x0 = solver.x0
        rng = np.random.default_rng(0)  # a stretch and a little noise, as XPBD's pass
        x = x0 * [1.02, 0.99, 0.995] + 1e-3 * np.ptp(x0) * rng.standard_normal(x0.shape)
        return solver.iteration_pass(x)

    def _solver(self, scene: Scene) -> Any:
        why = self.applies(scene)
        if why is not None:
            raise InputError(why)
        return type(self).Solver(scene, self._settings)

    def solve(self, scene: Scene, verbose: bool = False) -> ModelSolution:
        """The rest state under the scene's loads.

        Raises
        ------
        SolverError
            When rest does not come within ``max_frames`` or the positions stop being finite.
        SolveStopped
            At the time cap of :func:`springfem.mechanics.limits.solve_limits`.
        """
        deadline = Deadline()
        deadline.progress = "frames to rest"
        try:
            with deadline.watch():
                solver = self._solver(scene)
                out = solver.solve()
        except KeyboardInterrupt:
            raise deadline.stopped(interrupted=True) from None
        if not out.converged:
            raise SolverError(
                f"{self.name}: no rest after {out.frames} frames: still moving by more than "
                f"rest_tol = {self.settings['rest_tol']:g} of its displacement"
            )
        if verbose:
            print(f"{self.name}: rest after {out.frames} frames", file=sys.stderr)
        info = {"frames": out.frames, "substeps": out.substeps, "settings": dict(self.settings),
                "equilibrium_residual": out.residual, **out.info}  # fmt: skip
        info["settings"] = dict(self.settings)
        result = model_result(
            scene, out.u, model=self.name, element="P1", law=getattr(solver, "law", self.law),
            wall_time=out.wall_time, converged=True, iterations=out.substeps, info=info,
        )  # fmt: skip
        return ModelSolution(result, out.u)

    def run(self, scene: Scene, frames: int) -> ModelSolution:
        """``frames`` frames of the peer's dynamics from rest under the loads.

        Returns
        -------
        ModelSolution
            ``status`` "end of run at t = ...".
        """
        solver = self._solver(scene)
        t0 = time.perf_counter()
        x, _ = solver.run(frames)
        t = frames * self._settings.dt
        result = model_result(
            scene, x - solver.x0, model=self.name, element="P1",
            law=getattr(solver, "law", self.law),
            wall_time=time.perf_counter() - t0, converged=False,
            iterations=frames * self._settings.substeps,
            info={"frames": frames, "settings": dict(self.settings)},
            status=f"end of run at t = {t:.4g} s after {frames} frames",
        )  # fmt: skip
        return ModelSolution(result, np.asarray(x - solver.x0))


__all__ = ["FRAME_SWEEP", "SWEEP", "PeerFrames", "RestModel"]
