"""``springfem bench forces|fem|step``: kernel speeds, FEM assembly/solve, explicit steps.

``forces``
    On a box of about ``--tets`` tets (default 500k): median throughput (tets/s) of the fused
    spring kernel (:class:`springmodel.kernels.ForceKernel`, parallel and serial), of the numpy
    oracle (:func:`springmodel.springs.internal_forces`, fewer repeats: it is slow) and of the
    explicit P1 neo-Hookean kernel (:class:`reference_fem.explicit.ExplicitFem`), with the
    ratios measured in this one run.
``fem``
    :func:`reference_fem.bench`: assembly, solve, scikit-fem defaults, one Newton iteration.
``step``
    One whole explicit step (forces + symplectic-Euler update, through
    :func:`springfem.mechanics.explicit`) of a 100k-tet scene, spring model and
    explicit FEM.

Speeds are compared only as ratios measured in the same run (DESIGN §8); the machine's load
average is printed because other processes on a shared machine change every number.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

from springmodel.options import SpringOptions

# OpenMP's default (active) wait makes threads spin at every barrier; on a machine shared
# with other processes a spinning thread waits for a descheduled peer, and the colour-ordered
# kernels (one barrier per colour) ran 10-20x slower than serial here. Passive waiting is set
# before the OpenMP runtime starts (the first parallel kernel call), unless the user chose.
os.environ.setdefault("OMP_WAIT_POLICY", "passive")

DEFAULT_TETS = {"forces": 500_000, "fem": 100_000, "step": 100_000}
#: Explicit steps timed per repeat in ``bench step``.
STEP_COUNT = 10


def machine() -> dict:
    """Threads, numba threading layer and load average: the context of every timing."""
    import numba

    try:
        layer = numba.threading_layer()
    except ValueError:  # no parallel function has run yet
        layer = "not initialised"
    return {
        "cpus": os.cpu_count(),
        "numba_threads": numba.get_num_threads(),
        "threading_layer": layer,
        "omp_wait_policy": os.environ.get("OMP_WAIT_POLICY", "default"),
        "load_average": [round(v, 2) for v in os.getloadavg()],
    }


def timed(fn, repeats: int = 5, warmup: int = 1, count: int = 1) -> tuple[float, float]:
    """Median wall and CPU (process) seconds of ``count`` calls of ``fn()``, divided by
    ``count``, over ``repeats`` runs after ``warmup`` runs.

    On a busy machine the wall time includes the time the process waited for a core; the
    CPU time does not (for a serial code it is the cost of the work itself; for a parallel
    one it is the sum over its threads, spinning included).
    """
    for _ in range(warmup):
        fn()
    wall, cpu = [], []
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        for _ in range(count):
            fn()
        wall.append((time.perf_counter() - w0) / count)
        cpu.append((time.process_time() - c0) / count)
    return float(np.median(wall)), float(np.median(cpu))


def _state(points: np.ndarray, seed: int = 0) -> np.ndarray:
    """A deformed state: a smooth stretch plus noise of 1 % of the mesh spacing."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    h = float(np.min(hi - lo)) / max(2.0, round((points.shape[0]) ** (1 / 3)))
    rng = np.random.default_rng(seed)
    x = points * np.array([1.02, 0.99, 0.995])
    return x + 0.01 * h * rng.standard_normal(points.shape)


def bench_forces(n_tets: int = 500_000, repeats: int = 7, oracle_repeats: int | None = None):
    """Median time of one internal-force evaluation of each kernel on one mesh.

    Returns
    -------
    dict
        ``rows`` (name, seconds, tets/s), ``ratios`` and ``setup`` times, ``machine``.
    """
    from reference_fem.explicit import ExplicitFem
    from reference_fem.scenes import bench_scene
    from springmodel import springs
    from springmodel.elements import build_spring_elements
    from springmodel.kernels import ForceKernel
    from springmodel.model import variant_label

    t0 = time.perf_counter()
    scene = bench_scene(n_tets)
    mesh, options = scene.mesh, SpringOptions.of(scene)
    m = mesh.n_tets
    t1 = time.perf_counter()
    elements = build_spring_elements(mesh.points, mesh.tets, scene.frames, options, scene.material)
    t2 = time.perf_counter()
    spring_par = ForceKernel(elements, options, parallel=True)
    spring_ser = ForceKernel(elements, options, parallel=False)
    t3 = time.perf_counter()
    fem_par = ExplicitFem(scene, parallel=True)
    fem_ser = ExplicitFem(scene, parallel=False)
    fem_lin = ExplicitFem(scene, law="linear", parallel=True)
    t4 = time.perf_counter()
    x = _state(mesh.points)
    out = np.empty_like(x)
    oracle_repeats = oracle_repeats or max(1, repeats // 3)

    cases = [
        ("spring kernel, parallel", lambda: spring_par.forces(x, None, out), repeats),
        ("spring kernel, serial", lambda: spring_ser.forces(x, None, out), repeats),
        (
            "spring numpy oracle",
            lambda: springs.internal_forces(x, None, elements, options),
            oracle_repeats,
        ),
        ("explicit P1 FEM neo-Hookean, parallel", lambda: fem_par.kernel(x, out), repeats),
        ("explicit P1 FEM neo-Hookean, serial", lambda: fem_ser.kernel(x, out), repeats),
        ("explicit P1 FEM linear, parallel", lambda: fem_lin.kernel(x, out), repeats),
    ]
    load_before = os.getloadavg()[0]
    rows = []
    for name, fn, r in cases:
        sec, cpu = timed(fn, repeats=r)
        rows.append(
            {"name": name, "seconds": sec, "cpu_seconds": cpu, "tets_per_s": m / sec, "repeats": r}
        )
    t = {r["name"]: r["seconds"] for r in rows}
    c = {r["name"]: r["cpu_seconds"] for r in rows}
    # the kernels compute the same forces as their references (a sanity check, not timing)
    f_oracle = springs.internal_forces(x, None, elements, options)
    f_kernel = spring_par.forces(x, None)
    diff_spring = float(np.abs(f_kernel - f_oracle).max() / np.abs(f_oracle).max())
    ratios = {
        "fused_parallel_over_oracle": t["spring numpy oracle"] / t["spring kernel, parallel"],
        "fused_serial_over_oracle": t["spring numpy oracle"] / t["spring kernel, serial"],
        "parallel_speedup_spring": t["spring kernel, serial"] / t["spring kernel, parallel"],
        "parallel_speedup_fem": (
            t["explicit P1 FEM neo-Hookean, serial"] / t["explicit P1 FEM neo-Hookean, parallel"]
        ),
        "spring_over_fem_parallel": (
            t["spring kernel, parallel"] / t["explicit P1 FEM neo-Hookean, parallel"]
        ),
        "spring_over_fem_serial": (
            t["spring kernel, serial"] / t["explicit P1 FEM neo-Hookean, serial"]
        ),
        "spring_over_fem_serial_cpu": (
            c["spring kernel, serial"] / c["explicit P1 FEM neo-Hookean, serial"]
        ),
    }
    info = machine()
    info["load_average_during"] = round(0.5 * (load_before + os.getloadavg()[0]), 2)
    return {
        "benchmark": "forces",
        "n_tets": m,
        "n_nodes": mesh.n_points,
        "spring_options": variant_label(options),
        "scatter": {"spring": spring_par.scatter, "fem": fem_par.scatter},
        "setup_seconds": {
            "mesh": t1 - t0,
            "spring_elements": t2 - t1,
            "spring_kernels": t3 - t2,
            "fem_kernels": t4 - t3,
        },
        "rows": rows,
        "ratios": ratios,
        "kernel_vs_oracle_max_rel_diff": diff_spring,
        "machine": info,
    }


class WithoutEnergy:
    """A system seen without its energy, so a timed explicit run records none.

    The solver evaluates the potential energy at the first and last step of a run; the
    spring model's energy is a numpy oracle (several force evaluations' worth), which
    would otherwise be charged to a handful of timed steps.
    """

    def __init__(self, system):
        self._system = system

    def __getattr__(self, name):
        return getattr(self._system, name)

    def energy(self, x: np.ndarray, scale: float = 1.0) -> None:
        return None


def step_time(system, steps: int = STEP_COUNT, repeats: int = 5) -> tuple[float, float]:
    """Median wall and CPU seconds per explicit step (symplectic Euler, through the solver).

    A step is what :func:`springfem.mechanics.explicit` does per step: one force evaluation,
    the velocity and position updates, constraints, the kinetic energy and blow-up check and
    ``post_step``. The time step is tiny (the state barely moves, so no run can blow up);
    the cost of a step does not depend on it. No energies are recorded.
    """
    from springfem.mechanics import explicit

    plain = WithoutEnergy(system)
    wall, cpu = timed(lambda: explicit(plain, dt=1e-9, steps=steps, record_every=steps), repeats)
    return wall / steps, cpu / steps


def bench_step(n_tets: int = 100_000, repeats: int = 5, steps: int = STEP_COUNT) -> dict:
    """Cost of one whole explicit step: spring model and explicit P1 FEM on one scene."""
    from reference_fem.explicit import ExplicitFem
    from reference_fem.scenes import bench_scene
    from springmodel.model import SpringModel, variant_label

    scene = bench_scene(n_tets)
    m = scene.mesh.n_tets
    t0 = time.perf_counter()
    systems = {
        "spring model, parallel": SpringModel(scene, parallel=True),
        "spring model, serial": SpringModel(scene, parallel=False),
    }
    t1 = time.perf_counter()
    systems["explicit P1 FEM neo-Hookean, parallel"] = ExplicitFem(scene, parallel=True)
    systems["explicit P1 FEM neo-Hookean, serial"] = ExplicitFem(scene, parallel=False)
    t2 = time.perf_counter()
    x = _state(scene.mesh.points)
    load_before = os.getloadavg()[0]
    rows = []
    for name, system in systems.items():
        step, step_cpu = step_time(system, steps, repeats)
        forces, forces_cpu = timed(lambda s=system: s.forces(x, None, 1.0), repeats, count=steps)
        rows.append(
            {
                "name": name,
                "step_seconds": step,
                "forces_seconds": forces,
                "update_seconds": step - forces,
                "step_cpu_seconds": step_cpu,
                "forces_cpu_seconds": forces_cpu,
                "tets_per_s": m / step,
            }
        )
    t = {r["name"]: r["step_seconds"] for r in rows}
    c = {r["name"]: r["step_cpu_seconds"] for r in rows}
    info = machine()
    info["load_average_during"] = round(0.5 * (load_before + os.getloadavg()[0]), 2)
    return {
        "benchmark": "step",
        "n_tets": m,
        "n_nodes": scene.mesh.n_points,
        "spring_options": variant_label(systems["spring model, serial"].options),
        "steps_per_repeat": steps,
        "setup_seconds": {"spring_model": t1 - t0, "explicit_fem": t2 - t1},
        "rows": rows,
        "ratios": {
            "spring_over_fem_parallel": t["spring model, parallel"]
            / t["explicit P1 FEM neo-Hookean, parallel"],
            "spring_over_fem_serial": t["spring model, serial"]
            / t["explicit P1 FEM neo-Hookean, serial"],
            "spring_over_fem_serial_cpu": c["spring model, serial"]
            / c["explicit P1 FEM neo-Hookean, serial"],
        },
        "machine": info,
    }


# ------------------------------------------------------------------------------ printing


def _header(res: dict, what: str, file) -> None:
    mach = res["machine"]
    load = mach["load_average_during"]
    busy = "  [busy machine: timings are noisy]" if load > (mach["cpus"] or 1) else ""
    print(
        f"{what}: {res['n_tets']} tets, {res['n_nodes']} nodes; spring options "
        f"{res['spring_options']}",
        file=file,
    )
    print(
        f"  machine: {mach['cpus']} CPUs, {mach['numba_threads']} numba threads "
        f"({mach['threading_layer']}, OMP_WAIT_POLICY {mach['omp_wait_policy']}), "
        f"load average {load} during the run{busy}",
        file=file,
    )


def print_forces(res: dict, file=None) -> None:
    file = file or sys.stdout
    _header(res, "bench forces", file)
    base = next(r for r in res["rows"] if r["name"] == "spring numpy oracle")["seconds"]
    print(
        f"  {'kernel':<40} {'ms/eval':>9} {'M tets/s':>9} {'vs oracle':>9} {'cpu ms':>9}",
        file=file,
    )
    for r in res["rows"]:
        print(
            f"  {r['name']:<40} {1e3 * r['seconds']:>9.2f} {r['tets_per_s'] / 1e6:>9.2f} "
            f"{base / r['seconds']:>8.1f}x {1e3 * r['cpu_seconds']:>9.2f}",
            file=file,
        )
    q = res["ratios"]
    print(
        f"  fused / oracle speed-up: {q['fused_parallel_over_oracle']:.1f}x parallel, "
        f"{q['fused_serial_over_oracle']:.1f}x serial (kernel == oracle to "
        f"{res['kernel_vs_oracle_max_rel_diff']:.1e})",
        file=file,
    )
    print(
        f"  spring / explicit-FEM cost per force evaluation: "
        f"{q['spring_over_fem_parallel']:.2f} parallel, {q['spring_over_fem_serial']:.2f} serial, "
        f"{q['spring_over_fem_serial_cpu']:.2f} serial CPU time (> 1: the spring kernel is slower)",
        file=file,
    )
    print(
        f"  parallel speed-up on {res['machine']['numba_threads']} threads: spring "
        f"{q['parallel_speedup_spring']:.2f}x, FEM {q['parallel_speedup_fem']:.2f}x "
        f"(scatter: spring {res['scatter']['spring']}, FEM {res['scatter']['fem']})",
        file=file,
    )


def print_step(res: dict, file=None) -> None:
    file = file or sys.stdout
    _header(res, "bench step", file)
    print(
        f"  {'system':<40} {'ms/step':>9} {'forces ms':>9} {'update ms':>9} {'M tets/s':>9} "
        f"{'cpu ms/step':>11}",
        file=file,
    )
    for r in res["rows"]:
        print(
            f"  {r['name']:<40} {1e3 * r['step_seconds']:>9.2f} "
            f"{1e3 * r['forces_seconds']:>9.2f} {1e3 * r['update_seconds']:>9.2f} "
            f"{r['tets_per_s'] / 1e6:>9.2f} {1e3 * r['step_cpu_seconds']:>11.2f}",
            file=file,
        )
    q = res["ratios"]
    print(
        f"  spring / explicit-FEM cost per step: {q['spring_over_fem_parallel']:.2f} parallel, "
        f"{q['spring_over_fem_serial']:.2f} serial, {q['spring_over_fem_serial_cpu']:.2f} serial "
        f"CPU time (> 1: the spring model is slower)",
        file=file,
    )


def cmd_bench(args: argparse.Namespace) -> int:
    """Entry point of ``springfem bench``."""
    from springfem.errors import InputError

    what = args.what
    n = args.tets if args.tets is not None else DEFAULT_TETS[what]
    repeats = int(getattr(args, "repeats", 7) or 7)
    if n < 6:
        raise InputError(f"--tets must be at least 6, got {n}")
    if repeats < 1:
        raise InputError(f"--repeats must be at least 1, got {repeats}")
    as_json = bool(getattr(args, "json", False))
    if what == "forces":
        res = bench_forces(n, repeats)
        if not as_json:
            print_forces(res)
    elif what == "step":
        res = bench_step(n, repeats)
        if not as_json:
            print_step(res)
    elif what == "fem":
        from reference_fem import bench
        from reference_fem.bench import _print as print_fem

        res = bench(n, verbose=False)
        res["machine"] = machine()
        if not as_json:
            print_fem(res, file=sys.stdout)  # its default stream is bound at import time
            print(f"  machine load average {res['machine']['load_average']}")
    else:  # argparse restricts the choices
        raise InputError(f"unknown benchmark {what!r}; valid: forces, fem, step")
    if as_json:
        from springfem.files import jsonable as _jsonable

        print(json.dumps(_jsonable(res), indent=2, sort_keys=True))
    return 0
