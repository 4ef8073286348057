"""``springfem bench threads``: from which mesh size two threads beat one, against the rule.

On bench boxes (:func:`reference_fem.scenes.bench_scene`) of several sizes, in float64: the
spring kernel of the bench scene's variant (the seed element), the exact tissue element
(axis volume, shear torsion, Green axial springs, Poisson coupling) and the explicit P1
neo-Hookean FEM kernel, each serial and on all numba threads. Every case of every size runs
in every round, in a shuffled order (:func:`studies.timing.interleaved`); a timing repeats
the force pass until it covers about :data:`TETS_PER_TIMING` tets. A kernel's speed-up at a
size is the median of its per-round serial/parallel wall-time ratios.

The rule checked is the spring kernel's default (:mod:`springmodel.spring_kernel`: parallel
from ``PARALLEL_MIN_ELEMENTS`` elements when numba has two threads or more): at every size
the rule's choice must be the faster one for every kernel (speed-up above 1 from the
threshold up, not above 1 for some kernel below it). Measure on an idle machine: another
process on a core makes two threads slower than one at every size.

Examples
--------
>>> sizes_up_to(300_000)
[1000, 3000, 10000, 30000, 100000, 300000]
>>> rule_agrees({1000: 0.8, 3000: 1.3}, min_elements=2000)
True
"""

from __future__ import annotations

import numpy as np

from springmodel.options import GREEN_AXIAL_COEFFICIENTS, SpringOptions

from .timing import deformed_state, median, median_ratio, timed

#: Tets per timing (a force pass repeated until about this many): ~10 ms at 20 M tets/s.
TETS_PER_TIMING = 200_000
#: The exact tissue element of the bundled ventricle scene.
TISSUE = SpringOptions(
    volume="axes", torsion="shear", calibration="exact", coupling=True, axial="cubic",
    axial_coefficients=GREEN_AXIAL_COEFFICIENTS, volumetric="log",
)  # fmt: skip


def sizes_up_to(n_tets: int) -> list[int]:
    """Sizes 1k, 3k, 10k, 30k, ... up to ``n_tets`` (at least 1000)."""
    out, k = [], 0
    while True:
        s = (1000, 3000)[k % 2] * 10 ** (k // 2)
        if s > max(n_tets, 1000):
            return out
        out.append(s)
        k += 1


def rule_agrees(speedups: dict[int, float], min_elements: int) -> bool:
    """Whether "parallel from ``min_elements``" picks the faster choice at every size.

    Parameters
    ----------
    speedups
        Size (tets) -> the smallest serial/parallel speed-up over the kernels there.
    min_elements
        The rule's threshold.

    Returns
    -------
    bool
        True when every size at or above the threshold has a speed-up above 1 and every size
        below it a speed-up of at most 1.
    """
    return all((s > 1.0) == (m >= min_elements) for m, s in speedups.items())


def _cases(n_tets: int):
    """``(name, kernel, tets, pass)`` of every kernel at one size, serial and parallel."""
    from reference_fem.explicit import ExplicitFem
    from reference_fem.scenes import bench_scene
    from springmodel.elements import build_spring_elements
    from springmodel.spring_kernel import SpringKernel

    scene = bench_scene(n_tets)
    mesh = scene.mesh
    x = deformed_state(mesh.points)
    out = np.empty_like(x)
    kernels = {"spring seed": SpringOptions.of(scene), "spring tissue": TISSUE}
    for par, threads in ((False, "1"), (True, "all")):
        for label, o in kernels.items():
            el = build_spring_elements(mesh.points, mesh.tets, scene.frames, o, scene.material)
            k = SpringKernel(el, o, parallel=par)
            yield (
                f"{label} {mesh.n_tets} {threads}",
                label,
                mesh.n_tets,
                (lambda k=k: k.forces(x, None, out)),
            )
        fem = ExplicitFem(scene, law="neo-hookean", parallel=par)
        yield (
            f"FEM neo-Hookean {mesh.n_tets} {threads}",
            "FEM neo-Hookean",
            mesh.n_tets,
            (lambda f=fem: f.kernel(x, out)),
        )


def bench_threads(n_tets: int = 300_000, repeats: int = 7) -> dict:
    """Serial and parallel force passes at :func:`sizes_up_to` ``n_tets`` (module docstring).

    Returns
    -------
    dict
        ``rows`` (size, kernel, M tets/s serial and parallel, speed-up, CPU-time ratio),
        ``speedups`` (size -> smallest speed-up over the kernels), the rule, its verdict and
        the machine (load average before and after).
    """
    import numba

    from springmodel import spring_kernel as rule

    cases, meta = {}, {}
    for size in sizes_up_to(n_tets):
        for name, kernel, m, call in _cases(size):
            reps = max(1, round(TETS_PER_TIMING / m))
            cases[name] = lambda c=call, r=reps: [c() for _ in range(r)]
            meta[name] = (kernel, m, reps)
    samples, info = timed(cases, rounds=repeats)
    rows, speedups = [], {}
    for name, (kernel, m, reps) in meta.items():
        if not name.endswith(" 1"):
            continue
        par = name[:-2] + " all"
        speed = median_ratio(samples, name, par)
        rows.append(
            {
                "tets": m,
                "kernel": kernel,
                "mtets_per_s_serial": m * reps / median(samples, name) / 1e6,
                "mtets_per_s_parallel": m * reps / median(samples, par) / 1e6,
                "speedup": speed,
                "cpu_ratio": median_ratio(samples, name, par, "cpu"),
            }
        )
        speedups[m] = min(speedups.get(m, np.inf), speed)
    threads = numba.get_num_threads()
    return {
        "benchmark": "threads",
        "rounds": repeats,
        "rows": rows,
        "speedups": speedups,
        "rule": {
            "parallel_by_default": rule.PARALLEL_BY_DEFAULT,
            "min_elements": rule.PARALLEL_MIN_ELEMENTS,
            "agrees": threads > 1 and rule_agrees(speedups, rule.PARALLEL_MIN_ELEMENTS),
        },
        "machine": info,
    }
