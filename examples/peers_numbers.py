"""The numbers of docs/peers.rst#xpbd-bias and docs/peers.rst#measured, from one run.

    .venv/bin/python examples/peers_numbers.py

XPBD's rest state against P1 and P2 neo-Hookean on the same mesh as substeps and iterations
grow (a 60 Hz frame; coupled, auto damping, rest_tol 1e-7, at most 3,000 frames), the edge
mass-spring network's Newton answer, and the cost of one XPBD substep (one iteration) against
one explicit P1 neo-Hookean force pass (medians of interleaved rounds,
:func:`studies.timing.interleaved`). A shared machine: ratios from one run, not constants.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from peers.plugin import models as peer_models
from peers.xpbd import XPBD, StableNeoHookean, XPBDSettings
from reference_fem.explicit import ExplicitFem
from reference_fem.scenes import bench_scene
from springfem.errors import SolverError
from springfem.mechanics import static
from springfem.mechanics.limits import solve_limits
from springfem.scene import load_scene, scene_from_dict
from studies import metrics, models
from studies.timing import interleaved, median


def scene_rows(scene, grid, jacobi=()):
    """XPBD errors against P1-NH and P2-NH, the network's, times."""
    with solve_limits(max_time=600.0):
        ref = {n: models.run(scene, n) for n in ("P1-NH", "P2-NH")}
        ref = {n: models.run(scene, n) for n in ("P1-NH", "P2-NH")}  # timed after warm-up
    print(f"\n{scene.name} ({scene.mesh.n_tets} tets); P1-NH {ref['P1-NH'].seconds:.2f} s, "
          f"P2-NH {ref['P2-NH'].seconds:.2f} s; P1-NH vs P2-NH rel L2 "
          f"{metrics.relative_l2_error(ref['P1-NH'].u, ref['P2-NH'].u):.3e}")  # fmt: skip
    print(f"  {'model':<34} {'vs P1-NH':>9} {'vs P2-NH':>9} {'seconds':>8} {'frames':>7}")
    rows = []
    cases = [("gauss-seidel", n, k) for n, k in grid] + [("jacobi", n, k) for n, k in jacobi]
    for it, n, k in cases:
        name = f"xpbd {it} {n} substeps x {k}"
        try:
            XPBD(scene, XPBDSettings(substeps=n, iterations=k, iteration=it, max_frames=10)).solve()
            settings = XPBDSettings(
                substeps=n, iterations=k, iteration=it, rest_tol=1e-7, max_frames=3_000
            )
            out = XPBD(scene, settings).solve()
        except SolverError as exc:
            print(f"  {name:<34} {exc}")
            continue
        e1 = metrics.relative_l2_error(out.u, ref["P1-NH"].u)
        e2 = metrics.relative_l2_error(out.u, ref["P2-NH"].u)
        print(f"  {name:<34} {e1:9.2e} {e2:9.2e} {out.wall_time:8.2f} {out.frames:7d}"
              f"{'' if out.converged else '  (no rest)'}")  # fmt: skip
        rows.append((name, e1, e2, out.wall_time))
    ms = peer_models()[1]
    ms.solve(scene)
    got = ms.solve(scene)
    e1 = metrics.relative_l2_error(got.u, ref["P1-NH"].u)
    e2 = metrics.relative_l2_error(got.u, ref["P2-NH"].u)
    print(f"  {'mass-spring (Newton)':<34} {e1:9.2e} {e2:9.2e} {got.result.wall_time:8.2f}")
    return rows


def substep_cost() -> None:
    print("\none XPBD substep (1 iteration) vs one explicit P1 neo-Hookean force pass,")
    print("medians of 7 interleaved rounds of 20:")
    scene = bench_scene(50_000)
    fem = ExplicitFem(scene, law="neo-hookean")
    x_f = fem.x0 * 1.001
    one = {"substeps": 1, "iterations": 1, "damping": 0.0}
    solvers = {
        it: XPBD(scene, XPBDSettings(iteration=it, **one)) for it in ("gauss-seidel", "jacobi")
    }
    states = {it: s.start() for it, s in solvers.items()}
    a = {it: s.accelerations(s.x0) for it, s in solvers.items()}

    def xpbd(it):
        def go():
            for _ in range(20):
                solvers[it].advance(*states[it], a[it])

        return go

    def force():
        for _ in range(20):
            fem.internal(x_f)

    cases = {"P1 neo-Hookean force": force, **{f"xpbd {it}": xpbd(it) for it in solvers}}
    for go in cases.values():
        go()
    samples = interleaved(cases, rounds=7)
    base = median(samples, "P1 neo-Hookean force")
    m = scene.mesh.n_tets
    for k in cases:
        t = median(samples, k) / 20
        print(f"  {k:<22} {1e3 * t:7.3f} ms ({m / t / 1e6:5.1f} M tets/s), "
              f"{median(samples, k) / base:4.2f}x the force pass")  # fmt: skip


def gmsh_cantilever(path: Path, size: float = 0.01) -> None:
    """An unstructured gmsh box 0.1 x 0.02 x 0.02 m (the one of tests/peers)."""
    import gmsh

    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("box")
        gmsh.model.occ.addBox(0, 0, 0, 0.1, 0.02, 0.02)
        gmsh.model.occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMin", size)
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.model.addPhysicalGroup(3, [1], name="body")
        gmsh.model.mesh.generate(3)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()


def gmsh_convergence() -> None:
    """XPBD's rest state against the Newton answer of its own energy on a gmsh cantilever
    sagging under gravity (docs/peers.rst#xpbd-bias)."""
    path = Path(tempfile.mkdtemp()) / "box.msh"
    gmsh_cantilever(path)
    scene = scene_from_dict({
        "mesh": {"file": str(path)},
        "material": {"law": "neo-hookean", "E": 1e4, "nu": 0.3, "density": 1000.0},
        "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
        "load": [{"type": "gravity", "value": [0.0, 0.0, -9.81]}],
    })  # fmt: skip
    system = StableNeoHookean(scene)
    u = static(system, tol=1e-11).x - system.x0
    sag = -u[:, 2].min() / 0.1
    print(f"\ngmsh cantilever ({scene.mesh.n_tets} tets), tip sag / length {sag:.2f}")
    print("  max-norm error against Newton on the same energy:")

    def err(**settings):
        out = XPBD(scene, XPBDSettings(rest_tol=1e-9, **settings)).solve()
        return np.abs(out.u - u).max() / np.abs(u).max()

    n = np.array([10, 20, 40, 80])
    e = np.array([err(substeps=int(k), iterations=2) for k in n])
    print("  substeps x 2: " + ", ".join(f"{k}: {v:.2e}" for k, v in zip(n, e)))
    print(f"  rate over 20-80: {-np.polyfit(np.log(n[1:]), np.log(e[1:]), 1)[0]:.2f}")
    its = {k: err(substeps=10, iterations=k) for k in (1, 2, 4, 16)}
    print("  10 substeps, iterations: " + ", ".join(f"{k}: {v:.3e}" for k, v in its.items()))
    print(f"  40 x 2 sequential {err(substeps=40, iterations=2, coupling='sequential'):.2e}, "
          f"jacobi {err(substeps=40, iterations=2, iteration='jacobi'):.2e}")  # fmt: skip


def main() -> None:
    t0 = time.perf_counter()
    gmsh_convergence()
    grid = [(n, 2) for n in (10, 20, 40, 80)] + [(20, k) for k in (1, 4, 8)]
    rows = scene_rows(load_scene("cantilever-large-rotation"), grid, jacobi=[(20, 2), (40, 2)])
    n = np.array([10, 20, 40, 80])
    e = np.array([r[1] for r in rows[:4]])
    print(f"  rate in substeps (vs P1-NH, polyfit of the last 3): "
          f"{-np.polyfit(np.log(n[1:]), np.log(e[1:]), 1)[0]:.2f}")  # fmt: skip
    scene_rows(load_scene("sag"), [(n, 2) for n in (10, 40)], jacobi=[(40, 2)])
    substep_cost()
    print(f"\n({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
