"""Coloured finite-difference Jacobians against analytic tangents (and the test system's
own consistency)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse.linalg as spla

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the shared test systems
from mechanics_systems import (  # noqa: E402
    beam,
    random_displacement,
)

from springfem.mechanics.fd_jacobian import ColoredJacobian, distance2_coloring, fd_jacobian
from springfem.mechanics.system import MechanicalSystem, node_adjacency
from springfem.mesh import box_mesh


def test_test_system_is_consistent():
    """The test system itself: analytic K = -df/dx (central differences) and f = -dE/dx."""
    sys = beam(load=(0, 0, -0.1))
    assert isinstance(sys, MechanicalSystem)
    x = random_displacement(sys, 0.05)
    K = sys.stiffness(x).toarray()
    h = 1e-6
    for dof in (40, 77, 101):
        xp, xm = x.copy(), x.copy()
        xp.reshape(-1)[dof] += h
        xm.reshape(-1)[dof] -= h
        col = -(sys.forces(xp) - sys.forces(xm)).reshape(-1) / (2 * h)
        assert np.allclose(K[:, dof], col, atol=1e-7 * np.abs(K).max())
        dE = (sys.energy(xp) - sys.energy(xm)) / (2 * h)
        assert dE == pytest.approx(-sys.forces(x).reshape(-1)[dof], abs=1e-7)


# ------------------------------------------------------------------------------ colouring


def test_distance2_coloring_separates_nodes_within_two_elements():
    mesh = box_mesh((1.0, 1.0, 1.0), (4, 3, 3), split="six")
    n = mesh.n_points
    colors = distance2_coloring(mesh.tets, n)
    A = node_adjacency(mesh.tets, n).astype(np.int64)
    A2 = (A @ A).toarray() > 0  # distance <= 2 (A has its diagonal)
    i, j = np.nonzero(np.triu(A2, 1))
    assert np.all(colors[i] != colors[j])
    assert colors.max() + 1 < n / 2  # far fewer colours than nodes


def test_fd_jacobian_equals_analytic_stiffness_with_few_evaluations():
    sys = beam(divisions=(8, 3, 3), load=(0, 0, -0.1))
    n = sys.x0.shape[0]
    x = random_displacement(sys, 0.05)  # a deformed, non-trivial state
    K = sys.stiffness(x)
    calls = []

    def f(y):
        calls.append(1)
        return sys.forces(y)

    Kfd = fd_jacobian(f, x, sys.tets)
    cj = ColoredJacobian(sys.tets, n)
    # central differences with h = u^(1/3) L: ~1e-10 relative; 1e-6 is the brief's bound
    assert spla.norm(Kfd - K) / spla.norm(K) < 1e-6
    assert len(calls) == 6 * cj.n_colors == cj.n_evaluations("central")
    assert len(calls) < 0.5 * 3 * n  # central differences over every column would be 6n
    assert Kfd.nnz == 9 * node_adjacency(sys.tets, n).nnz  # pattern: adjacency (x) 3x3
    # forward differences: first order, ~sqrt(u) relative
    calls.clear()
    Kfw = fd_jacobian(f, x, sys.tets, scheme="forward")
    assert spla.norm(Kfw - K) / spla.norm(K) < 1e-5
    assert len(calls) == 3 * cj.n_colors + 1


# ------------------------------------------------------------------------- critical step


def test_spring_model_fd_jacobian_matches_its_hessian(stretch_model):
    m = stretch_model
    x = random_displacement(m, 2e-4)  # mesh size 1.7 mm: ~10 % strains
    K = m.stiffness(x)
    assert K is not None
    cj = ColoredJacobian(m.element_nodes(), m.x0.shape[0])
    Kfd = cj(lambda y: m.forces(y, None), x)
    assert spla.norm(Kfd - K) / spla.norm(K) < 1e-6  # central differences: ~1e-10
    assert cj.n_evaluations() < 0.2 * 3 * m.x0.shape[0]
