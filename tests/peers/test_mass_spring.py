"""The edge mass–spring network against independent references: the conformance check
(finite differences of its energy and forces, rigid motions, the explicit energy), the
Cauchy–Born moduli of a periodic lattice and the Cauchy relations every central-force
network obeys (Born & Huang 1954), on a gmsh mesh and on a box lattice; a static Newton
solve and an explicit run on the core's solvers."""

from __future__ import annotations

import numpy as np
import pytest
from support.meshes import gmsh_box

from peers.mass_spring import MassSpring
from springfem.errors import InputError
from springfem.mechanics import explicit, stable_time_step, static
from springfem.model_api import SystemModel
from springfem.scene import scene_from_dict
from springfem.testing import check_model

MATERIAL = {"law": "linear", "E": 1.0e4, "nu": 0.3, "density": 1000.0}


def _scene(mesh, load=True):
    table = {"mesh": mesh, "material": MATERIAL,
             "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}]}  # fmt: skip
    if load:
        table["load"] = [{"type": "traction", "region": "x_max", "value": [0.0, 0.0, -10.0]}]
    return scene_from_dict(table)


@pytest.fixture(scope="module")
def gmsh_scene(tmp_path_factory):
    path = tmp_path_factory.mktemp("ms") / "box.msh"
    gmsh_box(path, 0.01, dims=(0.1, 0.02, 0.02))
    return _scene({"file": str(path)})


def _deformed(x0, amplitude, seed=0):
    rng = np.random.default_rng(seed)
    return x0 + amplitude * np.ptp(x0, axis=0).max() * rng.standard_normal(x0.shape)


@pytest.mark.parametrize("damping", [0.0, 1e-4])
def test_conformance(gmsh_scene, damping):
    """Rigid motion, finite differences of energy and forces, the explicit energy
    (springfem.testing.check_model); damped, the energy may only fall. (A damping of
    1e-2 s makes ``beta omega_max / 2 = 5.8``: the stable step shrinks to 0.085 of the
    undamped one the core's stable_time_step gives, and a quarter of that blows up.)"""
    model = SystemModel("mass-spring", "mass-spring", MassSpring, damping=damping)
    check_model(model, gmsh_scene)


def test_the_dashpots_see_only_relative_motion(gmsh_scene):
    s = MassSpring(gmsh_scene, damping=0.01)
    scale = np.abs(s.internal(_deformed(s.x0, 0.01))).max()
    v = np.tile([1.0, -2.0, 0.5], (s.n_points, 1))  # a translation: no dashpot force
    assert np.abs(s.internal(s.x0, v)).max() < 1e-12 * scale


def _lattice_tensor(points, tets, E):
    """(1 / V) sum over tets of E V_t sum_{edges of t} n n n n (each edge's van Gelder
    stiffness k l^2 is E times the volume of the tets sharing it)."""
    C = np.zeros((3, 3, 3, 3))
    x = points[tets]
    V = np.abs(np.linalg.det(x[:, 1:] - x[:, :1])) / 6
    for a, b in ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)):
        n = x[:, b] - x[:, a]
        n /= np.linalg.norm(n, axis=1)[:, None]
        C += E * np.einsum("t,ti,tj,tk,tl->ijkl", V, n, n, n, n)
    return C / V.sum()


def test_small_strain_moduli_are_cauchy_born_and_obey_the_cauchy_relations():
    """A box lattice (six tets per cell) under affine strains: the network's energy is
    V/2 eps : C : eps with C from the bond sum (computed here from the geometry alone), the
    interior nodes feel no force (Cauchy–Born is exact for a lattice of centrosymmetric
    nodes), and C is fully symmetric (C_1122 = C_1212 ...: the Cauchy relations), so no
    spring constants give nu = 0.3 (Poisson's ratio along x here differs from 0.3)."""
    box = {"generator": "box", "size": [1.0, 1.0, 1.0], "divisions": [4, 4, 4]}
    s = MassSpring(_scene(box, load=False), calibration="van-gelder")
    C = _lattice_tensor(s.x0, s.tets, 1.0e4)
    interior = np.all((s.x0 > 1e-9) & (s.x0 < 1 - 1e-9), axis=1)
    rng = np.random.default_rng(4)
    for _ in range(5):
        eps = rng.standard_normal((3, 3)) * 1e-6
        eps = 0.5 * (eps + eps.T)
        x = s.x0 + s.x0 @ eps.T
        assert np.abs(s.internal(x)[interior]).max() < 1e-6 * np.abs(s.internal(x)).max()
        # boundary edges carry less volume: the total energy is the lattice density times V
        np.testing.assert_allclose(
            s.strain_energy(x), 0.5 * np.einsum("ij,ijkl,kl", eps, C, eps), rtol=1e-4
        )  # the O(eps^3) terms of the spring lengths: relative ~1e-6
    np.testing.assert_allclose(C, C.transpose(0, 2, 1, 3), atol=1e-12 * np.abs(C).max())
    voigt = [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)]
    D = np.array([[C[i, j, k, l] for k, l in voigt] for i, j in voigt])
    S = np.linalg.inv(D)
    assert abs(-S[0, 1] / S[0, 0] - 0.3) > 0.05


def test_van_gelder_rule_on_the_six_tet_lattice_has_its_closed_form_moduli():
    """van Gelder's claim is two-dimensional: on equilateral triangles his rule
    k = E sum A / l^2 = (sqrt 3 / 2) E gives the triangular lattice's Young's modulus
    2 k / sqrt 3 = E exactly (nu = 1/3). Its volume form has no such lattice in 3D. On the
    box lattice of six tets per cube (every tet has one edge along each axis, two face
    diagonals and the body diagonal) the bond sum gives, by hand, C_1111 = E (1 + 1/3 + 1/9)
    = 13/9 E and C_1122 = C_1212 = E (1/6 + 1/9) = 5/18 E: Young's modulus along an axis
    (C11 - C12)(C11 + 2 C12)/(C11 + C12) = 42/31 E, 35 % stiffer than E, and nu = 5/31.
    The network's energy under affine strains has exactly these moduli
    (docs/peers.rst#mass-spring)."""
    E = 2.0e3
    box = {"generator": "box", "size": [1.0, 1.0, 1.0], "divisions": [3, 3, 3], "split": "six"}
    fix = [{"region": "x_min", "fix": ["x", "y", "z"]}]
    table = {"mesh": box, "material": dict(MATERIAL, E=E), "boundary": fix}
    s = MassSpring(scene_from_dict(table), calibration="van-gelder")
    t = 1e-6

    def modulus(eps):  # 2 W / (V t^2), V = 1
        return 2 * s.strain_energy(s.x0 + s.x0 @ np.asarray(eps).T) / t**2

    c11 = modulus(np.diag([t, 0, 0]))
    c12 = (modulus(np.diag([t, t, 0])) - 2 * c11) / 2
    shear = np.zeros((3, 3))
    shear[0, 1] = shear[1, 0] = t / 2
    c44 = modulus(shear)
    np.testing.assert_allclose([c11, c12, c44], [13 / 9 * E, 5 / 18 * E, 5 / 18 * E], rtol=1e-5)
    young = (c11 - c12) * (c11 + 2 * c12) / (c11 + c12)
    np.testing.assert_allclose([young / E, c12 / (c11 + c12)], [42 / 31, 5 / 31], rtol=1e-5)


def test_static_newton_and_explicit_run_on_a_gmsh_mesh(gmsh_scene):
    """Newton converges; an undamped explicit run (velocity Verlet, 0.9 of the stable step)
    conserves the energy to 1 %; with damping the run loses energy."""
    s = MassSpring(gmsh_scene)
    info = static(s, tol=1e-10)
    assert info.converged and (info.x - s.x0)[:, 2].min() < 0
    dt = 0.9 * stable_time_step(s)[0]
    traj = explicit(s, dt=dt, steps=400, integrator="verlet")
    kinetic = 0.5 * float(np.sum(s.masses[:, None] * traj.v**2))
    total = kinetic + s.energy(traj.x)
    swing = abs(s.energy(info.x))  # the potential energy at equilibrium: the scale of the run
    assert abs(total) < 0.01 * swing


def test_tensor_fit_is_the_least_squares_fit_of_each_tet(gmsh_scene):
    """On a gmsh mesh the fitted springs of every tet are the least-squares optimum: the
    Frobenius distance of sum_e a_e n_e^4 from V C (computed here from the geometry alone)
    grows under any small change of the a_e that keeps them non-negative, and it is below
    van Gelder's a_e = E V for every tet."""
    from peers.mass_spring.network import tensor_fit_stiffness

    mesh = gmsh_scene.mesh
    E, nu = MATERIAL["E"], MATERIAL["nu"]
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    eye = np.eye(3)
    C = lam * np.einsum("ij,kl->ijkl", eye, eye) + mu * (
        np.einsum("ik,jl->ijkl", eye, eye) + np.einsum("il,jk->ijkl", eye, eye)
    )
    rng = np.random.default_rng(1)
    pairs = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))

    def distance(a, n4, V):
        return np.linalg.norm(np.einsum("e,eijkl->ijkl", a, n4) - V * C)

    for t in rng.choice(mesh.n_tets, size=20, replace=False):
        tet = mesh.tets[t : t + 1]
        x = mesh.points[tet[0]]
        V = abs(np.linalg.det(x[1:] - x[:1])) / 6
        d = np.array([x[b] - x[a] for a, b in pairs])
        l2 = np.sum(d * d, axis=1)
        n = d / np.sqrt(l2)[:, None]
        n4 = np.einsum("ei,ej,ek,el->eijkl", n, n, n, n)
        # one tet alone: its six springs, in mesh_edges' order (sorted node pairs)
        k = tensor_fit_stiffness(mesh.points, tet, lam, mu)
        edges = sorted(tuple(sorted((tet[0, a], tet[0, b]))) for a, b in pairs)
        local = [edges.index(tuple(sorted((tet[0, a], tet[0, b])))) for a, b in pairs]
        a = k[local] * l2
        best = distance(a, n4, V)
        assert best < distance(np.full(6, E * V), n4, V)
        for _ in range(10):
            trial = np.maximum(a + 1e-3 * np.abs(a).max() * rng.standard_normal(6), 0.0)
            assert distance(trial, n4, V) >= best * (1 - 1e-12)


def test_tensor_fit_on_a_regular_tet_is_the_closed_form():
    """A regular tet's six springs store 1/2 eps : a sum n^4 : eps, with sum (n_e . n_f)^4
    = 1 + 4/16 per row (four neighbours at 60 degrees, one opposite at 90), so the fit is
    a = V (lambda + 2 mu) / 1.25 for every edge: at nu = 1/4, k = (2 sqrt 2 / 25) E l."""
    from peers.mass_spring.network import tensor_fit_stiffness

    tet = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], dtype=float) * 0.3
    length = 0.6 * np.sqrt(2.0)
    volume = length**3 / (6 * np.sqrt(2.0))
    E, nu = 5.0e3, 0.25
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    k = tensor_fit_stiffness(tet, np.array([[0, 1, 2, 3]]), lam, mu)
    np.testing.assert_allclose(k, volume * (lam + 2 * mu) / 1.25 / length**2, rtol=1e-12)
    np.testing.assert_allclose(k, 2 * np.sqrt(2.0) / 25 * E * length, rtol=1e-12)


def test_bad_input_gives_one_line():
    box = {"generator": "box", "size": [1.0, 1.0, 1.0], "divisions": [1, 1, 1]}
    with pytest.raises(
        InputError, match="calibration 'lloyd' is not one of van-gelder, tensor-fit"
    ):
        MassSpring(_scene(box), calibration="lloyd")
    with pytest.raises(InputError, match="damping"):
        MassSpring(_scene(box), damping=-1.0)
