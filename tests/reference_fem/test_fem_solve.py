"""The public API: result contract, law selection, input and singular-system errors,
the speed benchmark's bookkeeping, and the modules' docstring examples."""

import doctest
import importlib
import json
import pkgutil
from pathlib import Path

import numpy as np
import pytest
import skfem
from skfem.helpers import det, grad, identity

import reference_fem
from reference_fem import FemSolution, bench, solve
from reference_fem.constraints import dirichlet
from reference_fem.options import FemOptions
from reference_fem.space import Space
from springfem.errors import InputError, SolverError
from springfem.mechanics import LinearSolver
from springfem.mesh import box_mesh
from springfem.result import write_result
from springfem.scene import Material, load_scene, scene_from_dict

SCENES = Path(__file__).resolve().parents[2] / "studies" / "scenes"
MODULES = ["reference_fem"] + sorted(
    m.name for m in pkgutil.walk_packages(reference_fem.__path__, "reference_fem.")
)


def test_the_modules_are_found():
    assert {"reference_fem.solver", "reference_fem.explicit_anisotropic"} <= set(MODULES)


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    """Every module, the package itself included, has a passing docstring example."""
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0
    assert result.attempted > 0, f"{name} has no docstring example"


def small_block(law="linear", **material):
    mesh = box_mesh((0.04, 0.01, 0.01), (4, 1, 1))
    return scene_from_dict(
        {
            "name": "block",
            "mesh": mesh,
            "material": Material(law, 1.0e4, 0.3, density=10.0, **material),
            "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
            "load": [
                {"type": "traction", "value": [0.0, 0.0, -1.0], "region": "x_max"},
                {"type": "gravity", "value": [0.0, 0.0, -9.81]},
            ],
            "probe": [
                {"name": "tip", "point": [0.04, 0.005, 0.005]},
                {"name": "inside", "point": [0.013, 0.0031, 0.0077]},
            ],
        }
    )


@pytest.mark.parametrize("order", [1, 2])
def test_result_contract(order, tmp_path):
    scene = small_block()
    sol = solve(scene, order=order)
    assert isinstance(sol, FemSolution)
    r = sol.result
    assert (r.scene, r.model, r.element, r.law) == ("block", "fem", f"P{order}", "linear")
    n_nodes = sol.problem.space.n_nodes
    assert r.counts == {
        "nodes": n_nodes,
        "tets": scene.mesh.n_tets,
        "dofs": 3 * n_nodes,
        "fixed_dofs": 3 * len(sol.problem.space.region_nodes(scene.boundaries[0].region.nodes)),
    }
    assert r.converged and r.iterations == 1 and r.wall_time > 0
    assert set(r.probes) == {"tip", "inside"}
    assert set(r.volume) == {"initial", "final", "relative_change"}
    assert r.volume["initial"] == pytest.approx(0.04 * 0.01 * 0.01)
    assert set(r.reactions) == {"x_min"}
    assert sol.u_vertices.shape == (scene.mesh.n_points, 3)
    assert sol.u.shape == (3 * n_nodes,)
    np.testing.assert_array_equal(sol.u_vertices, sol.u.reshape(-1, 3)[: scene.mesh.n_points])
    assert set(sol.cell_data) == {"J", "von_mises", "fiber", "sheet", "fiber_stretch"}
    assert all(v.shape[0] == scene.mesh.n_tets for v in sol.cell_data.values())
    if order == 2:
        # exact P2 volume against scikit-fem's own interpolation of the same field
        basis = skfem.Basis(
            sol.problem.space.skmesh, skfem.ElementVector(skfem.ElementTetP2()), intorder=3
        )
        J = skfem.Functional(lambda w: det(identity(grad(w["u"])) + grad(w["u"])))
        expect = J.assemble(basis, u=basis.interpolate(sol.u))
        assert r.info["volume_p2"] == pytest.approx(expect, rel=1e-13)
        assert r.info["volume_p2"] != pytest.approx(r.volume["final"], rel=1e-9)
    js, vtu = write_result(tmp_path, r, scene.mesh, sol.u_vertices, cell_data=sol.cell_data)
    assert json.loads(js.read_text())["model"] == "fem" and vtu.exists()


def test_reactions_balance_all_loads():
    scene = small_block()
    sol = solve(scene, order=2)
    weight = 10.0 * 0.04 * 0.01 * 0.01 * 9.81
    applied = np.array([0.0, 0.0, -1.0 * 1e-4 - weight])
    # round-off of the solve in the components that should vanish
    atol = 1e-10 * np.abs(applied).max()
    np.testing.assert_allclose(sol.result.reactions["x_min"], -applied, rtol=1e-9, atol=atol)


def test_p2_probe_uses_quadratic_shape_functions():
    """At an interior point the probe equals the P2 field, not the vertex interpolation."""
    scene = small_block()
    sol = solve(scene, order=2)
    probe = scene.probes[1]
    p1_interp = probe.bary @ sol.u_vertices[scene.mesh.tets[probe.tet]]
    P = sol.problem.space.basis.probes(probe.point[:, None])  # scikit-fem's own evaluation
    exact = P @ sol.u.reshape(-1, 3)
    np.testing.assert_allclose(sol.result.probes["inside"], exact[0], rtol=1e-12)
    assert not np.allclose(sol.result.probes["inside"], p1_interp, rtol=1e-6)


def test_defaults_come_from_the_scene():
    scene = load_scene(SCENES / "stretch-cross.toml")
    sol = solve(scene)
    assert sol.result.element == f"P{FemOptions.of(scene).order}"
    assert sol.result.law == "transverse-linear"


def test_law_names_and_errors():
    iso = small_block(law="neo-hookean", formulation="uncoupled", volumetric="quadratic")
    assert solve(iso, order=1).result.law == "neo-hookean/uncoupled/quadratic"
    assert solve(iso, order=1, law="neo-hookean/coupled").result.law == "neo-hookean/coupled"
    assert solve(iso, order=1, law="linear").result.law == "linear"
    with pytest.raises(InputError, match="not one of"):
        solve(iso, law="hooke")
    with pytest.raises(InputError, match="transverse-linear"):
        solve(iso, law="transverse-linear")
    with pytest.raises(InputError, match="order"):
        solve(iso, order=3)
    transverse = load_scene(SCENES / "stretch-fiber.toml")
    with pytest.raises(InputError, match="isotropic"):
        solve(transverse, law="neo-hookean")


def test_singular_system_is_reported():
    scene = small_block()
    scene.boundaries = []
    with pytest.raises(SolverError, match="no displacement is prescribed"):
        solve(scene)
    scene = small_block()
    scene.boundaries = scene.boundaries[:0]
    held = {"mesh": scene.mesh, "material": scene.material}
    scene2 = scene_from_dict({**held, "boundary": [{"region": "x_min", "fix": ["x"]}]})
    with pytest.raises(SolverError, match="translation y") as info:
        solve(scene2)
    assert info.value.exit_code == 3
    # all three translations held at one node: the three rotations stay free
    corner = {"region": {"point": [0, 0, 0]}, "fix": ["x", "y", "z"]}
    scene3 = scene_from_dict({**held, "boundary": [corner]})
    with pytest.raises(SolverError, match="rotation"):
        solve(scene3)


@pytest.mark.parametrize("method", ["direct", "amg"])
def test_linear_solver_rejects_singular_matrix(method):
    """Without the up-front check, the solvers themselves refuse a singular system."""
    scene = small_block()
    space = Space(scene.mesh, 1)
    from reference_fem import FemProblem

    K = FemProblem(scene, 1).stiffness
    b = np.zeros(space.n_dofs)
    b[2::3] = -1.0  # a net force: no solution without supports
    solver = LinearSolver(method, maxiter=200)
    with pytest.raises(SolverError):
        solver.solve(K, b, np.ones(space.n_dofs, dtype=bool))


def test_amg_and_direct_agree():
    scene = small_block()
    from reference_fem import FemProblem

    problem = FemProblem(scene, 2)
    K, f = problem.stiffness, problem.loads.vector(None)
    free = dirichlet(scene, problem.space).free
    x_direct = LinearSolver("direct").solve(K, f, free)
    amg = LinearSolver("amg", near_nullspace=problem.linear_solver.near_nullspace, rtol=1e-12)
    x_amg = amg.solve(K, f, free)
    np.testing.assert_allclose(x_amg, x_direct, atol=1e-8 * np.abs(x_direct).max())
    assert amg.stats["krylov_iterations"] > 0


def test_bench_bookkeeping():
    """Small run of the benchmark: both paths solve the same problem (no timing checks)."""
    out = bench(n_tets=600, verbose=False)
    assert out["n_tets"] > 0 and out["fast"]["total"] > 0 and out["speedup"] > 0
    assert out["tip_relative_difference"] < 1e-6  # CG tolerance 1e-10 vs SuperLU
    assert out["newton_iteration"]["total"] > 0


def test_public_names():
    for name in ("solve", "bench", "material_matrix", "element_stiffness_p1", "FemSolution"):
        assert hasattr(reference_fem, name)
