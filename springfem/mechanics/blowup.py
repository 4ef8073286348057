"""Detecting and reporting a blown-up time integration.

:class:`BlowupMonitor` tells exponential (unstable) growth of the kinetic energy from
physical growth; :func:`blowup_error` builds the :class:`~springfem.errors.SolverError`
that names the step, time, node and element.

Examples
--------
A non-finite kinetic energy is a blow-up; a quiet step is not:

>>> import numpy as np
>>> from springfem.mechanics.context import SolveContext
>>> from springfem.mechanics.toy import Oscillator
>>> ctx = SolveContext(Oscillator())
>>> monitor = BlowupMonitor(ctx, n_steps=10, dt=0.1, factor=1e4, ke0=1.0)
>>> x, v = ctx.x0.copy(), np.zeros_like(ctx.x0)
>>> monitor.check(1, 1.0, x, v, 1.0) is None
True
>>> monitor.check(2, float("nan"), x, v, 1.0)
'non-finite velocity'
"""

from __future__ import annotations

import numpy as np

from springfem.errors import SolverError

from .context import SolveContext
from .fd_jacobian import characteristic_length
from .timestep import stable_time_step


def blowup_error(
    ctx: SolveContext,
    kind: str,
    k: int,
    t: float,
    reason: str,
    x_prev: np.ndarray,
    x: np.ndarray,
    dt: float,
    dt_crit: float | None,
    state: np.ndarray,
) -> SolverError:
    """The error of a failed time integration: what, when, where, and ``dt`` vs ``dt_crit``.

    Parameters
    ----------
    ctx
        The solve context.
    kind
        ``explicit`` or ``implicit``.
    k, t
        Step and time of the failure.
    reason
        What failed.
    x_prev, x
        Positions before and at the failed step (to locate it).
    dt, dt_crit
        Time step and critical time step (``None``: computed at rest here).
    state
        The last good positions, kept on the error.

    Returns
    -------
    SolverError
        To be raised by the caller.
    """
    where = ctx.locate(x_prev, x)
    if dt_crit is None:
        try:
            dt_crit = stable_time_step(ctx.system)[0]
        except Exception:  # noqa: BLE001 - the report must not fail while reporting
            dt_crit = None
    crit = (
        f" (critical dt {dt_crit:.3g} s at rest: dt / dt_crit = {dt / dt_crit:.3g})"
        if dt_crit and np.isfinite(dt_crit)
        else ""
    )
    msg = f"{kind} integration blew up at step {k} (t = {t:.3g} s): {reason}; {where}; "
    msg += f"dt = {dt:.3g} s{crit}"
    return SolverError(msg, state=state)


class BlowupMonitor:
    """Detects an explicit blow-up from the kinetic energy history.

    A step is a blow-up when the velocity is not finite, or when both

    1. the kinetic energy exceeds ``factor`` times its largest value in the first half of
       the current window (a stable run grows polynomially, by ``~2^p`` over such a window;
       an unstable one exponentially), and
    2. the velocity field oscillates on the unstable time scale: its Rayleigh quotient
       ``omega_eff^2 = v.K v / v.M v`` (one central difference of the forces along ``v``)
       gives ``omega_eff dt >= 1.5``. Linear explicit integration is unstable only for
       modes with ``omega dt > 2`` and ``omega_eff <= omega_max``, so a stable step
       (``dt <~ 0.75 dt_crit``) never passes this test.

    Growth that fails the second test is physical (e.g. a load switched on after a quiet
    start): the window restarts at that step.

    Parameters
    ----------
    ctx
        The solve context.
    n_steps
        Steps of the run (the kinetic-energy history is preallocated).
    dt
        Time step.
    factor
        Growth factor of condition 1 (``blowup_factor`` of :func:`explicit`).
    ke0
        Initial kinetic energy.
    """

    def __init__(self, ctx: SolveContext, n_steps: int, dt: float, factor: float, ke0: float):
        self.ctx = ctx
        self.dt = dt
        self.factor = factor
        self.ke = np.empty(n_steps + 1)
        self.ke[0] = ke0
        self.start = 0  # window start
        self.ref_idx = 0
        self.ref = ke0
        self._length: float | None = None

    def check(self, k: int, ke: float, x: np.ndarray, v: np.ndarray, s: float) -> str | None:
        """Record step ``k``'s kinetic energy; the reason if it is a blow-up, else ``None``."""
        self.ke[k] = ke
        if not np.isfinite(ke):
            return "non-finite velocity"
        j = self.start + (k - self.start) // 2
        while self.ref_idx < j:
            self.ref_idx += 1
            self.ref = max(self.ref, self.ke[self.ref_idx])
        if not (self.ref > 0 and ke > self.factor * self.ref):
            return None
        w_dt = self.omega_dt(x, v, s)
        if w_dt >= 1.5:
            return (
                f"kinetic energy grew by a factor {ke / self.ref:.3g} between steps {j} and {k} "
                f"while the velocity oscillates at omega dt = {w_dt:.3g} (unstable above 2)"
            )
        self.start, self.ref_idx, self.ref = k, k, ke  # physical growth: new window
        return None

    def omega_dt(self, x: np.ndarray, v: np.ndarray, s: float) -> float:
        """``dt sqrt(v.K v / v.M v)`` on the free DOFs (K by a central difference)."""
        ctx = self.ctx
        w = np.zeros(3 * ctx.n)
        w[ctx.free] = v.reshape(-1)[ctx.free]
        wmax = np.abs(w).max()
        if not wmax > 0:
            return 0.0
        w = (w / wmax).reshape(-1, 3)
        if self._length is None:
            self._length = characteristic_length(ctx.x0, ctx.tets)
        h = 1e-6 * self._length
        df = ctx.forces(x + h * w, None, s) - ctx.forces(x - h * w, None, s)
        wKw = -float(np.sum(w * df)) / (2 * h)
        wMw = float(np.einsum("i,ij,ij->", ctx.m, w, w))
        return self.dt * float(np.sqrt(max(wKw, 0.0) / wMw))
