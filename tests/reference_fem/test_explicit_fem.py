"""Explicit P1 FEM kernel (reference_fem.explicit) against independent references.

- the conformance check (springfem.testing.check_model): rigid motion gives no force and
  f(Qx) = Q f(x), forces and tangent are central differences of the energy and the forces,
  the tangent at rest is the core's linear P1, velocity Verlet conserves the energy;
- the energy equals springfem.materials.laws.neo_hookean's NeoHookean energy summed with V;
- forces equal the reference assembly's internal force vector (numpy einsum route);
- net force and moment zero;
- the parallel kernel equals the serial one;
- inverted elements are reported by id and step;
- dynamic relaxation (springfem.mechanics.explicit_static) reaches reference_fem's Newton
  solution of a neo-Hookean stretch.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from reference_fem import solve
from reference_fem.assembly import assemble_vector, hyperelastic_element_arrays
from reference_fem.explicit import ExplicitFem
from reference_fem.space import Space, p1_gradients
from springfem.errors import InputError, SolverError
from springfem.materials.laws.neo_hookean import NeoHookean
from springfem.mechanics import explicit, explicit_static, stable_time_step
from springfem.mechanics.system import MechanicalSystem
from springfem.mesh import box_mesh, element_colouring
from springfem.model_api import SystemModel
from springfem.scene import Material, scene_from_dict
from springfem.testing import check_model

E, NU = 1.0e3, 0.3


def rel(a, b):
    return float(np.abs(np.asarray(a) - np.asarray(b)).max() / np.abs(np.asarray(b)).max())


@pytest.fixture(scope="module")
def scene():
    """A perturbed five-tet box (irregular tets), clamped at x_min, pulled at x_max."""
    mesh = box_mesh((1.0, 0.8, 0.6), (3, 3, 2), split="five")
    rng = np.random.default_rng(3)
    inner = np.all((mesh.points > 1e-9) & (mesh.points < np.array([1.0, 0.8, 0.6]) - 1e-9), 1)
    points = mesh.points + 0.05 * rng.standard_normal(mesh.points.shape) * inner[:, None]
    mesh = replace(mesh, points=points)
    return scene_from_dict(
        {
            "mesh": mesh,
            "material": {"law": "neo-hookean", "E": E, "nu": NU},
            "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
            "load": [{"type": "traction", "value": [0.0, 0.0, -5.0], "region": "x_max"}],
        }
    )


@pytest.fixture(scope="module")
def fem(scene):
    return ExplicitFem(scene, parallel=True)


def state(fem, amplitude, seed=0):
    rng = np.random.default_rng(seed)
    return fem.x0 + amplitude * rng.standard_normal(fem.x0.shape)


def test_is_a_mechanical_system(fem):
    assert isinstance(fem, MechanicalSystem)
    assert fem.masses.sum() == pytest.approx(1000.0 * fem.V0.sum(), rel=1e-12)


@pytest.mark.parametrize("law", ["neo-hookean", "linear"])
def test_conformance(scene, law):
    """Rigid motion gives no force and f(Qx) = Q f(x), forces and tangent are central
    differences of the energy and the forces, the tangent at rest is the core's linear P1,
    velocity Verlet conserves the energy (springfem.testing.check_model)."""
    model = SystemModel(f"explicit-{law}", law, lambda s: ExplicitFem(s, law=law))
    check_model(model, scene, small_strain="exact")


def test_energy_matches_reference_law(scene, fem):
    """The numba energy equals NeoHookean.energy (numpy) integrated over the elements."""
    x = state(fem, 0.03)
    G, V = p1_gradients(fem.x0, fem.tets)
    F = np.einsum("eai,eaj->eij", x[fem.tets], G)
    ref = float(V @ NeoHookean(fem.mu, fem.lam).energy(F))
    assert fem.strain_energy(x) == pytest.approx(ref, rel=1e-12)
    assert fem.energy(x) == pytest.approx(ref - np.sum(fem.external(x) * (x - fem.x0)), rel=1e-12)


def test_forces_match_reference_assembly(scene, fem):
    """Same forces as reference_fem's vectorised hyperelastic assembly (to round-off)."""
    x = state(fem, 0.02)
    space = Space(scene.mesh, 1)
    fe, _ = hyperelastic_element_arrays(space, NeoHookean(fem.mu, fem.lam), x - fem.x0, False)
    ref = -assemble_vector(space.element_nodes, fe, space.n_nodes).reshape(-1, 3)
    assert rel(fem.internal(x), ref) < 1e-12


def test_net_force_and_moment(fem):
    """Each element's forces balance (sum f = 0, sum x x f = 0)."""
    x = state(fem, 0.02)
    f = fem.internal(x)
    scale = np.abs(f).max()
    assert np.abs(f.sum(axis=0)).max() < 1e-12 * scale * fem.n_points
    assert np.abs(np.cross(x, f).sum(axis=0)).max() < 1e-12 * scale * fem.n_points


# the parallel driver is law-independent (springfem.blocks): neo-Hookean by default, linear
# (another compiled variant, seconds on a cold numba cache) with -m slow
@pytest.mark.parametrize("law", ["neo-hookean", pytest.param("linear", marks=pytest.mark.slow)])
def test_parallel_equals_serial(scene, law):
    """Per-thread buffers == serial pass to round-off (different summation order at nodes
    shared by the chunks), and bit-identical from call to call."""
    serial = ExplicitFem(scene, law=law, parallel=False)
    x = state(serial, 0.02)
    ref = serial.internal(x).copy()
    par = ExplicitFem(scene, law=law, parallel=True)
    assert par.parallel, "needs two numba threads"
    first = par.internal(x).copy()
    assert rel(first, ref) < 1e-12
    np.testing.assert_array_equal(par.internal(x), first)


def test_colouring_separates_elements(scene):
    tets = scene.mesh.tets
    colour = element_colouring(tets, scene.mesh.n_points)
    for c in np.unique(colour):
        nodes = tets[colour == c].ravel()
        assert np.unique(nodes).size == nodes.size


def test_inverted_element_is_reported(scene):
    fem = ExplicitFem(scene)
    x = fem.x0.copy()
    k = 7
    a, b, c, d = fem.tets[k]
    # push vertex a through the opposite face (b, c, d): that element's J becomes negative
    centre = x[[b, c, d]].mean(axis=0)
    x[a] = centre + 0.5 * (centre - x[a])
    bad = fem.inverted_elements(x)
    assert k in bad
    _, count = fem.kernel(x)
    assert count == bad.size
    with pytest.raises(SolverError, match=rf"inverted element {bad[0]} .*at step 1"):
        fem.internal(x)
    nan_fem = ExplicitFem(scene, on_inverted="nan")
    f = nan_fem.internal(x)
    assert np.isnan(f[a]).all() and nan_fem.last_inverted == bad.size
    assert fem.energy(x) == np.inf
    # the linear law is defined for any F: it counts but does not fail
    lin = ExplicitFem(scene, law="linear")
    assert np.isfinite(lin.internal(x)).all() and lin.last_inverted == bad.size


def test_inverted_during_explicit_run_names_step(scene):
    """A node thrown through its neighbours: the run stops with the element and the step."""
    fem = ExplicitFem(scene)
    dt = 0.5 * stable_time_step(fem)[0]
    v0 = np.zeros_like(fem.x0)
    free_node = int(np.argmax(fem.x0[:, 0]))
    v0[free_node] = [-3.0 / dt, 0.0, 0.0]  # crosses an element within one step
    with pytest.raises(SolverError, match=r"inverted element \d+ .*at step 1 "):
        explicit(fem, dt=dt, steps=5, v_init=v0, record_every=5)


def test_bad_law_and_material():
    mesh = box_mesh((1.0, 1.0, 1.0), (1, 1, 1))
    sc = scene_from_dict(
        {
            "mesh": mesh,
            "material": {"law": "linear", "E": E, "nu": NU},
            "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
        }
    )
    with pytest.raises(InputError, match="not one of"):
        ExplicitFem(sc, law="mooney")
    unc = replace(sc, material=Material("neo-hookean", E=E, nu=NU, formulation="uncoupled"))
    with pytest.raises(InputError, match="coupled"):
        ExplicitFem(unc)


STRETCH = {
    "name": "stretch-neo",
    "mesh": {"generator": "box", "size": [1.0, 1.0, 1.0], "divisions": [2, 2, 2], "split": "six"},
    "material": {"law": "neo-hookean", "E": 1000.0, "nu": 0.3, "density": 1000.0},
    "boundary": [
        {"region": "x_min", "fix": ["x"]},
        {"region": {"point": [0.0, 0.0, 0.0]}, "fix": ["y", "z"]},
        {"region": {"point": [0.0, 1.0, 0.0]}, "fix": ["z"]},
    ],
    "load": [{"type": "traction", "region": "x_max", "value": [250.0, 0.0, 0.0]}],
    "probe": [{"name": "corner", "point": [1.0, 1.0, 1.0]}],
}


def test_dynamic_relaxation_reaches_newton_solution():
    """Explicit damped run to rest == reference_fem P1 coupled neo-Hookean Newton solution.

    A 25 % stretch (clearly nonlinear). explicit_static stops at a relative residual of
    1e-10; the displacement then differs from Newton's (tol 1e-10) by ~1e-10 relative, so
    1e-7 leaves room while still failing for any different energy or load.
    """
    scene = scene_from_dict(STRETCH)
    fem = ExplicitFem(scene)
    info = explicit_static(fem, tol=1e-10, max_steps=50_000)
    assert info.converged
    u = info.x - fem.x0
    ref = solve(scene, order=1, law="neo-hookean/coupled").u_vertices
    assert np.abs(u).max() > 0.2  # really nonlinear
    assert rel(u, ref) < 1e-7
