"""``springfem bench fem``: the reference FEM's speed against scikit-fem's defaults.

One run times, on the same box mesh (a clamped block, end traction, linear P1):

- this package: assembly (space, pattern, einsum element matrices, loads, constraints)
  and solve (AMG-preconditioned CG), and the whole :func:`reference_fem.solve`;
- scikit-fem's defaults: ``Basis`` with the default quadrature, ``asm(linear_elasticity)``,
  ``solve(*condense(...))`` (SuperLU);
- one Newton iteration (residual, tangent, AMG solve) of the neo-Hookean problem.

Speeds are compared as ratios measured in the same run
(docs/verification.rst#how-speed-is-measured).

Examples
--------
>>> r = bench(n_tets=100, defaults=False, newton=False, verbose=False)
>>> r["n_tets"], r["n_dofs"], sorted(r["fast"])[:3]
(96, 135, ['assembly', 'krylov_iterations', 'solve'])
"""

from __future__ import annotations

import sys
import time

import numpy as np

from springfem.scene import Scene

from .scenes import bench_scene


def _skfem_defaults(scene: Scene) -> dict:
    """Assemble and solve the bench problem the way scikit-fem's examples do by default."""
    import skfem
    from skfem.helpers import dot
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    mesh = scene.mesh
    t0 = time.perf_counter()
    m = skfem.MeshTet(np.ascontiguousarray(mesh.points.T), np.ascontiguousarray(mesh.tets.T))
    e = skfem.ElementVector(skfem.ElementTetP1())
    basis = skfem.Basis(m, e)
    K = skfem.asm(linear_elasticity(*lame_parameters(scene.material.E, scene.material.nu)), basis)
    x_max = float(mesh.points[:, 0].max())
    fbasis = skfem.FacetBasis(m, e, facets=m.facets_satisfying(lambda x: x[0] > x_max - 1e-9))
    t = scene.loads[0].value

    @skfem.LinearForm
    def traction(v, w):
        return dot(t, v)

    f = skfem.asm(traction, fbasis)
    D = basis.get_dofs(lambda x: x[0] < 1e-9).all()
    t1 = time.perf_counter()
    u = skfem.solve(*skfem.condense(K, f, D=D))
    t2 = time.perf_counter()
    tip = scene.probes[0]
    u_tip = (tip.bary @ u.reshape(-1, 3)[mesh.tets[tip.tet]]).tolist()
    return {"assembly": t1 - t0, "solve": t2 - t1, "total": t2 - t0, "tip": u_tip}


def bench(
    n_tets: int = 100_000, defaults: bool = True, newton: bool = True, verbose: bool = True
) -> dict:
    """Time the reference FEM on about ``n_tets`` P1 tets, against scikit-fem's defaults.

    Parameters
    ----------
    n_tets
        Target mesh size (a 2k x k x k box, six tets per hexahedron).
    defaults
        Also run scikit-fem's defaults (slow: SuperLU on the full problem).
    newton
        Also time one Newton iteration of the neo-Hookean problem.
    verbose
        Print a short table.

    Returns
    -------
    dict
        Seconds per phase (``fast``, ``skfem_defaults``, ``newton_iteration``), the
        ``speedup`` ``skfem_defaults.total / fast.total`` and the tip displacements.
    """
    import pyamg  # noqa: F401  (import time is not solve time)
    import skfem  # noqa: F401

    from springfem.mechanics import LinearSolver, rigid_body_modes

    from .assembly import BlockPattern, linear_element_blocks
    from .constraints import dirichlet
    from .loads import ExternalLoads
    from .materials import material_groups
    from .problem import FemProblem
    from .solver import solve
    from .space import Space

    scene = bench_scene(n_tets)
    out: dict = {"n_tets": scene.mesh.n_tets, "n_dofs": 3 * scene.mesh.n_points}

    # phases of the fast path, timed separately
    t0 = time.perf_counter()
    space = Space(scene.mesh, 1)
    pattern = BlockPattern(space.element_nodes, space.n_nodes)
    D, group = material_groups(scene.material, scene.frames)
    K = pattern.matrix(linear_element_blocks(space.grads, space.dx, D, group))
    f = ExternalLoads.from_scene(scene, space, follower=False).vector(None)
    bc = dirichlet(scene, space)
    t1 = time.perf_counter()
    solver = LinearSolver("amg", near_nullspace=rigid_body_modes(space.node_coordinates))
    x = solver.solve(K, f, bc.free)
    t2 = time.perf_counter()
    del K, f, bc, space, pattern
    sol = solve(scene)
    t3 = time.perf_counter()
    out["fast"] = {
        "assembly": t1 - t0,
        "solve": t2 - t1,
        "total": t2 - t0,
        "solve_api": t3 - t2,
        "krylov_iterations": solver.stats["krylov_iterations"],
        "tip": sol.result.probes["tip"],
    }
    del x, sol
    if newton:
        problem = FemProblem(scene, 1, law="neo-hookean")
        u = np.zeros(problem.n_dofs)
        t4 = time.perf_counter()
        R, Kt, sym, _ = problem.residual_tangent(u, 1.0)
        t5 = time.perf_counter()
        problem.solve_linear(Kt, -R, sym)
        t6 = time.perf_counter()
        out["newton_iteration"] = {"assemble": t5 - t4, "solve": t6 - t5, "total": t6 - t4}
        del problem, Kt, R
    if defaults:
        out["skfem_defaults"] = _skfem_defaults(scene)
        out["speedup"] = out["skfem_defaults"]["total"] / out["fast"]["total"]
        a, b = np.array(out["fast"]["tip"]), np.array(out["skfem_defaults"]["tip"])
        out["tip_relative_difference"] = float(np.linalg.norm(a - b) / np.linalg.norm(b))
    if verbose:
        _print(out)
    return out


def _print(out: dict, file=sys.stdout) -> None:
    print(f"FEM bench: linear P1, {out['n_tets']} tets, {out['n_dofs']} DOFs", file=file)
    fast = out["fast"]
    print(
        f"  reference_fem   assembly {fast['assembly']:7.2f} s   solve {fast['solve']:7.2f} s"
        f"   total {fast['total']:7.2f} s   (solve() end to end {fast['solve_api']:.2f} s,"
        f" {fast['krylov_iterations']} CG iterations)",
        file=file,
    )
    if "skfem_defaults" in out:
        d = out["skfem_defaults"]
        print(
            f"  skfem defaults  assembly {d['assembly']:7.2f} s   solve {d['solve']:7.2f} s"
            f"   total {d['total']:7.2f} s",
            file=file,
        )
        print(
            f"  speed-up {out['speedup']:.1f}x  (tip displacements differ by "
            f"{out['tip_relative_difference']:.1e} relative)",
            file=file,
        )
    if "newton_iteration" in out:
        n = out["newton_iteration"]
        print(
            f"  neo-Hookean Newton iteration: residual + tangent {n['assemble']:.2f} s, "
            f"AMG solve {n['solve']:.2f} s, total {n['total']:.2f} s",
            file=file,
        )
