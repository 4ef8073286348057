"""The numbers of docs/plugins.rst#co-rotational-p1-measured, from one run.

    .venv/bin/python examples/corotational_numbers.py

Static solves (each model warmed up once on the same scene, then timed), the consistent
tangent against the warped stiffness, and the cost of one explicit force pass against the
explicit P1 FEM's kernels (medians of interleaved rounds, :func:`studies.timing.interleaved`).
Timings are from a shared machine: ratios from one run, not constants.
"""

from __future__ import annotations

import time

import numpy as np

from reference_fem.explicit import ExplicitFem
from reference_fem.scenes import bench_scene
from springfem.mechanics import stable_time_step
from springfem.mechanics.limits import solve_limits
from springfem.scene import load_scene
from studies import metrics, models
from studies.overrides import load_scene_with
from studies.timing import interleaved, median


def static_rows(scene, names, reference, cap=300.0):
    """Error against ``reference``, wall time (second solve) and iterations per model."""
    got = {}
    for n in names:
        with solve_limits(max_time=cap):
            models.run(scene, n)  # warm-up: compiled kernels, imports
            got[n] = models.run(scene, n)
    u_ref = got[reference].u
    print(f"\n{scene.name} ({scene.mesh.n_tets} tets), errors against {reference}:")
    for n, o in got.items():
        err = metrics.relative_l2_error(o.u, u_ref) if o.ok else float("nan")
        its = o.solution.result.iterations if o.ok else "-"
        tip = o.solution.result.probes.get("tip", [np.nan] * 3)[2] if o.ok else np.nan
        print(f"  {n:<20} {o.status:<8} rel L2 {err:9.2e}  tip uz {tip:10.4e}  "
              f"{o.seconds:7.2f} s  {its} iterations")  # fmt: skip
    return got


def main() -> None:
    big = load_scene("cantilever-large-rotation")
    names = ["P1", "P1-NH", "corotational", "corotational-warped", "P2-NH"]
    rows = static_rows(big, names, "P1-NH")
    e = metrics.relative_l2_error(rows["corotational"].u, rows["P2-NH"].u)
    e1 = metrics.relative_l2_error(rows["P1-NH"].u, rows["P2-NH"].u)
    print(f"  against P2-NH: corotational {e:.3f}, P1-NH {e1:.3f}")
    mild = load_scene_with(
        "studies/scenes/cantilever-large-rotation.toml", ["load.0.value=[0, 0, -1.0]"]
    )
    static_rows(mild, ["P1-NH", "corotational", "corotational-warped"], "P1-NH")
    small = load_scene("cantilever")
    static_rows(small, ["P1", "corotational", "P2"], "P1")

    for law in ("linear", "transverse-linear"):  # FD check at a random state, one number each
        scene = small if law == "linear" else load_scene("stretch-cross")
        print(f"\n{law}: rigid rotation, max |f| / max |f(1 % strain)|:", end=" ")
        s = models.get("corotational").system(scene)
        from scipy.spatial.transform import Rotation

        Q = Rotation.from_rotvec([0.4, 1.1, -0.7]).as_matrix()
        rng = np.random.default_rng(0)
        ref = np.abs(s.internal(s.x0 * (1 + 0.01 * rng.standard_normal(s.x0.shape)))).max()
        print(f"{np.abs(s.internal(s.x0 @ Q.T)).max() / ref:.1e}")

    print("\nexplicit force pass, medians of 7 interleaved rounds of 20 passes:")
    scene = bench_scene(50_000)
    systems = {
        "corotational": models.get("corotational").system(scene),
        "P1 linear": ExplicitFem(scene, law="linear"),
        "P1 neo-Hookean": ExplicitFem(scene, law="neo-hookean"),
    }
    x = {k: s.x0 * 1.001 for k, s in systems.items()}

    def runner(k):
        s = systems[k]

        def go():
            for _ in range(20):
                s.internal(x[k])

        return go

    for k in systems:
        runner(k)()
    t0 = time.perf_counter()
    samples = interleaved({k: runner(k) for k in systems}, rounds=7)
    base = median(samples, "P1 neo-Hookean")
    m = next(iter(systems.values())).n_elements
    for k in systems:
        t = median(samples, k) / 20
        print(f"  {k:<16} {1e3 * t:7.3f} ms/pass ({m / t / 1e6:5.1f} M tets/s), "
              f"{median(samples, k) / base:4.2f}x P1 neo-Hookean")  # fmt: skip
    dts = {k: stable_time_step(s)[0] for k, s in systems.items()}
    print("  stable step at rest, corotational / P1 neo-Hookean: "
          f"{dts['corotational'] / dts['P1 neo-Hookean']:.3f}")  # fmt: skip
    print(f"  ({time.perf_counter() - t0:.1f} s)")


if __name__ == "__main__":
    main()
