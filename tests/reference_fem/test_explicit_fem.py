"""Explicit P1 FEM kernel (reference_fem.explicit) against independent references.

- forces are minus the gradient of the (separately coded) energy, by central differences;
- the energy equals springfem.materials.laws.neo_hookean's NeoHookean energy summed with V;
- forces equal the reference assembly's internal force vector (numpy einsum route);
- at small displacement they equal -K u of the linear P1 stiffness (element_stiffness_p1)
  up to a remainder quadratic in u; the linear law equals -K u exactly;
- net force and moment zero, rigid motions give no force, objectivity f(Qx) = Q f(x);
- the parallel kernel equals the serial one;
- inverted elements are reported by id and step;
- dynamic relaxation (springfem.mechanics.explicit_static) reaches reference_fem's Newton
  solution of a neo-Hookean stretch.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from reference_fem import element_stiffness_p1, solve
from reference_fem.assembly import assemble_vector, hyperelastic_element_arrays
from reference_fem.explicit import ExplicitFem
from reference_fem.space import Space, p1_gradients
from springfem.errors import InputError, SolverError
from springfem.materials import isotropic_matrix
from springfem.materials.laws.neo_hookean import NeoHookean
from springfem.mechanics import explicit, explicit_static, stable_time_step
from springfem.mechanics.fd_jacobian import fd_jacobian
from springfem.mechanics.system import MechanicalSystem
from springfem.mesh import box_mesh, element_colouring
from springfem.scene import Material, scene_from_dict

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
def test_forces_are_minus_energy_gradient(scene, law):
    """Central differences of the energy kernel: truncation ~h^2, roundoff ~eps E / h."""
    fem = ExplicitFem(scene, law=law)
    x = state(fem, 0.03)
    f = fem.internal(x).ravel()
    h = 1e-6
    rng = np.random.default_rng(1)
    for dof in rng.choice(x.size, 12, replace=False):
        xp, xm = x.copy(), x.copy()
        xp.ravel()[dof] += h
        xm.ravel()[dof] -= h
        g = (fem.strain_energy(xp) - fem.strain_energy(xm)) / (2 * h)
        assert abs(f[dof] + g) <= 1e-6 * np.abs(f).max(), (dof, f[dof], -g)


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


def test_small_displacement_is_linear_p1(scene, fem):
    """f(x0 + u) = -K u + O(u^2) with K from element_stiffness_p1; the linear law is exact."""
    Ke = element_stiffness_p1(fem.x0, fem.tets, isotropic_matrix(E, NU))
    rng = np.random.default_rng(2)
    d = rng.standard_normal(fem.x0.shape)

    def minus_Ku(u):
        fe = -np.einsum("eab,eb->ea", Ke, u[fem.tets].reshape(-1, 12)).reshape(-1, 4, 3)
        return assemble_vector(fem.tets, fe, fem.n_points).reshape(-1, 3)

    errors = []
    for a in (1e-4, 5e-5):
        u = a * d
        ref = minus_Ku(u)
        errors.append(rel(fem.internal(fem.x0 + u), ref))
    # remainder O(u^2): relative error ~ strain (~1e-3 here) and halves with u
    assert errors[0] < 1e-2
    assert errors[0] / errors[1] == pytest.approx(2.0, rel=0.05)
    lin = ExplicitFem(scene, law="linear")
    u = 1e-2 * d
    assert rel(lin.internal(lin.x0 + u), minus_Ku(u)) < 1e-11  # round-off of positions


def test_net_force_moment_and_rigid_motion(fem):
    """Each element's forces balance (sum f = 0, sum x x f = 0); rigid motion is force-free;
    rotating the deformed state rotates the forces (objectivity)."""
    x = state(fem, 0.02)
    f = fem.internal(x)
    scale = np.abs(f).max()
    assert np.abs(f.sum(axis=0)).max() < 1e-12 * scale * fem.n_points
    assert np.abs(np.cross(x, f).sum(axis=0)).max() < 1e-12 * scale * fem.n_points
    Q = Rotation.from_rotvec([0.3, -1.1, 0.7]).as_matrix()
    t = np.array([0.4, -2.0, 1.5])
    assert np.abs(fem.internal(fem.x0 @ Q.T + t)).max() < 1e-12 * scale
    assert rel(fem.internal(x @ Q.T + t), f @ Q.T) < 1e-12


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


def test_stiffness_is_the_force_jacobian(fem):
    """Analytic tangent (reference_fem assembly) == coloured central differences of the
    kernel's forces (~1e-9 relative)."""
    x = state(fem, 0.03)
    K = fem.stiffness(x).toarray()
    K_fd = fd_jacobian(lambda y: fem.internal(y).copy(), x, fem.tets).toarray()
    assert np.abs(K - K_fd).max() < 1e-6 * np.abs(K).max()


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
