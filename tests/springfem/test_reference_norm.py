"""The static tolerance's reference force on a stiffening system with a prescribed
displacement (``springfem.mechanics.context.reference_norm``).

Reference: two exponential springs in series along x, solved by bracketing root search
(``scipy.optimize.brentq``) of the force balance, independent of the solver under test.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.optimize import brentq

from springfem.errors import SolverError
from springfem.mechanics import static
from springfem.mechanics.context import SolveContext, reference_norm

BETA = 10.0  # force k e exp(BETA e^2) in a spring extended by e
K1, K2 = 1.0, 3.0


def spring_force(k, e):
    return k * e * np.exp(BETA * e * e)


def spring_stiffness(k, e):
    return k * np.exp(BETA * e * e) * (1.0 + 2.0 * BETA * e * e)


class Chain:
    """Node 0 fixed, node 1 free along x (spring K1 to node 0, K2 to node 2), node 2 pulled
    by ``d`` along x, node 3 a fixed bystander (the tet of the solvers' bookkeeping)."""

    x0 = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]])
    masses = np.ones(4)
    fixed_dofs = np.array([0, 1, 2, 4, 5, 6, 7, 8, 9, 10, 11])

    def __init__(self, d: float):
        self.d = d

    def prescribed(self, s):
        p = self.x0.reshape(-1)[self.fixed_dofs].copy()
        p[self.fixed_dofs == 6] += s * self.d  # node 2's x
        return p

    def forces(self, x, v, s=1.0):
        e1, e2 = x[1, 0] - x[0, 0] - 1.0, x[2, 0] - x[1, 0] - 1.0
        f = np.zeros((4, 3))
        f[0, 0], f[1, 0] = spring_force(K1, e1), spring_force(K2, e2) - spring_force(K1, e1)
        f[2, 0] = -spring_force(K2, e2)
        return f

    def energy(self, x, s=1.0):
        return None

    def stiffness(self, x, s=1.0):
        e1, e2 = x[1, 0] - x[0, 0] - 1.0, x[2, 0] - x[1, 0] - 1.0
        a, b = spring_stiffness(K1, e1), spring_stiffness(K2, e2)
        rows = [0, 0, 3, 3, 3, 6, 6]
        cols = [0, 3, 0, 3, 6, 3, 6]
        vals = [a, -a, -a, a + b, -b, -b, b]
        return sp.csr_matrix((vals, (rows, cols)), shape=(12, 12))

    def element_nodes(self):
        return np.array([[0, 1, 2, 3]])

    def post_step(self, x, dt):
        return None


def test_reference_is_the_linearised_load_when_the_rest_state_is_far_stiffer():
    # at rest with node 2 moved by d = 3 the K2 spring carries 3 * 3 e^90 ~ 1e40; its
    # linearisation, K2 d = 9, is the load the solution balances in order of magnitude
    ctx = SolveContext(Chain(3.0))
    assert reference_norm(ctx, 1.0) == pytest.approx(K2 * 3.0, rel=1e-6)


def test_static_solution_is_the_force_balance_not_the_predictor():
    # with the rest-state reference (K2 d e^(BETA d^2) = 1.4e18) the tolerance was 1e8 and
    # Newton accepted the linear predictor (node 1 moved by 3/4 d, residual ~20); the
    # solution balances the two springs
    d = 2.0
    e1 = brentq(lambda e: spring_force(K1, e) - spring_force(K2, d - e), 0.0, d, xtol=1e-14)
    sys = Chain(d)
    info = static(sys, tol=1e-10)
    assert info.x[1, 0] - 1.0 == pytest.approx(e1, rel=1e-8)
    assert abs(e1 - 0.75 * d) > 0.05  # the predictor is far from it


def test_no_finite_scale_is_an_error():
    class Broken(Chain):
        def forces(self, x, v, s=1.0):
            f = super().forces(x, v, s)
            return f if np.allclose(x, self.x0) else f * np.inf

    with pytest.raises(SolverError, match="not finite"):
        reference_norm(SolveContext(Broken(1.0)), 1.0)
