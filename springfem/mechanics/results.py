"""What the solvers return: a :class:`Trajectory` (time integration) or a
:class:`SolveInfo` (static equilibrium).

Examples
--------
>>> import numpy as np
>>> info = SolveInfo(x=np.zeros((1, 3)), converged=True, iterations=2,
...                  residual_history=[1.0, 1e-3, 1e-9], load_steps=[1.0], method="newton",
...                  jacobian="analytic", linear_solver="direct", wall_time=0.0,
...                  reference_force=1.0)
>>> info.residual
1e-09
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Trajectory:
    """A time integration: recorded energies, final state and cost.

    Attributes
    ----------
    times, kinetic, potential
        Recorded every ``record_every`` steps (and at the end). ``potential`` is NaN when
        the system has no energy (non-gradient forces). Symplectic Euler is leapfrog with
        the stored velocity half a step behind the positions; its kinetic energy is recorded
        with the synchronised velocity ``v + dt/2 M^-1 f`` (as velocity Verlet's), so the
        recorded total energy of both integrators oscillates by ``O((omega dt)^2)`` without
        drifting.
    x, v
        Final positions and velocities ``(n, 3)``.
    steps, dt, dt_crit
        Steps taken, time step, critical time step (``None`` when not computed).
    converged
        ``True`` when the run completed (or, for equilibrium runs, reached the tolerance).
    iterations
        Total Newton iterations (implicit), 0 for explicit runs.
    residual_history
        Implicit: final relative Newton residual of every step. Equilibrium runs: relative
        static residual at every check.
    """

    times: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    x: np.ndarray
    v: np.ndarray
    steps: int
    dt: float
    dt_crit: float | None
    integrator: str
    converged: bool = True
    wall_time: float = 0.0
    iterations: int = 0
    residual_history: list[float] = field(default_factory=list)
    force_evaluations: int = 0
    message: str = ""

    @property
    def energies(self) -> np.ndarray:
        """``(r, 2)``: kinetic and potential energy at the recorded times."""
        return np.column_stack([self.kinetic, self.potential])

    @property
    def total_energy(self) -> np.ndarray:
        """Kinetic plus potential energy at the recorded times."""
        return self.kinetic + self.potential


@dataclass
class SolveInfo:
    """A static (equilibrium) solve.

    Attributes
    ----------
    x
        Equilibrium positions ``(n, 3)``.
    converged
        Relative residual reached ``tol``.
    iterations
        Newton iterations summed over load steps (explicit steps for dynamic relaxation).
    residual_history
        ``|f_free| / reference_force`` after every iteration (or check).
    load_steps
        The converged load factors, in order.
    method
        ``newton``, ``dynamic-relaxation`` or ``newton+dynamic-relaxation``.
    jacobian
        ``analytic``, ``fd`` (coloured finite differences) or ``none``.
    linear_solver
        Linear solvers used (``direct``, ``cg+amg``, ``gmres+amg``), comma separated.
    reference_force
        ``|f_free|`` at the rest positions with prescribed DOFs: the load being balanced.
    cutbacks
        Load-step cut-backs after a failed Newton solve.
    """

    x: np.ndarray
    converged: bool
    iterations: int
    residual_history: list[float]
    load_steps: list[float]
    method: str
    jacobian: str
    linear_solver: str
    wall_time: float
    reference_force: float
    cutbacks: int = 0
    steps: int = 0
    dt: float | None = None
    force_evaluations: int = 0
    message: str = ""

    @property
    def residual(self) -> float:
        """Final relative residual."""
        return self.residual_history[-1] if self.residual_history else float("nan")
