"""Static equilibrium by dynamic relaxation: explicit integration with kinetic or mass
damping until the residual is small.

Examples
--------

>>> import numpy as np
>>> from springfem.mechanics.toy import Oscillator
>>> info = explicit_static(Oscillator(), tol=1e-10)
>>> info.converged, round(float(info.x[3, 0]), 8)  # load / k
(True, 0.25)
"""

from __future__ import annotations

import sys
import time
from typing import Literal

import numpy as np

from springfem.errors import SolverError

from .context import SolveContext, reference_norm
from .explicit import Integrator, explicit_loop
from .results import SolveInfo
from .system import MechanicalSystem, constrained_positions
from .timestep import choose_time_step

Damping = Literal["auto", "kinetic", "mass"]
#: Kinetic-energy growth that marks a blow-up (see :class:`~.blowup.BlowupMonitor`).
BLOWUP_FACTOR = 1e4
#: Seconds between residual lines on stderr with ``progress`` (``springfem solve -v``).
PROGRESS_EVERY = 1.0


def explicit_static(
    system: MechanicalSystem,
    tol: float = 1e-8,
    max_steps: int = 200_000,
    dt: float | None = None,
    integrator: Integrator = "symplectic-euler",
    mass_damping: float = 0.0,
    damping: Damping = "auto",
    scale: float = 1.0,
    check_every: int = 10,
    progress: bool = False,
    *,
    x_init: np.ndarray | None = None,
    dt_safety: float = 0.5,
    raise_on_failure: bool = True,
) -> SolveInfo:
    """Equilibrium by damped explicit integration (dynamic relaxation).

    Runs :func:`explicit` with mass damping ``alpha = mass_damping`` or kinetic damping
    (velocities zeroed at every kinetic-energy peak; the default when ``mass_damping`` is
    0) until ``|f_free(x)| < tol * reference_force``, checked every ``check_every`` steps.

    Parameters
    ----------
    system
        The system.
    tol
        Relative residual tolerance.
    max_steps
        Explicit steps at most.
    dt, integrator, mass_damping, progress, dt_safety
        As in :func:`~springfem.mechanics.explicit.explicit`.
    damping
        ``kinetic``, ``mass`` (needs ``mass_damping > 0``) or ``auto`` (``mass`` when
        ``mass_damping > 0``).
    scale
        Load factor.
    check_every
        Steps between residual checks.
    x_init
        Starting positions (default: the rest positions).
    raise_on_failure
        Raise when ``max_steps`` pass without convergence (else return, ``converged``
        false, with a ``message``).

    Returns
    -------
    SolveInfo
        ``method = "dynamic-relaxation"``; ``iterations`` and ``steps`` count explicit steps.

    Raises
    ------
    SolverError
        On blow-up, or (``raise_on_failure``) when ``max_steps`` pass without convergence.
    """
    t_start = time.perf_counter()
    ctx = SolveContext(system)
    s = float(scale)
    if damping == "auto":
        damping = "mass" if mass_damping > 0 else "kinetic"
    if damping not in ("kinetic", "mass"):
        raise ValueError(f"unknown damping {damping!r}; valid: 'auto', 'kinetic', 'mass'")
    if damping == "mass" and not mass_damping > 0:
        raise ValueError("damping='mass' needs mass_damping > 0")
    dt, dt_crit = choose_time_step(system, dt, dt_safety, s)
    x = constrained_positions(system, s, x_init)
    f_ref = reference_norm(ctx, s)
    r0 = float(np.linalg.norm(ctx.free_force(x, s))) / f_ref
    if r0 <= tol:
        return SolveInfo(
            x=x, converged=True, iterations=0, residual_history=[r0], load_steps=[s],
            method="dynamic-relaxation", jacobian="none", linear_solver="none",
            wall_time=time.perf_counter() - t_start, reference_force=f_ref, dt=dt,
            force_evaluations=ctx.n_evals,
        )  # fmt: skip

    shown = [time.perf_counter()]

    def stop(k: int, t: float, x: np.ndarray) -> tuple[bool, float]:
        r = float(np.linalg.norm(ctx.free_force(x, s))) / f_ref
        if progress and time.perf_counter() - shown[0] >= PROGRESS_EVERY:
            shown[0] = time.perf_counter()
            print(f"relaxation step {k}: relative residual {r:.3e} (tol {tol:.1e})",
                  file=sys.stderr, flush=True)  # fmt: skip
        return r <= tol, r

    v = np.zeros_like(x)
    traj, done = explicit_loop(
        ctx,
        dt=dt,
        n_steps=int(max_steps),
        integrator=integrator,
        alpha=float(mass_damping) if damping == "mass" else 0.0,
        scale=s,
        x=x,
        v=v,
        record_every=max(1, int(max_steps) // 1000),
        callback=None,
        progress=progress,
        kinetic_damping=damping == "kinetic",
        stop_fn=stop,
        check_every=max(1, int(check_every)),
        blowup_factor=BLOWUP_FACTOR,
        dt_crit=dt_crit,
    )
    hist = [r0, *traj.residual_history]
    info = SolveInfo(
        x=traj.x,
        converged=bool(done),
        iterations=traj.steps,
        residual_history=hist,
        load_steps=[s] if done else [],
        method="dynamic-relaxation",
        jacobian="none",
        linear_solver="none",
        wall_time=time.perf_counter() - t_start,
        reference_force=f_ref,
        steps=traj.steps,
        dt=dt,
        force_evaluations=ctx.n_evals,
    )
    if not done:
        info.message = (
            f"dynamic relaxation ({damping} damping) stopped after "
            f"{time.perf_counter() - t_start:.3g} s / {traj.steps} steps at relative residual "
            f"{hist[-1]:.3g} (the cap of {int(max_steps)} steps; tolerance {tol:.3g})"
        )
        if raise_on_failure:
            raise SolverError(info.message, state=traj.x)
    return info
