"""``springfem bench forces|fem|step|threads``: kernel speeds, FEM assembly/solve, explicit steps.

Timing rules (:mod:`studies.timing`): every case runs in every round, in a shuffled order;
figures are medians over the rounds of wall and CPU time, ratios are medians of per-round
ratios; the machine's load average is printed beside them (other processes on a shared
machine change every number, docs/verification.rst#how-speed-is-measured).

``forces``
    On a box of about ``--tets`` tets (default 500k), for each precision (``float64``,
    ``mixed``, ``float32``): the spring kernel of the scene's variant and the explicit P1
    neo-Hookean and linear FEM kernels and the anisotropic ones (transverse-linear,
    Guccione, Holzapfel–Ogden with the log penalty, rotated frames), serial and on all
    threads, and the numpy spring oracle; ``--variants`` adds every spring variant (serial)
    and the stiffened exact element (kernel + :mod:`springmodel.stiffening_kernel`,
    float64) with its parts (:mod:`studies.bench_stiffening`). Each kernel's ratio to the
    neo-Hookean FEM kernel of the same precision and threads, its bytes read per element and
    the bandwidth-bound limit (a measured read bandwidth / bytes per element); whether the
    spring kernel's threads rule picks the faster at this size. NVIDIA Warp is timed as a
    peer when installed (it is skipped with a note when not).
``threads``
    :func:`studies.bench_threads.bench_threads`: serial and parallel force passes at sizes
    from 1k tets up to ``--tets``, and whether the kernels' threads rule picks the faster.
``fem``
    :func:`reference_fem.bench`: assembly, solve, scikit-fem defaults, one Newton iteration.
``step``
    One whole explicit step (forces + symplectic-Euler update, through
    :func:`springfem.mechanics.explicit`) against its bare force pass, timed in the
    same round: spring model and explicit FEM, serial and parallel.
"""

from __future__ import annotations

import os

import numpy as np

from reference_fem.explicit_anisotropic import NCOL
from springmodel.options import SpringOptions

from .bench_stiffening import stiffening_parts
from .timing import (
    deformed_state,
    interleaved,
    load_average,
    machine,
    median,
    median_ratio,
    stream_bandwidth,
    timed,
)

# Passive OpenMP waiting (spinning threads steal a shared machine's cores), set before the
# OpenMP runtime starts, unless the user chose.
os.environ.setdefault("OMP_WAIT_POLICY", "passive")

DEFAULT_TETS = {"forces": 500_000, "fem": 100_000, "step": 100_000, "threads": 300_000}
PRECISIONS = ("float64", "mixed", "float32")
#: Explicit steps (and force passes) per timing in ``bench step``.
STEP_COUNT = 10
_FEM_BYTES = {"float64": 10 * 8 + 16, "mixed": 10 * 4 + 16, "float32": 10 * 4 + 16}
#: The anisotropic FEM kernels (reference_fem.explicit_anisotropic): constants per element.
_ANISOTROPIC_FEM = NCOL  # the compiled anisotropic kernels and their constants per element


def anisotropic_fem_scene(scene, law: str):
    """``scene`` with an anisotropic ``law`` (Land's Guccione constants, a Holzapfel–Ogden
    and a transverse material of the same order) and one rotated frame for every element."""
    from dataclasses import replace

    from scipy.spatial.transform import Rotation

    from springfem.scene import Material

    params = {
        "guccione": {"C": 2.0e3, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0, "kappa": 1.0e5},
        "holzapfel-ogden": {"a": 1.0e3, "b": 5.0, "a_f": 2.0e3, "b_f": 5.0, "a_s": 1.0e3,
                            "b_s": 5.0, "a_fs": 0.5e3, "b_fs": 5.0, "kappa": 1.0e5},
    }.get(law, {})  # fmt: skip
    transverse = {"E_fiber": 3.0e4, "E_cross": 1.0e4, "nu_fiber_cross": 0.3, "nu_cross": 0.4,
                  "G_fiber": 5.0e3} if law == "transverse-linear" else {}  # fmt: skip
    mat = Material(law, 1.0e4, 0.3, parameters=params, **transverse)  # type: ignore[arg-type]
    R = Rotation.from_rotvec([0.3, -0.5, 0.7]).as_matrix().T
    return replace(scene, material=mat, frames=np.broadcast_to(R, scene.frames.shape).copy())


def spring_variants() -> list[SpringOptions]:
    """Every spring variant the model has (axial laws x torsion laws, volume forms, damping)."""
    out = []
    for axial in ("linear", "quadratic", "cubic", "stress-scaled"):
        for torsion in ("off", "angle", "cosine", "cubic", "energy"):
            out.append(SpringOptions(axial=axial, torsion=torsion, axial_coefficients=(0.5, 0.5)))
    out.append(SpringOptions(volume_form="spec"))
    out.append(SpringOptions(volume=False))
    out.append(SpringOptions(axial_damping=0.1, volume_damping=0.1))
    for vol in ("quadratic", "log", "simo-taylor"):
        out.append(SpringOptions(torsion="energy", volume="axes", volumetric=vol))
    out.append(SpringOptions(torsion="energy", volume="axes", coupling=True))
    return out


def short_label(o: SpringOptions) -> str:
    """``axial/torsion/volume[/damped]`` of a spring variant, e.g. ``linear/cosine/gradient``."""
    vol = o.volume_form if o.volume is True else (f"axes-{o.volumetric}" if o.volume else "off")
    damped = "/damped" if (o.axial_damping or o.volume_damping) else ""
    coupled = "/coupling" if o.coupling else ""
    return f"{o.axial}/{o.torsion}/{vol}{coupled}{damped}"


def _warp_note() -> str:
    try:
        import warp  # noqa: F401
    except ImportError:
        return "NVIDIA Warp (warp-lang) is not installed: peer kernel skipped"
    return "NVIDIA Warp is installed but its peer kernel is not wired here: skipped"


def _meta(kernel: str, precision: str, threads: str, nbytes: int | None, fem: str) -> dict:
    return {"kernel": kernel, "precision": precision, "threads": threads, "bytes": nbytes,
            "fem": fem}  # fmt: skip


def force_rows(samples: dict, meta: dict, m: int, bandwidth: float) -> list[dict]:
    """One row per timed case: medians, per-round ratio to the FEM kernel of the same
    precision and threads, bytes per element and the bandwidth-bound limit.

    ``meta[name]`` holds ``kernel``, ``precision``, ``threads``, ``bytes`` and ``fem`` (the
    name of the reference case, or ``None``).
    """
    rows = []
    for name, info in meta.items():
        wall, cpu = median(samples, name), median(samples, name, "cpu")
        ref = info.get("fem")
        nbytes = info.get("bytes")
        rows.append(
            {
                "name": name,
                "kernel": info["kernel"],
                "precision": info["precision"],
                "threads": info["threads"],
                "wall_seconds": wall,
                "cpu_seconds": cpu,
                "mtets_per_s_wall": m / wall / 1e6,
                "mtets_per_s_cpu": m / cpu / 1e6 if cpu > 0 else None,
                "ratio_to_fem": median_ratio(samples, name, ref) if ref else None,
                "ratio_to_fem_cpu": median_ratio(samples, name, ref, "cpu") if ref else None,
                "bytes_per_element": nbytes,
                "limit_mtets_per_s": bandwidth / nbytes / 1e6 if nbytes else None,
            }
        )
    return rows


def bench_forces(
    n_tets: int = 500_000,
    repeats: int = 7,
    variants: bool = False,
    precisions: tuple[str, ...] = PRECISIONS,
    threads: tuple[str, ...] = ("1", "all"),
) -> dict:
    """Interleaved force-pass timings of every kernel at every precision (module docstring).

    Returns
    -------
    dict
        ``rows`` (see :func:`force_rows`), ``ratios``, ``machine``, ``bandwidth``, notes.
    """
    from reference_fem.explicit import ExplicitFem
    from reference_fem.scenes import bench_scene
    from springmodel import springs
    from springmodel.elements import build_spring_elements
    from springmodel.model import variant_label
    from springmodel.spring_kernel import PARALLEL_MIN_ELEMENTS as min_par
    from springmodel.spring_kernel import SpringKernel

    scene = bench_scene(n_tets)
    mesh, options = scene.mesh, SpringOptions.of(scene)
    m = mesh.n_tets
    el = build_spring_elements(mesh.points, mesh.tets, scene.frames, options, scene.material)
    x = deformed_state(mesh.points)
    out = np.empty_like(x)
    cases, meta = {}, {}
    for p in precisions:
        for nthreads, par in (("1", False), ("all", True)):
            if nthreads not in threads:
                continue
            fem_name = f"FEM neo-Hookean {p} {nthreads}"
            for law, name in (("neo-hookean", fem_name), ("linear", f"FEM linear {p} {nthreads}")):
                fem = ExplicitFem(scene, law=law, parallel=par, precision=p)
                cases[name] = lambda f=fem: f.kernel(x, out)
                meta[name] = _meta(f"fem-{law}", p, nthreads, _FEM_BYTES[p], fem_name)
            for law, ncol in _ANISOTROPIC_FEM.items():
                name = f"FEM {law} {p} {nthreads}"
                fem = ExplicitFem(anisotropic_fem_scene(scene, law), parallel=par, precision=p)
                cases[name] = lambda f=fem: f.kernel(x, out)
                nbytes = ncol * (8 if p == "float64" else 4) + 16
                meta[name] = _meta(f"fem-{law}", p, nthreads, nbytes, fem_name)
            kernel = SpringKernel(el, options, parallel=par, precision=p)
            name = f"spring {short_label(options)} {p} {nthreads}"
            cases[name] = lambda k=kernel: k.forces(x, None, out)
            label = f"spring[{short_label(options)}]"
            meta[name] = _meta(label, p, nthreads, kernel.bytes_per_element, fem_name)
        if variants:
            for o in spring_variants():
                els = build_spring_elements(mesh.points, mesh.tets, scene.frames, o, scene.material)
                kernel = SpringKernel(els, o, parallel=False, precision=p)
                v = np.zeros_like(x) if o.axial_damping or o.volume_damping else None
                name = f"spring {short_label(o)} {p} 1 (variant)"
                cases[name] = lambda k=kernel, v=v: k.forces(x, v, out)
                meta[name] = _meta(f"spring[{short_label(o)}]", p, "1",
                                   kernel.bytes_per_element, f"FEM neo-Hookean {p} 1")  # fmt: skip
    if variants and "float64" in precisions:
        for name, call, info in stiffening_parts(scene, mesh, x, out):
            cases[name], meta[name] = call, info
    cases["spring numpy oracle"] = lambda: springs.internal_forces(x, None, el, options)
    meta["spring numpy oracle"] = _meta("spring-oracle", "float64", "1", None,
                                        "FEM neo-Hookean float64 1")  # fmt: skip
    bandwidth = stream_bandwidth()
    load_before = load_average()
    samples = interleaved(cases, rounds=repeats)
    rows = force_rows(samples, meta, m, bandwidth)
    by = {r["name"]: r for r in rows}
    f_oracle = springs.internal_forces(x, None, el, options)
    f_kernel = SpringKernel(el, options, parallel=False).forces(x)
    seed = f"spring {short_label(options)} float64 1"
    pairs = [(n.replace(" all", " 1"), n) for n in meta if n.endswith(" all")]
    pairs = [(one, n) for one, n in pairs if one in samples]
    ratios = {f"threads_speedup[{n}]": median_ratio(samples, one, n) for one, n in pairs}
    for one, n in pairs:  # serial CPU time / parallel CPU time: 1 = threads add no work
        ratios[f"threads_cpu_efficiency[{n}]"] = median_ratio(samples, one, n, "cpu")
    if seed in samples:
        ratios["oracle_over_seed_float64"] = median_ratio(samples, "spring numpy oracle", seed)
    info = machine(load_before)
    rule = {"default_parallel": SpringKernel(el, options).parallel, "min_elements": min_par}
    rule["speedup"] = ratios.get(f"threads_speedup[{seed[:-2]} all]")
    return {
        "benchmark": "forces",
        "threads_rule": rule,
        "n_tets": m,
        "n_nodes": mesh.n_points,
        "rounds": repeats,
        "spring_options": variant_label(options),
        "bandwidth_bytes_per_s": bandwidth,
        "rows": rows,
        "ratios": ratios,
        "kernel_vs_oracle_max_rel_diff": float(
            np.abs(f_kernel - f_oracle).max() / np.abs(f_oracle).max()
        ),
        "seed_row": by.get(seed),
        "notes": [_warp_note()],
        "machine": info,
    }


class WithoutEnergy:
    """A system seen without its energy, so a timed explicit run records none (the spring
    model's energy is a numpy oracle, several force passes' worth)."""

    def __init__(self, system):
        self._system = system

    def __getattr__(self, name):
        return getattr(self._system, name)

    def energy(self, x: np.ndarray, scale: float = 1.0) -> None:
        return None


def explicit_steps(system, steps: int = STEP_COUNT) -> None:
    """Run ``steps`` explicit steps (symplectic Euler, through the solver), no energies.

    A step is what :func:`springfem.mechanics.explicit` does per step: one force evaluation,
    the velocity and position updates, constraints, the blow-up check and ``post_step``.
    The time step is tiny (the state barely moves, so no run can blow up); the cost of a
    step does not depend on it. Time it with :func:`studies.timing.interleaved`.
    """
    from springfem.mechanics import explicit

    explicit(WithoutEnergy(system), dt=1e-9, steps=steps, record_every=steps)


def step_costs(systems: dict, steps: int, rounds: int) -> dict:
    """Interleaved timings of ``steps`` explicit steps of every system (bench's rules).

    Returns
    -------
    dict
        :func:`studies.timing.interleaved` samples; divide by ``steps`` for per-step times.
    """
    cases = {name: (lambda s=s: explicit_steps(s, steps)) for name, s in systems.items()}
    return interleaved(cases, rounds=rounds, warmup=1)


def step_and_force_cases(systems: dict, x, steps: int = STEP_COUNT) -> dict:
    """``<name>: step`` (``steps`` explicit steps) and ``<name>: forces`` (as many bare force
    passes at ``x``) of every system, to time in the same rounds."""
    cases = {}
    for name, s in systems.items():
        cases[f"{name}: step"] = lambda s=s: explicit_steps(s, steps)
        cases[f"{name}: forces"] = lambda s=s: [s.forces(x, None, 1.0) for _ in range(steps)]
    return cases


def bench_step(n_tets: int = 100_000, repeats: int = 5, steps: int = STEP_COUNT) -> dict:
    """A whole explicit step against its bare force pass, both timed in every round."""
    from reference_fem.explicit import ExplicitFem
    from reference_fem.scenes import bench_scene
    from springmodel.model import SpringModel, variant_label

    scene = bench_scene(n_tets)
    m = scene.mesh.n_tets
    systems = {
        "spring model, serial": SpringModel(scene, parallel=False),
        "spring model, parallel": SpringModel(scene, parallel=True),
        "explicit P1 FEM neo-Hookean, serial": ExplicitFem(scene, parallel=False),
        "explicit P1 FEM neo-Hookean, parallel": ExplicitFem(scene, parallel=True),
    }
    cases = step_and_force_cases(systems, deformed_state(scene.mesh.points), steps)
    samples, info = timed(cases, rounds=repeats)
    rows = []
    for name in systems:
        st, fo = f"{name}: step", f"{name}: forces"
        step = median(samples, st) / steps
        update = np.asarray(samples[st]["wall"]) - np.asarray(samples[fo]["wall"])
        rows.append(
            {
                "name": name,
                "step_seconds": step,
                "forces_seconds": median(samples, fo) / steps,
                "update_seconds": float(np.median(update)) / steps,
                "step_cpu_seconds": median(samples, st, "cpu") / steps,
                "step_over_forces": median_ratio(samples, st, fo),
                "mtets_per_s": m / step / 1e6,
            }
        )
    sp = "spring model, {}: step"
    fe = "explicit P1 FEM neo-Hookean, {}: step"
    return {
        "benchmark": "step",
        "n_tets": m,
        "n_nodes": scene.mesh.n_points,
        "rounds": repeats,
        "spring_options": variant_label(systems["spring model, serial"].options),
        "steps_per_timing": steps,
        "rows": rows,
        "ratios": {
            "spring_over_fem_serial": median_ratio(
                samples, sp.format("serial"), fe.format("serial")
            ),
            "spring_over_fem_parallel": median_ratio(
                samples, sp.format("parallel"), fe.format("parallel")
            ),
        },
        "machine": info,
    }
