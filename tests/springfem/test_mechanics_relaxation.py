"""Dynamic relaxation reaches the Newton equilibrium."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the shared test systems
from mechanics_systems import (  # noqa: E402
    beam,
    free_block,
)

from springfem.mechanics import (
    explicit_static,
    static,
)


@pytest.mark.parametrize("damping", ["kinetic", "mass"])
def test_explicit_static_reaches_newton_solution(damping):
    sys = beam(divisions=(4, 2, 2), load=(0.0, 0.0, -0.05))
    ref = static(sys, tol=1e-12)
    alpha = 0.0
    if damping == "mass":  # about critical for the lowest mode
        free, Kff = free_block(sys, sys.stiffness(ref.x))
        w = scipy.linalg.eigh(Kff.toarray(), np.diag(np.repeat(sys.masses, 3)[free]),
                              eigvals_only=True)  # fmt: skip
        alpha = 2 * np.sqrt(w[0])
    info = explicit_static(sys, tol=1e-8, damping=damping, mass_damping=alpha)
    assert info.converged and info.steps > 0 and info.residual <= 1e-8
    u_ref = ref.x - sys.x0
    assert np.abs(info.x - ref.x).max() < 1e-5 * np.abs(u_ref).max()


# ------------------------------------------------------------------------------ implicit
