"""A law added in one file (examples/toy_law.py, docs/laws.rst) runs through every model.

The toy law, Saint Venant–Kirchhoff with a fibre term, registers itself in the law table;
nothing else is edited. Checked against independent references:

- its small-strain tangent, which the table derives from the law at ``F = I``, equals the
  closed form ``lame_matrix(lambda + kappa, mu)`` plus ``2 k_fibre`` on ``D_ff``;
- its stress is the finite-difference gradient of its energy, its tangent that of its
  stress;
- the FEM reference's static solve (P1) at a small load equals linear P1 elasticity with the
  same small-strain constants to O(strain) (here strains ~1e-4: 1e-3 relative allowed);
- the explicit FEM (the numpy fallback of a law without a compiled kernel) gives the forces
  of the FEM residual, and the fallback run on Guccione gives the compiled Guccione
  kernel's forces, on Holzapfel–Ogden the compiled Holzapfel–Ogden kernel's (1e-12
  relative: round-off of reordered sums); an explicit run conserves
  the energy within the Verlet bound of tests/reference_fem/test_explicit_anisotropic.py;
- the spring model's default element for it takes the law's energy on its Green measures:
  under a homogeneous deformation it equals P1 FEM of the law (exact there) to round-off,
  its tangent is the finite-difference derivative of its forces; the Guccione and
  Holzapfel–Ogden terms written out for the compiled pass equal their laws through the
  same derivation (1e-13);
- ``springfem verdict`` weighs FEM and spring models on a scene of the law.
"""

from __future__ import annotations

import importlib.util
import sys
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from reference_fem import solve
from reference_fem.explicit import ExplicitFem
from reference_fem.explicit_anisotropic import (
    anisotropic_kernel,
    anisotropic_layout,
    law_parameters,
)
from reference_fem.explicit_generic import generic_kernel
from reference_fem.problem import FemProblem
from springfem.materials import lame_matrix
from springfem.materials.laws import LAWS, TISSUE_LAWS, small_strain_tangent, tissue_law
from springfem.mechanics import explicit, stable_time_step
from springfem.scene import LAWS as SCENE_LAWS
from springfem.scene import scene_from_dict
from springmodel.model import SpringModel
from springmodel.tissue_element import TissueLawParameters, frame_measures, measure_derivatives

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "toy_law.py"
MU, LAM, KAPPA, K_F = 1.0e3, 0.5e3, 1.0e3, 2.0e3


@pytest.fixture(scope="module")
def toy():
    """The example module, imported once (it registers its law); unregistered afterwards so
    that the other tests see the shipped table."""
    spec = importlib.util.spec_from_file_location("toy_law", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    sys.modules["toy_law"] = module
    spec.loader.exec_module(module)
    yield module
    LAWS.pop("fibre-svk")
    TISSUE_LAWS.pop("fibre-svk")
    sys.modules.pop("toy_law")


def bar(k_fibre=K_F, load=-0.05, divisions=(8, 2, 2)):
    return scene_from_dict({
        "name": "toy-bar",
        "mesh": {"generator": "box", "size": [4.0, 1.0, 1.0], "divisions": list(divisions)},
        "material": {"law": "fibre-svk", "lame_mu": MU, "lame_lambda": LAM,
                     "k_fibre": k_fibre, "kappa": KAPPA, "density": 1.0},
        "axes": {"fiber": [1.0, 0.2, 0.0], "sheet": [-0.2, 1.0, 0.0]},
        "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
        "load": [{"type": "traction", "region": "x_max", "value": [0.0, 0.0, load]}],
    })  # fmt: skip


def test_one_registration_line_makes_a_scene_law(toy):
    assert "fibre-svk" in SCENE_LAWS
    assert TISSUE_LAWS["fibre-svk"] == ("lame_mu", "lame_lambda", "k_fibre")
    assert bar().material.law == "fibre-svk"
    # the manual's scene-key reference (read off the parsers) lists the new law's keys
    from springfem.scene.reference import accepted_keys

    assert {"lame_mu", "lame_lambda", "k_fibre", "kappa"} <= set(
        accepted_keys()["material (fibre-svk)"]
    )


def test_an_installed_package_registers_a_law_by_entry_point(toy, monkeypatch):
    """``[project.entry-points."springfem.laws"]`` (docs/laws.rst#add-a-law-plug-in): the
    table loads the class the entry point names."""
    import springfem.plugins

    LAWS.pop("fibre-svk")
    monkeypatch.setattr(
        springfem.plugins, "entry_points", lambda group: {"fibre-svk": "toy_law:FibreSVK"}
    )
    from springfem.materials.laws import register_plugins

    register_plugins()
    assert LAWS["fibre-svk"] is toy.FibreSVK


def test_the_small_strain_tangent_is_the_closed_form(toy):
    params = {"lame_mu": MU, "lame_lambda": LAM, "k_fibre": K_F}
    D = small_strain_tangent("fibre-svk", params, kappa=KAPPA)
    closed = lame_matrix(LAM + KAPPA, MU)
    closed[0, 0] += 2.0 * K_F
    assert np.allclose(D, closed, rtol=1e-14, atol=1e-12 * abs(closed).max())


def _fd(fun, F, h=1e-6):
    out = np.array([[(fun(F + h * e) - fun(F - h * e)) / (2 * h) for e in row] for row in BASIS])
    return np.moveaxis(out, (0, 1), (-2, -1))


BASIS = np.eye(9).reshape(3, 3, 3, 3)


def test_stress_and_tangent_are_derivatives(toy):
    law = toy.FibreSVK(lame_mu=1.0, lame_lambda=2.0, k_fibre=3.0, kappa=5.0)
    rng = np.random.default_rng(2)
    F = np.eye(3) + 0.2 * rng.standard_normal((3, 3))
    R = np.linalg.qr(rng.standard_normal((3, 3)))[0]
    P, A = law.stress_tangent(F, R)
    # central differences: ~h^2 |d3W| + eps |W| / h, 1e-7 relative is ample
    assert np.allclose(P, _fd(lambda G: law.energy(G, R), F), atol=1e-7 * abs(P).max())
    assert np.allclose(A, _fd(lambda G: law.stress(G, R), F), atol=1e-7 * abs(A).max())


def test_fem_static_solve_is_linear_elasticity_at_small_load(toy):
    scene = bar(k_fibre=0.0)
    u = solve(scene, order=1).u_vertices
    lam, mu = LAM + KAPPA, MU
    linear = replace(
        scene,
        material=replace(
            scene.material,
            law="linear",
            E=mu * (3 * lam + 2 * mu) / (lam + mu),
            nu=lam / (2 * (lam + mu)),
            parameters={},
        ),
    )
    u_lin = solve(linear, order=1).u_vertices
    assert abs(u).max() > 1e-5  # it bends
    assert np.abs(u - u_lin).max() < 1e-3 * np.abs(u_lin).max()


def test_explicit_forces_are_the_fem_residual(toy):
    scene = bar(divisions=(3, 2, 2))
    fem = ExplicitFem(scene)
    assert fem.law == "fibre-svk"
    rng = np.random.default_rng(4)
    x = fem.x0 + 0.05 * rng.standard_normal(fem.x0.shape)
    f = fem.internal(x)
    oracle = -FemProblem(scene, 1).internal_force((x - fem.x0).ravel())[0].reshape(-1, 3)
    assert np.abs(f - oracle).max() < 1e-12 * np.abs(oracle).max()


@pytest.mark.parametrize(
    ("law", "volumetric"), [("guccione", "log"), ("holzapfel-ogden", "simo-taylor")]
)
def test_the_fallback_kernel_is_the_compiled_one(law, volumetric):
    """The compiled kernels, written out per law, against the law modules through the
    fallback: the same forces at a finite strain with an active tension."""
    constants = {"guccione": {"C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0},
                 "holzapfel-ogden": {"a": 1.0, "b": 5.0, "a_f": 2.0, "b_f": 5.0, "a_s": 1.0,
                                     "b_s": 5.0, "a_fs": 0.5, "b_fs": 5.0}}[law]  # fmt: skip
    scene = scene_from_dict({
        "mesh": {"generator": "box", "size": [1.0, 0.8, 0.6], "divisions": [3, 2, 2]},
        "material": {"law": law, **constants, "kappa": 100.0, "active_tension": 3.0,
                     "volumetric": volumetric},
        "axes": {"fiber": [1.0, 0.3, 0.1], "sheet": [-0.3, 1.0, 0.0]},
    })  # fmt: skip
    mesh, frames = scene.mesh, scene.frames
    tissue = tissue_law(scene.material)
    prm = law_parameters(law, scene.material, tissue)
    rng = np.random.default_rng(5)
    x = mesh.points * [1.15, 0.95, 1.02] + 0.02 * rng.standard_normal(mesh.points.shape)
    T, K = anisotropic_layout(mesh.tets, mesh.points, frames, law, "float64")
    compiled, out_c = anisotropic_kernel(law, volumetric, "float64")[0], np.empty_like(x)
    compiled(x, T, K, mesh.n_tets, prm, out_c)
    fallback, out_g = generic_kernel(tissue, mesh.tets, mesh.points, frames)[0], np.empty_like(x)
    fallback(x, None, None, mesh.n_tets, prm, out_g)
    # round-off of reordered sums and FMA (the kernels' own bound against the FEM residual)
    assert np.abs(out_g - out_c).max() < 1e-12 * np.abs(out_c).max()


def test_explicit_dynamics_conserves_the_energy(toy):
    """Symplectic Euler at half the critical step, no damping: the energy stays within the
    Verlet bound ``1.1 B``, ``B = dt^2/8 max f^T M^-1 f`` (the derivation:
    tests/reference_fem/test_explicit_anisotropic.py)."""
    fem = ExplicitFem(bar(divisions=(6, 2, 2)))
    dt = 0.5 * stable_time_step(fem)[0]
    X = fem.x0
    x_init = X + np.stack([0 * X[:, 0], 0 * X[:, 0], 0.002 * X[:, 0] ** 2], axis=1)
    free = np.ones(X.size, bool)
    free[fem.fixed_dofs] = False
    minv = 1.0 / np.repeat(fem.masses, 3)[free]
    bounds = []

    def record(step, t, x, v):
        f = fem.internal(x).ravel()[free]
        bounds.append(dt**2 / 8 * float(f @ (f * minv)))

    f0 = fem.internal(x_init).ravel()[free]
    bounds.insert(0, dt**2 / 8 * float(f0 @ (f0 * minv)))
    traj = explicit(fem, dt=dt, steps=300, x_init=x_init, record_every=1, callback=record)
    H = traj.kinetic + traj.potential
    assert traj.kinetic.max() > 0.3 * H[0]  # it moved
    assert np.ptp(H) <= 1.1 * max(bounds)


def test_the_spring_tissue_element_is_the_law(toy):
    """The default spring element of a tissue law takes the law's own energy on its Green
    measures (springmodel.tissue_element.law_derivatives): under a homogeneous deformation
    it equals P1 FEM of the law, which is exact there (forces and energy to round-off)."""
    scene = bar(divisions=(3, 2, 2))
    model = SpringModel(scene)
    assert model.options.stiffening == "law"
    X = scene.mesh.points
    F = np.array([[1.1, 0.05, 0.0], [0.02, 0.97, 0.04], [0.0, -0.03, 1.02]])
    x = X @ F.T
    f_fem = FemProblem(scene, 1).internal_force((x - X).ravel())[0].reshape(-1, 3)
    assert np.abs(model.internal(x) + f_fem).max() < 1e-10 * np.abs(f_fem).max()
    law = tissue_law(scene.material)
    W = float(scene.mesh.volumes().sum() * law.energy(F, scene.frames[0]))
    assert abs(model.energy(x, scale=0.0) - W) < 1e-10 * W  # no load work
    # the tangent is the derivative of the forces (central differences, 1e-6 relative)
    K = model.stiffness(x).toarray()
    h, rng = 1e-6, np.random.default_rng(6)
    d = rng.standard_normal(x.shape)
    fd = (model.internal(x - h * d) - model.internal(x + h * d)).ravel() / (2 * h)
    assert np.abs(K @ d.ravel() - fd).max() < 1e-6 * np.abs(fd).max()


@pytest.mark.parametrize("law", ["guccione", "holzapfel-ogden"])
def test_the_compiled_laws_spring_terms_are_their_laws(law):
    """The Guccione and Holzapfel–Ogden terms written out on the spring measures (numpy and
    compiled) against the same laws' ``local`` through the generic derivation."""
    constants = {"guccione": {"C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0},
                 "holzapfel-ogden": {"a": 1.0, "b": 2.0, "a_f": 2.0, "b_f": 3.0, "a_s": 1.5,
                                     "b_s": 2.5, "a_fs": 0.5, "b_fs": 1.5}}[law]  # fmt: skip
    rng = np.random.default_rng(7)
    F = np.eye(3) + 0.2 * rng.standard_normal((9, 3, 3))
    m = frame_measures(np.transpose(F, (0, 2, 1)))  # rows Z_l = F e_l
    el = SimpleNamespace(V0=rng.uniform(0.5, 2.0, 9))
    values = tuple(constants.values())
    hand = TissueLawParameters(law, law=values + (0.0,) * (8 - len(values)))
    derived = TissueLawParameters("law", tissue=LAWS[law](**constants))
    for a, b in zip(
        measure_derivatives(m, el, hand, True)[:3],
        measure_derivatives(m, el, derived, True)[:3],
        strict=True,
    ):
        assert np.abs(a - b).max() < 1e-13 * np.abs(a).max()  # round-off (1e-15 measured)


def test_verdict_weighs_the_models_on_the_new_law(toy):
    from studies.verdict import verdict

    v = verdict(bar(divisions=(4, 1, 1)), budget=120.0, rounds=1, solves=0)
    assert v.reference == "P2"  # the FEM reference of a finite-strain law
    rows = v.table.set_index("model")
    assert {"P1", "spring"} <= set(rows.index)
    # the default (tissue) spring element is P1 of the law (the test above), the exact one
    # its small-strain P1 element (docs/calibration.rst), O(strain) ~ 1e-4 off here
    assert float(rows.loc["spring", "vs P1 (same mesh)"]) < 1e-8
    assert float(rows.loc["spring-exact", "vs P1 (same mesh)"]) < 1e-3
    assert rows.loc["spring", "status"] == "ok"
