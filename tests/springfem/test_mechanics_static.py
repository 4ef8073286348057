"""Static Newton with load stepping against direct linear solves, quadratic convergence,
finite-difference tangents, cut-backs and the dynamic-relaxation fallback."""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse.linalg as spla

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the shared test systems
from mechanics_systems import (  # noqa: E402
    SCENES,
    beam,
    linear_reference,
    prescribe_tip,
)

from springfem.errors import SolverError
from springfem.mechanics import (
    SolveInfo,
    explicit_static,
    static,
)
from springfem.mechanics.fd_jacobian import fd_jacobian
from springmodel.options import SpringOptions


@pytest.mark.parametrize("linear_solver", ["auto", "amg"])
def test_static_linear_equals_direct_solve(linear_solver):
    sys = beam(load=(0.0, 0.02, -0.05), linear=True)
    u_ref = linear_reference(sys)
    info = static(sys, tol=1e-13, linear_solver=linear_solver)
    u = (info.x - sys.x0).reshape(-1)
    assert isinstance(info, SolveInfo) and info.converged
    # direct: Newton is exact in one step to roundoff; AMG-CG to its rtol 1e-10
    tol = 1e-10 if linear_solver == "auto" else 1e-8
    assert np.linalg.norm(u - u_ref) / np.linalg.norm(u_ref) < tol
    assert info.iterations <= 3  # 1 (exact) + roundoff stagnation; AMG: +1 for its rtol
    assert info.linear_solver == ("direct" if linear_solver == "auto" else "cg+amg")


def test_static_linear_with_prescribed_displacement():
    sys = beam(linear=True)
    prescribe_tip(sys, [0.0, 0.0, -0.1])
    u_ref = linear_reference(sys)
    info = static(sys, tol=1e-13, load_steps=3)
    u = (info.x - sys.x0).reshape(-1)
    assert np.linalg.norm(u - u_ref) / np.linalg.norm(u_ref) < 1e-10
    assert info.load_steps == pytest.approx([1 / 3, 2 / 3, 1.0])


def test_newton_converges_quadratically_on_nonlinear_springs():
    load = (0.0, 0.0, -0.15)
    sys = beam(load=load)
    iterates = []
    info = static(sys, tol=1e-13, callback=lambda it, s, x, r: iterates.append(x.copy()))
    u_lin = linear_reference(beam(load=load, linear=True))
    u = (info.x - sys.x0).reshape(-1)
    assert np.linalg.norm(u - u_lin) > 0.1 * np.linalg.norm(u_lin)  # really nonlinear
    assert info.converged and info.residual <= 2e-13 and info.load_steps == [1.0]
    # quadratic: e_{k+1} <= C e_k^2 with C of order one once e_k is small (a linearly
    # convergent iteration with ratio rho has e_{k+1} / e_k^2 = rho / e_k -> infinity);
    # pairs whose e_{k+1} is at roundoff (< 1e-12, lengths ~ 1) say nothing.
    e = np.array([np.abs(x - info.x).max() for x in iterates])
    pairs = [(a, b) for a, b in zip(e[:-1], e[1:]) if a < 1e-2 and b > 1e-12]
    assert len(pairs) >= 2, e
    assert all(b <= 100 * a * a for a, b in pairs), e
    # equilibrium checked independently: the net force on the free DOFs vanishes
    f = sys.forces(info.x).reshape(-1)
    free = np.setdiff1d(np.arange(f.size), sys.fixed_dofs)
    assert np.linalg.norm(f[free]) <= 2e-13 * info.reference_force


def test_static_with_fd_jacobian_matches_analytic():
    sys = beam(load=(0.0, 0.0, -0.15))
    ref = static(sys, tol=1e-12)
    sys.analytic = False
    info = static(sys, tol=1e-12)
    assert info.converged and info.jacobian == "fd" and ref.jacobian == "analytic"
    assert np.abs(info.x - ref.x).max() < 1e-9
    assert info.iterations <= ref.iterations + 2  # FD tangent accurate to ~1e-10


@pytest.mark.parametrize("linear_solver", ["direct", "amg"])
def test_static_non_gradient_forces_converge(linear_solver):
    """A circulatory load: no energy, non-symmetric FD Jacobian, spsolve or GMRES."""
    sys = beam(load=(0.0, 0.0, -0.1), circulation=1e-3)  # ~1/5 of K's smallest eigenvalue
    info = static(sys, tol=1e-10, linear_solver=linear_solver)
    assert info.converged and info.jacobian == "fd"
    assert info.linear_solver == ("direct" if linear_solver == "direct" else "gmres+amg")
    f = sys.forces(info.x).reshape(-1)
    free = np.setdiff1d(np.arange(f.size), sys.fixed_dofs)
    assert np.linalg.norm(f[free]) <= 1e-10 * info.reference_force * 1.0001
    K = fd_jacobian(lambda y: sys.forces(y), info.x, sys.tets)
    assert spla.norm(K - K.T) > 1e-5 * spla.norm(K)  # non-symmetric (FD noise is ~1e-10)


def test_static_cuts_back_and_falls_back_to_dynamic_relaxation():
    sys = beam(load=(0.0, 0.0, -0.15))
    ref = static(sys, tol=1e-10)
    cut = static(sys, tol=1e-10, max_iter=3)
    assert cut.converged and cut.cutbacks > 0 and len(cut.load_steps) > 1
    assert np.abs(cut.x - ref.x).max() < 1e-8
    dr = static(sys, tol=1e-7, max_iter=1, max_cutbacks=1)
    assert dr.converged and dr.method == "newton+dynamic-relaxation" and dr.steps > 0
    assert np.abs(dr.x - ref.x).max() < 1e-4 * np.abs(ref.x - sys.x0).max()
    with pytest.raises(SolverError, match="static solve did not converge") as e:
        static(sys, tol=1e-10, max_iter=1, max_cutbacks=1, fallback=False)
    assert e.value.state.shape == sys.x0.shape


@pytest.mark.parametrize("fixed", [np.array([], dtype=int), np.array([0, 1, 2])])
def test_singular_system_raises(fixed):
    sys = beam(load=(0.0, 0.0, -0.1))
    sys.fixed_dofs = fixed
    sys.u_presc = np.zeros(fixed.size)
    with pytest.raises(
        SolverError,
        match="singular stiffness: the scene has no boundary condition that stops rigid motion",
    ):
        static(sys)


def test_spring_model_static_fd_and_dynamic_relaxation_agree(stretch_model):
    m = stretch_model
    ref = static(m, tol=1e-11)
    fd = static(m, tol=1e-11, jacobian="fd")
    assert ref.jacobian == "analytic" and fd.jacobian == "fd"
    u = ref.x - m.x0
    assert np.abs(fd.x - ref.x).max() < 1e-8 * np.abs(u).max()
    dr = explicit_static(m, tol=1e-8)
    assert dr.converged and np.abs(dr.x - ref.x).max() < 1e-5 * np.abs(u).max()


def test_spring_model_non_gradient_torsion_newton_on_the_cantilever():
    """Cosine torsion (eq. 2.44-2.45): no energy, non-symmetric FD tangent. The slender
    cantilever's first Newton step raises the residual norm tenfold; the natural
    monotonicity test accepts it and Newton converges in a few iterations."""
    from springfem.scene import load_scene
    from springmodel.model import SpringModel

    scene = load_scene(SCENES / "cantilever.toml")
    m = SpringModel(scene, replace(SpringOptions.of(scene), torsion="cosine"), parallel=False)
    assert m.energy(m.x0) is None
    info = static(m, tol=1e-8)  # this scene's roundoff floor is ~3e-9 of its tiny load
    assert info.converged and info.jacobian == "fd" and info.iterations <= 6
    assert max(info.residual_history) > 2.0  # the residual norm did grow on the way
    f = m.forces(info.x, None).reshape(-1)
    free = np.setdiff1d(np.arange(f.size), m.fixed_dofs)
    assert np.linalg.norm(f[free]) <= 1e-8 * info.reference_force
    K = fd_jacobian(lambda y: m.forces(y, None), info.x, m.element_nodes())
    assert spla.norm(K - K.T) > 1e-6 * spla.norm(K)  # FD noise alone is ~1e-10
