"""The measured critical explicit time step of a mechanical system, by bisection.

Examples
--------
>>> from springfem.mechanics.toy import Oscillator
>>> dt_pred, omega, ratio = measure_critical_step(Oscillator(), steps=200, bisections=6)
>>> float(omega), float(dt_pred)   # sqrt(k / m) = 2 and 2 / omega
(2.0, 1.0)
>>> 0.5 < ratio <= 1.0   # never above the linear-stability bound 2 / omega
True
"""

from __future__ import annotations

import numpy as np

from springfem.errors import SolverError


def measure_critical_step(system, steps: int, bisections: int) -> tuple[float, float, float]:
    """Bisect the largest stable explicit step of ``system`` (loads off) in ``[0.5, 2]`` dt_crit.

    A step is stable when ``steps`` central-difference steps from a tiny random velocity do
    not blow up (no :class:`SolverError`). Returns the predicted step ``2 / omega_max``,
    ``omega_max``, and the measured step over the predicted one after ``bisections``
    bisections (``nan``: unstable at 0.5; ``2.0``: stable at the top of the bracket).
    """
    from springfem.mechanics import explicit, stable_time_step

    dt_pred, omega = stable_time_step(system)
    rng = np.random.default_rng(0)
    v0 = 1e-6 * rng.standard_normal(system.x0.shape)
    v0.ravel()[system.fixed_dofs] = 0.0

    def stable(f: float) -> bool:
        try:
            explicit(system, dt=f * dt_pred, steps=steps, v_init=v0, record_every=steps)
            return True
        except SolverError:
            return False

    lo, hi = 0.5, 2.0
    if not stable(lo):
        return dt_pred, omega, float("nan")
    if stable(hi):
        return dt_pred, omega, hi
    for _ in range(bisections):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return dt_pred, omega, lo
