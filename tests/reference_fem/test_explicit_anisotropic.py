"""Anisotropic explicit FEM kernels (reference_fem.explicit_anisotropic) against references.

- the kernel forces equal minus the numpy residual's internal force
  (``FemProblem(scene, 1).internal_force``: the laws of springfem.materials.laws and
  reference_fem.materials, einsum assembly) for transverse-linear, Guccione and
  Holzapfel–Ogden, each volumetric penalty, on a jittered five-tet box (irregular tets, a
  padded last block) with a smoothly rotating, tilted frame per element, at a finite
  deformation of ~25 % strain: float64 to 1e-12 relative (round-off of reordered sums and
  FMA; ~1e-15 measured), mixed and float32 within the isotropic kernels' documented bounds;
- frame invariance: rotating the mesh, the deformed state and the frames by one rotation
  rotates the forces (norms unchanged);
- ExplicitFem passes the conformance check (springfem.testing.check_model): rigid motion,
  finite differences of its (numpy) energy and of its forces, the small-strain tangent;
- symplectic Euler without damping, at half the critical step, conserves the energy within
  the bound derived in :func:`test_energy_conserved_without_damping`.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from reference_fem.explicit import ExplicitFem
from reference_fem.explicit_anisotropic import (
    BLOCK,
    anisotropic_kernel,
    anisotropic_layout,
    law_parameters,
)
from reference_fem.problem import FemProblem
from springfem.blocks import chunks
from springfem.errors import InputError
from springfem.mechanics import explicit, stable_time_step
from springfem.mesh import box_mesh
from springfem.model_api import SystemModel
from springfem.scene import scene_from_dict
from springfem.testing import check_model

SIZE = np.array([1.0, 0.8, 0.6])
MATERIALS = {
    "transverse-linear": {"E_fiber": 3.0e3, "E_cross": 1.0e3, "nu_fiber_cross": 0.3,
                          "nu_cross": 0.4, "G_fiber": 0.5e3},
    "guccione": {"C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0, "kappa": 100.0},
    "holzapfel-ogden": {"a": 1.0, "b": 5.0, "a_f": 2.0, "b_f": 5.0, "a_s": 1.0, "b_s": 5.0,
                        "a_fs": 0.5, "b_fs": 5.0, "kappa": 100.0},
}  # fmt: skip
SLOW = pytest.mark.slow


def rel(a, b):
    return float(np.abs(a - b).max() / np.abs(b).max())


def rotating_frames(centres: np.ndarray) -> np.ndarray:
    """A frame per element that turns smoothly through the body (about all three axes)."""
    rotvec = np.stack(
        [1.2 * centres[:, 2] - 0.3, 0.9 * centres[:, 0] + 0.4, 1.5 * centres[:, 1] - 0.6], 1
    )
    return Rotation.from_rotvec(rotvec).as_matrix().transpose(0, 2, 1)  # rows: the axes


@pytest.fixture(scope="module")
def mesh():
    m = box_mesh(tuple(SIZE), (3, 3, 2), split="five")
    rng = np.random.default_rng(3)
    inner = np.all((m.points > 1e-9) & (m.points < SIZE - 1e-9), axis=1)
    points = m.points + 0.05 * rng.standard_normal(m.points.shape) * inner[:, None]
    assert m.n_tets % BLOCK != 0  # a padded last block
    return replace(m, points=points)


def make_scene(mesh, law, volumetric="log", load=(), **extra):
    material = {"law": law, **MATERIALS[law], **extra}
    if law != "transverse-linear":
        material["volumetric"] = volumetric
    scene = scene_from_dict(
        {
            "mesh": mesh,
            "material": material,
            "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
            "load": list(load),
        }
    )
    return replace(scene, frames=rotating_frames(mesh.centers()))


def deformed(points, seed=0):
    """A homogeneous ~25 % strain, a smooth bend and a small jitter (all J > 0)."""
    rng = np.random.default_rng(seed)
    A = np.array([[0.18, 0.08, -0.05], [-0.07, -0.10, 0.07], [0.04, 0.10, 0.14]])
    u = points @ A.T + 0.06 * np.sin(2.0 * points[:, [1, 2, 0]])
    return points + u + 0.005 * rng.standard_normal(points.shape)


def kernel_forces(scene, x, precision="float64", parallel=False, volumetric=None):
    mesh, law = scene.mesh, scene.material.law
    fem = FemProblem(scene, 1)
    prm = law_parameters(law, scene.material, fem.law)
    vol = volumetric or scene.material.volumetric
    T, K = anisotropic_layout(mesh.tets, mesh.points, scene.frames, law, precision)
    serial, par = anisotropic_kernel(law, vol, precision)
    out = np.full_like(x, np.nan)
    if parallel:
        ptr = chunks(T.shape[0])
        buf = np.zeros((ptr.size - 1, x.shape[0], 3))
        bad = par(x, T, K, mesh.n_tets, prm, ptr, buf, out)
    else:
        bad = serial(x, T, K, mesh.n_tets, prm, out)
    return out, bad


def numpy_forces(scene, x):
    """Minus the residual's internal force of P1 (the oracle)."""
    u = (x - scene.mesh.points).ravel()
    return -FemProblem(scene, 1).internal_force(u)[0].reshape(-1, 3)


def test_the_state_is_a_finite_deformation(mesh):
    x = deformed(mesh.points)
    X, Y = mesh.points[mesh.tets], x[mesh.tets]
    F = np.einsum("kai,kja->kij", Y[:, 1:] - Y[:, :1], np.linalg.inv(X[:, 1:] - X[:, :1]))
    E = 0.5 * (np.einsum("kji,kjl->kil", F, F) - np.eye(3))
    strain = np.linalg.eigvalsh(E)
    assert np.linalg.det(F).min() > 0.5
    assert 0.2 < np.abs(strain).max(axis=1).mean() < 0.4  # ~20-30 % Green strain


@pytest.mark.parametrize(
    ("law", "volumetric"),
    [("transverse-linear", "log"), ("guccione", "log"), ("holzapfel-ogden", "log"),
     pytest.param("guccione", "quadratic", marks=SLOW),
     pytest.param("guccione", "simo-taylor", marks=SLOW),
     pytest.param("holzapfel-ogden", "quadratic", marks=SLOW),
     pytest.param("holzapfel-ogden", "simo-taylor", marks=SLOW)],
)  # fmt: skip
def test_float64_equals_numpy_residual(mesh, law, volumetric):
    scene = make_scene(mesh, law, volumetric)
    x = deformed(mesh.points)
    f, bad = kernel_forces(scene, x)
    assert bad == 0
    assert rel(f, numpy_forces(scene, x)) < 1e-12


@pytest.mark.parametrize(
    ("law", "steep"),
    [("guccione", {"b_f": 300.0, "b_fs": 100.0}),
     ("holzapfel-ogden", {"b": 60.0, "b_f": 300.0, "b_s": 200.0, "b_fs": 300.0})],
)  # fmt: skip
def test_steep_exponentials_equal_numpy_residual(mesh, law, steep):
    """Exponents up to ~60 (2^k up to 2^90): the written-out exp over a wide range; an
    exponent rounded in its last bit moves e^x by x eps, ~1e-14 here."""
    scene = make_scene(mesh, law, **steep)
    x = deformed(mesh.points, seed=4)
    f, _ = kernel_forces(scene, x)
    assert rel(f, numpy_forces(scene, x)) < 1e-12


@pytest.mark.parametrize("law", ["guccione", "holzapfel-ogden"])
def test_active_tension_equals_numpy_residual(mesh, law):
    scene = make_scene(mesh, law, active_tension=3.0)
    x = deformed(mesh.points, seed=1)
    f, _ = kernel_forces(scene, x)
    assert rel(f, numpy_forces(scene, x)) < 1e-12
    f0, _ = kernel_forces(scene, mesh.points)  # at rest: the active stress alone
    assert np.abs(f0).max() > 1e-3 and rel(f0, numpy_forces(scene, mesh.points)) < 1e-12


def test_holzapfel_ogden_compressed_fibres_carry_no_fibre_stress(mesh):
    """Fibres and sheets in compression: the tension-only terms switch off in the kernel."""
    scene = make_scene(mesh, "holzapfel-ogden")
    x = 0.92 * mesh.points  # uniform 8 % compression: I4f = I4s = 0.85 < 1 everywhere
    f, _ = kernel_forces(scene, x)
    assert rel(f, numpy_forces(scene, x)) < 1e-12
    stiff = make_scene(mesh, "holzapfel-ogden", a_f=200.0, a_s=100.0)
    assert rel(kernel_forces(stiff, x)[0], f) < 1e-14


@pytest.mark.parametrize(
    ("law", "precision", "tol"),
    # float32 rounding (6e-8) of the constants (mixed) or of every operation (float32),
    # amplified by the cancellation in E = (C - I)/2 and by the exponentials: the isotropic
    # kernels' bounds (reference_fem/test_explicit_kernels.py), measured 1e-7 - 1e-6 here
    [("transverse-linear", "float32", 1e-4), ("guccione", "float32", 1e-4),
     ("holzapfel-ogden", "float32", 1e-4), ("guccione", "mixed", 1e-5),
     pytest.param("transverse-linear", "mixed", 1e-5, marks=SLOW),
     pytest.param("holzapfel-ogden", "mixed", 1e-5, marks=SLOW)],
)  # fmt: skip
def test_reduced_precision(mesh, law, precision, tol):
    scene = make_scene(mesh, law)
    x = deformed(mesh.points)
    f, _ = kernel_forces(scene, x, precision)
    assert 1e-10 < rel(f, numpy_forces(scene, x)) < tol


@pytest.mark.parametrize("law", ["transverse-linear", "guccione", "holzapfel-ogden"])
def test_frame_invariance(mesh, law):
    """f(Q X, Q x, R Q^T) = Q f(X, x, R): the force norms do not change."""
    scene = make_scene(mesh, law)
    x = deformed(mesh.points)
    f, _ = kernel_forces(scene, x)
    Q = Rotation.from_rotvec([0.7, -1.1, 0.4]).as_matrix()
    turned = replace(scene, mesh=replace(mesh, points=mesh.points @ Q.T), frames=scene.frames @ Q.T)
    g, _ = kernel_forces(turned, x @ Q.T)
    norms, turned_norms = np.linalg.norm(f, axis=1), np.linalg.norm(g, axis=1)
    assert np.abs(norms - turned_norms).max() < 1e-12 * norms.max()
    assert rel(g, f @ Q.T) < 1e-12


def test_left_handed_frames_give_the_same_forces(mesh):
    scene = make_scene(mesh, "guccione")
    flipped = replace(scene, frames=scene.frames * np.array([1.0, 1.0, -1.0])[:, None])
    x = deformed(mesh.points)
    assert rel(kernel_forces(flipped, x)[0], kernel_forces(scene, x)[0]) < 1e-14


def test_inverted_elements_counted_and_refused(mesh):
    scene = make_scene(mesh, "guccione")
    x = mesh.points.copy()
    k = mesh.n_tets - 1  # an element of the padded last block: counted once
    a, b = mesh.tets[k, :2]
    x[a], x[b] = mesh.points[b], mesh.points[a]
    J = np.linalg.det(x[mesh.tets[:, 1:]] - x[mesh.tets[:, :1]])
    f, bad = kernel_forces(scene, x)
    assert bad == int(np.sum(J <= 0)) >= 1 and np.isfinite(f).all()
    fem = ExplicitFem(scene)
    with pytest.raises(Exception, match="inverted element"):
        fem.internal(x)


@SLOW
def test_parallel_equals_serial(mesh):
    scene = make_scene(mesh, "holzapfel-ogden")
    x = deformed(mesh.points)
    f, _ = kernel_forces(scene, x)
    g, _ = kernel_forces(scene, x, parallel=True)
    assert rel(g, f) < 1e-13


# --------------------------------------------------------------------------- ExplicitFem


@pytest.mark.parametrize("law", ["transverse-linear", "guccione", "holzapfel-ogden"])
def test_explicit_fem_conforms(mesh, law):
    """ExplicitFem of each anisotropic law, with an active tension for the tissue laws:
    rigid motion gives no force and f(Qx) = Q f(x) with the frames turning with the body,
    forces and tangent are central differences of the energy and the forces, the tangent at
    rest is the core's linear P1 of the law's small-strain matrix, velocity Verlet conserves
    the energy (springfem.testing.check_model). Holzapfel–Ogden's fibres carry tension only,
    so its tangent at F = I is one-sided (off there, on in the core's small-strain matrix:
    tests/reference_fem/test_laws.py): no small-strain claim."""
    extra = {} if law == "transverse-linear" else {"active_tension": 1.0}
    scene = make_scene(mesh, law, **extra)
    model = SystemModel("explicit-" + law, law, lambda s: ExplicitFem(s, law=law))
    check_model(model, scene, small_strain=None if law == "holzapfel-ogden" else "exact")


@pytest.mark.parametrize("law", ["guccione", "holzapfel-ogden"])
def test_explicit_fem_energy_is_the_laws(mesh, law):
    """ExplicitFem's (tangent-free) energy equals the numpy law's, integrated with V."""
    scene = make_scene(mesh, law, volumetric="simo-taylor", active_tension=2.0)
    fem = ExplicitFem(scene)
    x = deformed(mesh.points, seed=3)
    ref = FemProblem(scene, 1).energy((x - mesh.points).ravel())
    assert fem.strain_energy(x) == pytest.approx(ref, rel=1e-12)


def test_active_tension_ramps_with_the_load_factor(mesh):
    scene = make_scene(mesh, "guccione", active_tension=3.0)
    fem = ExplicitFem(scene)
    half = fem.forces(mesh.points, None, 0.5).copy()
    full = fem.forces(mesh.points, None, 1.0)
    assert rel(2.0 * half, full) < 1e-12
    assert rel(full, numpy_forces(scene, mesh.points)) < 1e-12


def test_explicit_fem_refuses_what_it_cannot_do(mesh):
    scene = make_scene(mesh, "guccione")
    incompressible = replace(scene, material=replace(scene.material, incompressible=True))
    with pytest.raises(InputError, match="kappa"):
        ExplicitFem(incompressible, law="guccione")
    with pytest.raises(InputError, match="needs a holzapfel-ogden material"):
        ExplicitFem(scene, law="holzapfel-ogden")
    with pytest.raises(InputError, match="transverse-linear"):
        ExplicitFem(make_scene(mesh, "transverse-linear"), law="neo-hookean")


def test_energy_conserved_without_damping():
    """A Guccione bar, clamped at x = 0, released from a bend; symplectic Euler at half the
    critical step, no damping.

    Bound. The recorded energy uses the synchronised velocity (velocity Verlet's). For a
    linear system, in each mode ``q_k`` Verlet conserves ``H~_k = H_k - dt^2/8 omega_k^4
    q_k^2``, so ``H~ = H - dt^2/8 a^T M a`` with ``a = M^-1 f``: the energy exceeds the
    conserved one by ``0 <= dt^2/8 f^T M^-1 f``, and any two recorded energies differ by
    at most ``B = dt^2/8 max_n f_n^T M^-1 f_n``. This run's strains are ~1 %, so the
    nonlinear remainder is a few per cent of ``B``; the test allows ``1.1 B`` for the raw
    energy and ``0.1 B`` for the drift of ``H~`` (a secular drift would grow with the
    number of steps and exceed it).
    """
    bar = box_mesh((4.0, 1.0, 1.0), (8, 2, 2), split="five")
    scene = make_scene(bar, "guccione")
    scene = replace(scene, material=replace(scene.material, density=1.0))
    fem = ExplicitFem(scene)
    dt_crit, _ = stable_time_step(fem)
    dt = 0.5 * dt_crit
    X = fem.x0
    x_init = X + np.stack([0 * X[:, 0], 0 * X[:, 0], 0.01 * X[:, 0] ** 2], axis=1)
    free = np.ones(X.size, bool)
    free[fem.fixed_dofs] = False
    corrections = []

    def record(step, t, x, v):
        f = fem.internal(x).ravel()[free]
        corrections.append(dt**2 / 8 * float(f @ (f / np.repeat(fem.masses, 3)[free])))

    f0 = fem.internal(x_init).ravel()[free]
    corrections.insert(0, dt**2 / 8 * float(f0 @ (f0 / np.repeat(fem.masses, 3)[free])))
    traj = explicit(fem, dt=dt, steps=600, x_init=x_init, record_every=1, callback=record)
    H = traj.kinetic + traj.potential
    B = max(corrections)
    assert B > 1e-4 * H[0]  # the bound is not vacuous: the energy does oscillate
    assert np.ptp(H) <= 1.1 * B
    H_mod = H - np.asarray(corrections)
    assert np.ptp(H_mod) <= 0.1 * B
    assert traj.kinetic.max() > 0.5 * H[0]  # it moved: energy went through the kinetic part


def test_fem_solver_explicit_runs_a_tissue_scene(mesh):
    """``[fem] solver = "explicit"`` on a Guccione scene: the scene's law, its kernel."""
    from reference_fem.dynamics import dynamic_system, solve_dynamic
    from reference_fem.options import FemOptions

    load = [{"type": "traction", "value": [0.0, 0.0, -0.5], "region": "x_max"}]
    scene = make_scene(mesh, "guccione", load=load)
    system = dynamic_system(scene)
    assert system.law == "guccione" and system.tissue is not None
    traj = solve_dynamic(system, FemOptions(solver="explicit", steps=40))
    assert traj.steps == 40 and np.isfinite(traj.x).all()
    assert (traj.x - system.x0)[:, 2].min() < 0  # pulled down at x_max
    incompressible = replace(scene, material=replace(scene.material, incompressible=True))
    with pytest.raises(InputError, match="kappa"):
        dynamic_system(incompressible)
