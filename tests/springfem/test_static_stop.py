"""A static solve that stops part way along its load says where and hands back that state.

Reference: the equilibrium residual of the returned state, evaluated with the system's own
forces at the load factor reported (independent of the solver's bookkeeping), against the
force scale ``|f_ext|`` of the full load.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the shared test systems
from mechanics_systems import beam  # noqa: E402

from springfem.errors import SolverError  # noqa: E402
from springfem.mechanics import static  # noqa: E402

TOL = 1e-4


def _free_force(system, x: np.ndarray, scale: float) -> float:
    f = system.forces(x, None, scale).reshape(-1)
    free = np.setdiff1d(np.arange(f.size), system.fixed_dofs)
    return float(np.linalg.norm(f[free]))


def test_stop_part_way_reports_the_load_reached_and_its_equilibrium():
    """Three Newton iterations per step and no cut-back: the first steps (small increments
    of a mildly nonlinear beam) converge, the last does not. The error names the load
    factor reached, and its state is an equilibrium at that load (residual within the
    tolerance, times 1.0001 for the norm's rounding) but not at the full load."""
    system = beam(load=(0.0, 0.0, -0.15))
    with pytest.raises(SolverError) as e:
        static(system, tol=TOL, max_iter=3, max_cutbacks=0, load_steps=4, fallback=False)
    lf = e.value.load_factor
    assert lf is not None and 0.0 < lf < 1.0
    assert f"stopped at load factor {lf:.4g} of 1 (Newton at " in str(e.value)
    x = np.asarray(e.value.state).reshape(-1, 3)
    f_ref = _free_force(system, system.x0, 1.0)  # dead load on a clamped beam: |f_ext|
    assert _free_force(system, x, lf) <= TOL * f_ref * 1.0001
    assert _free_force(system, x, 1.0) > 10 * TOL * f_ref


def test_a_solve_that_finishes_raises_nothing():
    """The same solve with enough iterations converges (the stop above is the cap's)."""
    system = beam(load=(0.0, 0.0, -0.15))
    info = static(system, tol=TOL, max_iter=20, load_steps=4, fallback=False)
    assert (
        info.converged
        and _free_force(system, info.x, 1.0) <= TOL * _free_force(system, system.x0, 1.0) * 1.0001
    )
