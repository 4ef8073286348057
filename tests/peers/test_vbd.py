"""Vertex Block Descent against independent references: finite differences of the energy for
its per-vertex gradient and Hessian block, the definition of a vertex colouring, the Newton
answer of the same stable neo-Hookean energy (peers.xpbd.StableNeoHookean with the core's
Newton) on a jittered large-rotation cantilever, and linear P1 FEM of reference_fem for the
linear law."""

from __future__ import annotations

import tomllib
from importlib import resources

import numpy as np
import pytest

from peers.vbd import VBD, VBDSettings
from peers.vbd.colouring import vertex_colouring
from peers.vbd.energy import LAW_CODES, density, vertex_block
from peers.vbd.kernels import vertex_terms
from peers.xpbd import StableNeoHookean
from peers.xpbd.constraints import deformation_gradients
from springfem.errors import InputError
from springfem.mechanics import static
from springfem.model_api import plugin_models
from springfem.scene import scene_from_dict


def _cantilever(law="neo-hookean", divisions=(12, 2, 2)):
    """The bundled large-rotation cantilever (tip a quarter of its length down) on a
    jittered Delaunay mesh of the same box."""
    text = resources.files("studies.scenes").joinpath("cantilever-large-rotation.toml")
    table = tomllib.loads(text.read_text())
    table["mesh"] = {**table["mesh"], "split": "delaunay", "divisions": list(divisions)}
    table["material"] = {**table["material"], "law": law}
    if law == "linear":
        del table["material"]["formulation"]
    return scene_from_dict(table)


@pytest.fixture(scope="module")
def scene():
    return _cantilever()


def _energy(solver, x):
    F = deformation_gradients(x, solver.tets, solver.G)
    return float(np.sum(solver.V * density(F, solver.mu, solver.lam, solver.gamma, solver.law)))


def _terms(solver, x, xt, q, kd_h=0.0):
    c = solver.colouring
    f, H = np.zeros(3), np.zeros((3, 3))
    vertex_terms(q, x, xt, solver.tets, solver.G, solver.V, c.inc_ptr, c.inc_elem, c.inc_local,
                 LAW_CODES[solver.law], solver.mu, solver.lam, solver.gamma, kd_h, f, H,
                 np.empty((4, 3, 3)))  # fmt: skip
    return f, H


@pytest.mark.parametrize("law", ["neo-hookean", "linear"])
def test_vertex_gradient_and_hessian_are_finite_differences(law):
    """The kernel's f_i = -dE/dx_i (central differences of the numpy energy) and its block
    H_i = -df_i/dx_i (central differences of the kernel's own f), at a random strained state
    for a few vertices; the stiffness-proportional damping adds -kd/h H_i (x_i - x_i^t) and
    scales H_i by 1 + kd/h."""
    solver = VBD(_cantilever(law, (4, 2, 2)), VBDSettings(damping=0.0))
    rng = np.random.default_rng(0)
    x = solver.x0 + 0.004 * rng.standard_normal(solver.x0.shape)
    order = solver.colouring.order
    h = 1e-7
    for q in rng.choice(order.size, 5, replace=False):
        i = order[q]
        f, H = _terms(solver, x, x, q)
        fd_f, fd_H = np.zeros(3), np.zeros((3, 3))
        for r in range(3):
            xp, xm = x.copy(), x.copy()
            xp[i, r] += h
            xm[i, r] -= h
            fd_f[r] = -(_energy(solver, xp) - _energy(solver, xm)) / (2 * h)
            fd_H[:, r] = -(_terms(solver, xp, xp, q)[0] - _terms(solver, xm, xm, q)[0]) / (2 * h)
        np.testing.assert_allclose(f, fd_f, rtol=1e-5, atol=1e-6 * np.abs(f).max())
        np.testing.assert_allclose(H, fd_H, rtol=1e-5, atol=1e-6 * np.abs(H).max())
        delta = 1e-4 * rng.standard_normal(3)
        xt = x.copy()
        xt[i] -= delta
        fk, Hk = _terms(solver, x, xt, q, kd_h=3.0)
        np.testing.assert_allclose(fk, f - 3.0 * H @ delta, rtol=1e-12, atol=1e-12 * abs(f).max())
        np.testing.assert_allclose(Hk, 4.0 * H, rtol=1e-12)


def test_vertex_blocks_are_positive_definite_even_for_inverted_elements():
    """The stable neo-Hookean block (mu'|g|^2 I + lam' c c^T) at random F, half of them
    inverted, against numpy's eigenvalues; and against the full element Hessian of the
    numpy energy by finite differences of first_piola (the d cof F term drops out)."""
    from peers.vbd.energy import first_piola

    rng = np.random.default_rng(1)
    for k in range(20):
        F = np.eye(3) + 0.8 * rng.standard_normal((3, 3))
        if k % 2:
            F[:, 0] *= -np.sign(np.linalg.det(F))
        g = rng.standard_normal(3)
        H = vertex_block(F, g, 1.0, 5.0, 1.2, "stable-neo-hookean")
        assert np.linalg.eigvalsh(H).min() > 0
        fd = np.zeros((3, 3))
        for s in range(3):  # d/dx_s of P g with F(x) = ... + x (x) g
            dF = np.outer(np.eye(3)[s], g) * 1e-7
            dP = first_piola(F + dF, 1.0, 5.0, 1.2, "stable-neo-hookean") - first_piola(
                F - dF, 1.0, 5.0, 1.2, "stable-neo-hookean"
            )
            fd[:, s] = dP @ g / 2e-7
        np.testing.assert_allclose(H, fd, rtol=1e-6, atol=1e-6 * np.abs(H).max())


def test_vertex_colouring_separates_neighbours_and_keeps_every_incidence(scene):
    tets = scene.mesh.tets
    c = vertex_colouring(tets, scene.mesh.n_points)
    colour = np.empty(scene.mesh.n_points, dtype=int)
    for k in range(c.n_colours):
        colour[c.order[c.colour_ptr[k] : c.colour_ptr[k + 1]]] = k
    cols = colour[tets]
    assert all(np.unique(row).size == 4 for row in cols)  # no element has a colour twice
    assert sorted(c.order.tolist()) == list(range(scene.mesh.n_points))
    for q, i in enumerate(c.order):
        span = slice(c.inc_ptr[q], c.inc_ptr[q + 1])
        assert (tets[c.inc_elem[span], c.inc_local[span]] == i).all()
        assert c.inc_ptr[q + 1] - c.inc_ptr[q] == np.count_nonzero(tets == i)


@pytest.fixture(scope="module")
def newton(scene):
    s = StableNeoHookean(scene)
    info = static(s, tol=1e-11)
    assert info.converged
    return info.x - s.x0


def _error(u, ref):
    return np.abs(u - ref).max() / np.abs(ref).max()


def test_rest_state_at_default_settings_is_the_newton_answer(scene, newton):
    """Default settings (40 substeps x 2 iterations of 60 Hz frames, adaptive guess, auto
    damping, rest at 1e-6): the rest state equals the Newton answer of the same energy to
    0.05 % of the tip displacement (a rest state of VBD is an equilibrium whatever its
    iterations; what remains is the rest tolerance). The tip moves by a quarter of
    the length: large rotation."""
    assert np.abs(newton).max() > 0.25 * 0.1
    out = VBD(scene).solve()
    assert out.converged and out.residual < 1e-4
    assert _error(out.u, newton) < 5e-4, _error(out.u, newton)


def test_linear_law_rest_state_is_linear_p1_fem():
    """A linear scene: VBD solves linear elasticity on the mesh, reference_fem's P1 on the
    same mesh is the independent answer (0.05 %)."""
    from studies import models

    scene = _cantilever("linear", (8, 2, 2))
    ref = models.run(scene, "P1").u
    out = VBD(scene).solve()
    assert out.converged and _error(out.u, ref) < 5e-4, _error(out.u, ref)


def test_plug_in_is_registered_with_its_sweep_and_refuses_other_laws(scene):
    vbd = plugin_models()["vbd"]
    assert vbd.default and vbd.system(scene) is None and vbd.applies(scene) is None
    assert {"substeps": 40, "iterations": 2} in vbd.sweep  # type: ignore[attr-defined]
    assert vbd.with_settings(iterations=4).settings["iterations"] == 4  # type: ignore[attr-defined]
    transverse = {"law": "transverse-linear", "E_fiber": 3e4, "E_cross": 1e4,
                  "nu_fiber_cross": 0.3, "nu_cross": 0.4, "G_fiber": 5e3}  # fmt: skip
    box = {"generator": "box", "size": [1, 1, 1], "divisions": [1, 1, 1]}
    other = scene_from_dict({"mesh": box, "material": transverse})
    assert vbd.applies(other).startswith("model vbd: no transverse-linear law")
    with pytest.raises(InputError, match="init 'zero' is not one of"):
        VBDSettings(init="zero")  # type: ignore[arg-type]


def test_release_run_swings_back_and_keeps_its_energy_bounded():
    """Released from rest (loads off), VBD's own undamped substeps: the tip swings up from
    its sagged state, and implicit Euler only loses energy (never gains, within 1e-9)."""
    scene = _cantilever(divisions=(6, 2, 2))
    vbd = plugin_models()["vbd"].with_settings(substeps=10)  # type: ignore[attr-defined]
    tip = int(np.argmax(scene.mesh.points[:, 0] + scene.mesh.points[:, 2]))
    out = vbd.release_run(scene, t_end=0.2, safety=0.5, samples=10,
                          probe=(np.array([tip]), np.array([1.0])))  # fmt: skip
    assert out["status"] == "ok" and out["steps"] in (120, 121)  # 0.2 s of 1/600 s
    assert out["u_steps"][-1, 2] > out["u_steps"][0, 2]  # moving up, back towards rest
    E = np.array(out["energy"])
    assert np.all(np.diff(E) <= 1e-9 * E[0]) and E[-1] < E[0]
    go = vbd.step_timer(scene, 0.5)
    ticks = []
    go(3, lambda: ticks.append(1))
    assert len(ticks) == 3
