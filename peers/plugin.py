"""XPBD and the edge mass–spring network as models of the plug-in API
(:mod:`springfem.model_api`; docs/peers.rst).

``xpbd``
    the run to rest of :class:`peers.xpbd.XPBD` (its own settings: frame, substeps,
    iterations, Gauss–Seidel or Jacobi, coupled or sequential, damping, rest tolerance); it
    has no force-based explicit form (:meth:`XPBDModel.system` is ``None``), its dynamics
    are its own frames (:meth:`XPBDModel.run`);
``mass-spring``
    :class:`peers.mass_spring.MassSpring` through :class:`~springfem.model_api.SystemModel`:
    Newton for the static answer, the core's integrators for timed runs;
``vbd``
    Vertex Block Descent's run to rest (:class:`peers.vbd.model.VBDModel`);
``pd``, ``pd-nh``
    Projective Dynamics' run to rest, with its ARAP-like energy and in its quasi-Newton
    neo-Hookean form (:mod:`peers.pd.model`).

All are weighed by default where they apply (``default`` true: the verdict and the
studies of docs/peers.rst#in-the-studies). The entry
point ``peers = "peers.plugin:models"`` of group ``springfem.models`` registers them.

Examples
--------
>>> [m.name for m in models()], models()[0].settings["substeps"]
(['xpbd', 'mass-spring', 'vbd', 'pd', 'pd-nh'], 40)
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Mapping
from dataclasses import asdict, replace
from functools import cache
from typing import Any

import numpy as np

from springfem.errors import InputError, SolverError
from springfem.mechanics.limits import Deadline
from springfem.mechanics.system import MechanicalSystem
from springfem.model_api import ModelSolution, SystemModel, model_result
from springfem.scene import Scene

from .mass_spring.network import MassSpring
from .mass_spring.network import why_not as mass_spring_why_not
from .pd.model import PDModel, PDNHModel
from .rest_model import FRAME_SWEEP, PeerFrames, RestModel
from .vbd.model import VBDModel
from .xpbd.solver import XPBD, XPBDSettings
from .xpbd.solver import why_not as xpbd_why_not


class XPBDModel:
    """XPBD as a plug-in model: :meth:`solve` runs to rest.

    Parameters
    ----------
    name, label
        See :class:`~springfem.model_api.ModelPlugin`.
    default
        Weighed by the studies without being named.
    **settings
        Fields of :class:`peers.xpbd.XPBDSettings`.

    Attributes
    ----------
    sweep
        The settings the speed-accuracy study charts (:data:`SWEEP`, substeps x iterations;
        see :class:`~springfem.model_api.ModelPlugin`); :meth:`with_settings` makes each.
    variants
        Named changes of its settings the stability study weighs beside it (:data:`VARIANTS`).
    setting_step
        The substep of its settings, ``dt / substeps`` (s).
    """

    #: Jacobi iteration beside the own Gauss–Seidel: the step search and the run to rest
    #: (at most 3,000 frames: 20,000 cost minutes when rest never comes, and
    #: docs/peers.rst's measured runs took at most 3,000).
    VARIANTS: Mapping[str, Mapping[str, Any]] = {
        "xpbd-jacobi": {"iteration": "jacobi", "max_frames": 3000}
    }

    #: Substeps x iterations, most telling first (a quick study takes the first few, every
    #: level the first): the default and 80 substeps, the rest of the substep series at 2
    #: iterations, then 1 and 4 iterations at the default 40 substeps (a series is the
    #: points whose other settings are the defaults).
    SWEEP: tuple[Mapping[str, Any], ...] = tuple(
        {"substeps": n, "iterations": k} for n, k in ((40, 2), (80, 2), (20, 2), (10, 2),
                                                     (40, 1), (40, 4))
    )  # fmt: skip

    def __init__(self, name: str = "xpbd", label: str | None = None, default: bool = True,
                 **settings: Any):  # fmt: skip
        self.name = name
        self._settings = XPBDSettings(**settings)
        s = self._settings
        self.label = label or f"XPBD stable neo-Hookean ({s.substeps} substeps x {s.iterations})"
        self.default = default
        self.settings: Mapping[str, Any] = asdict(s)
        self.sweep: tuple[Mapping[str, Any], ...] = self.SWEEP
        self.variants: Mapping[str, Mapping[str, Any]] = self.VARIANTS
        self.setting_step = s.dt / s.substeps
        #: What it solves (the verdict's ``law vs reference``).
        self.law = "stable-neo-hookean"

    def with_settings(self, **settings: Any) -> XPBDModel:
        """The same model with some settings changed (its label follows them).

        Examples
        --------
        >>> XPBDModel().with_settings(substeps=40).label
        'XPBD stable neo-Hookean (40 substeps x 2)'
        """
        return XPBDModel(self.name, None, self.default, **{**self.settings, **settings})

    def __repr__(self) -> str:
        return f"XPBDModel({self.name!r}, settings={dict(self.settings)!r})"

    frame_sweep = FRAME_SWEEP

    def frames(self, scene: Scene, frame_dt: float) -> PeerFrames:
        """XPBD's own frames of ``frame_dt`` (:class:`peers.rest_model.PeerFrames`)."""
        return PeerFrames.of(self, scene, frame_dt)

    def applies(self, scene: Scene) -> str | None:
        return xpbd_why_not(scene)

    def system(self, scene: Scene) -> MechanicalSystem | None:
        """``None``: XPBD moves positions by constraint projection, not by forces."""
        return None

    def _solver(self, scene: Scene) -> XPBD:
        why = self.applies(scene)
        if why is not None:
            raise InputError(why)
        return XPBD(scene, self._settings)

    def solve(self, scene: Scene, verbose: bool = False) -> ModelSolution:
        """The rest state under the scene's loads.

        Raises
        ------
        SolverError
            When rest does not come within ``max_frames`` (a moving state is no static
            answer; the error names the frames) or the positions stop being finite.
        SolveStopped
            At the time cap of :func:`springfem.mechanics.limits.solve_limits` (``--max-time``,
            a study's budget): a watchdog interrupts the frames.
        """
        deadline = Deadline()
        deadline.progress = "frames to rest"
        try:
            with deadline.watch():
                out = self._solver(scene).solve()
        except KeyboardInterrupt:
            raise deadline.stopped(interrupted=True) from None
        if not out.converged:
            s = self._settings
            raise SolverError(
                f"{self.name}: no rest after {out.frames} frames ({out.frames * s.dt:.4g} s): "
                f"still moving by more than rest_tol = {s.rest_tol:g} of its displacement"
            )
        if verbose:
            print(f"{self.name}: rest after {out.frames} frames ({out.substeps} substeps)",
                  file=sys.stderr)  # fmt: skip
        info = {"frames": out.frames, "substeps": out.substeps, "settings": dict(self.settings),
                "equilibrium_residual": out.residual}  # fmt: skip
        result = model_result(
            scene, out.u, model=self.name, element="P1", law="stable-neo-hookean",
            wall_time=out.wall_time, converged=out.converged, iterations=out.substeps, info=info,
        )  # fmt: skip
        return ModelSolution(result, out.u)

    def largest_step(self, scene: Scene, steps: int, bisections: int) -> dict[str, Any]:
        """The largest substep its undamped run survives (loads off), against
        ``2 / omega_max`` of its energy: :func:`peers.xpbd.step_search.largest_step`."""
        from .xpbd.step_search import largest_step

        return largest_step(scene, self._settings, steps, bisections)

    def release_run(self, scene: Scene, **run: Any) -> dict[str, Any]:
        """Released from its rest state, its own undamped substeps:
        :func:`peers.xpbd.release.release_run` (``t_end``, ``safety``, ``samples``,
        ``probe``)."""
        from .xpbd.release import release_run

        return release_run(scene, self._settings, **run)

    def step_timer(self, scene: Scene, safety: float):
        """``(steps, tick)`` running its substeps from rest:
        :func:`peers.xpbd.release.step_timer`."""
        from .xpbd.release import step_timer

        return step_timer(scene, self._settings, safety)

    def kernel_pass(self, scene: Scene) -> tuple[Callable[[], object], float]:
        """One constraint iteration over every element at a deformed state (its settings,
        undamped): a function to time and the bytes it moves per element
        (:meth:`peers.xpbd.XPBD.projection_pass`)."""
        solver = XPBD(scene, replace(self._settings, damping=0.0))
        x0 = solver.x0
        rng = np.random.default_rng(0)  # a stretch and a little noise
        x = x0 * [1.02, 0.99, 0.995] + 1e-3 * np.ptp(x0) * rng.standard_normal(x0.shape)
        return solver.projection_pass(x)

    def run(self, scene: Scene, frames: int) -> ModelSolution:
        """``frames`` frames of XPBD dynamics from rest under the loads.

        Parameters
        ----------
        scene
            The scene.
        frames
            Frames of ``dt``.

        Returns
        -------
        ModelSolution
            ``status`` "end of run at t = ...".
        """
        solver = self._solver(scene)
        t0 = time.perf_counter()
        x, _ = solver.run(frames)
        u = x - solver.x0
        t = frames * solver.settings.dt
        result = model_result(
            scene, u, model=self.name, element="P1", law="stable-neo-hookean",
            wall_time=time.perf_counter() - t0, converged=False,
            iterations=frames * solver.settings.substeps,
            info={"frames": frames, "settings": dict(self.settings)},
            status=f"end of run at t = {t:.4g} s after {frames} frames",
        )  # fmt: skip
        return ModelSolution(result, np.asarray(u))


def build_mass_spring(
    scene: Scene, calibration: str = "van-gelder", damping: float = 0.0
) -> MassSpring:
    """The network of ``scene`` (what :class:`~springfem.model_api.SystemModel` builds)."""
    return MassSpring(scene, calibration=calibration, damping=damping)


@cache
def models() -> tuple[XPBDModel | SystemModel | RestModel, ...]:
    """The peers (one object each per process).

    Returns
    -------
    tuple
    """
    return (
        XPBDModel(),
        SystemModel(
            "mass-spring", "edge mass-spring network (van Gelder)", build_mass_spring,
            law="mass-spring", applies=mass_spring_why_not,
            calibration="van-gelder", damping=0.0,
        ),
        VBDModel(),
        PDModel(),
        PDNHModel(),
    )  # fmt: skip


__all__ = ["XPBDModel", "build_mass_spring", "models"]
