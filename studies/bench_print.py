"""Printing of ``springfem bench forces|step|threads`` results (:mod:`studies.bench`).

Examples
--------
>>> _f(None, "6.2f"), _f(1.5, "6.2f")
('-', '  1.50')
"""

from __future__ import annotations

import sys


def _header(res: dict, what: str, file) -> None:
    mach = res["machine"]
    print(
        f"{what}: {res['n_tets']} tets, {res['n_nodes']} nodes, {res['rounds']} interleaved "
        f"rounds; spring options {res['spring_options']}",
        file=file,
    )
    print(
        f"  machine: {mach['cpus']} CPUs, {mach['numba_threads']} numba threads "
        f"({mach['threading_layer']}, OMP_WAIT_POLICY {mach['omp_wait_policy']}); load "
        f"average {mach['load_average_before']} before, {mach['load_average_after']} after",
        file=file,
    )


def _f(v, fmt):
    return format(v, fmt) if v is not None else "-"


def print_forces(res: dict, file=None) -> None:
    """Print a :func:`studies.bench.bench_forces` result as a table on ``file`` (default stdout)."""
    file = file or sys.stdout
    _header(res, "bench forces", file)
    bw = res["bandwidth_bytes_per_s"] / 1e9
    print(f"  read bandwidth {bw:.1f} GB/s (numpy sum of 256 MB); medians over rounds", file=file)
    print(
        f"  {'case':<66} {'M/s wall':>8} {'M/s cpu':>8} {'/FEM':>6} {'B/el':>5} {'limit M/s':>9}",
        file=file,
    )
    for r in res["rows"]:
        print(
            f"  {r['name']:<66} {r['mtets_per_s_wall']:>8.2f} {_f(r['mtets_per_s_cpu'], '8.2f')} "
            f"{_f(r['ratio_to_fem'], '6.2f')} {_f(r['bytes_per_element'], '5d')} "
            f"{_f(r['limit_mtets_per_s'], '9.0f')}",
            file=file,
        )
    q = res["ratios"]
    print(
        f"  /FEM: median per-round time ratio to the neo-Hookean FEM kernel of the same "
        f"precision and threads (> 1: slower); oracle / specification kernel "
        f"{_f(q.get('oracle_over_seed_float64'), '.1f')}x (kernel == oracle to "
        f"{res['kernel_vs_oracle_max_rel_diff']:.1e})",
        file=file,
    )
    for k, v in q.items():
        if k.startswith("threads_speedup"):
            eff = q.get(f"threads_cpu_efficiency[{k[16:-1]}]")
            print(
                f"  all threads vs one, {k[16:-1]}: {v:.2f}x wall; serial/parallel CPU time "
                f"{_f(eff, '.2f')} (1 = threads add no work)",
                file=file,
            )
    rule = res.get("threads_rule")
    if rule and rule["speedup"] is not None:
        faster = rule["speedup"] > 1.0
        verdict = "agrees" if faster == rule["default_parallel"] else "DISAGREES"
        print(
            f"  threads rule (springmodel.spring_kernel: parallel from {rule['min_elements']} "
            f"elements): {'parallel' if rule['default_parallel'] else 'serial'} at "
            f"{res['n_tets']} tets; measured {rule['speedup']:.2f}x: the rule {verdict}",
            file=file,
        )
    for note in res["notes"]:
        print(f"  note: {note}", file=file)


def print_step(res: dict, file=None) -> None:
    """Print a :func:`studies.bench.bench_step` result as a table on ``file`` (default stdout)."""
    file = file or sys.stdout
    _header(res, "bench step", file)
    print(
        f"  {'system':<40} {'ms/step':>9} {'forces ms':>9} {'update ms':>9} "
        f"{'step/forces':>11} {'M tets/s':>9}",
        file=file,
    )
    for r in res["rows"]:
        print(
            f"  {r['name']:<40} {1e3 * r['step_seconds']:>9.2f} "
            f"{1e3 * r['forces_seconds']:>9.2f} {1e3 * r['update_seconds']:>9.2f} "
            f"{r['step_over_forces']:>11.2f} {r['mtets_per_s']:>9.2f}",
            file=file,
        )
    q = res["ratios"]
    print(
        f"  spring / explicit-FEM cost per step: {q['spring_over_fem_serial']:.2f} serial, "
        f"{q['spring_over_fem_parallel']:.2f} parallel (> 1: the spring model is slower); "
        f"update = step - forces per round (same round)",
        file=file,
    )


def print_threads(res: dict, file=None) -> None:
    """Print a :func:`studies.bench_threads.bench_threads` result as a table on ``file``
    (default stdout)."""
    file = file or sys.stdout
    mach = res["machine"]
    print(
        f"bench threads: {res['rounds']} interleaved rounds, float64; {mach['cpus']} CPUs, "
        f"{mach['numba_threads']} numba threads ({mach['threading_layer']}, OMP_WAIT_POLICY "
        f"{mach['omp_wait_policy']}); load average {mach['load_average_before']} before, "
        f"{mach['load_average_after']} after",
        file=file,
    )
    print(
        f"  {'tets':>8} {'kernel':<18} {'M/s 1 thread':>12} {'M/s all':>9} {'speed-up':>8} "
        f"{'CPU 1/all':>9}",
        file=file,
    )
    for r in res["rows"]:
        print(
            f"  {r['tets']:>8} {r['kernel']:<18} {r['mtets_per_s_serial']:>12.2f} "
            f"{r['mtets_per_s_parallel']:>9.2f} {r['speedup']:>8.2f} {r['cpu_ratio']:>9.2f}",
            file=file,
        )
    rule = res["rule"]
    print(
        f"  speed-up: median per-round serial/parallel wall time (> 1: threads faster); rule "
        f"(springmodel.spring_kernel): parallel from {rule['min_elements']} elements "
        f"(default {'on' if rule['parallel_by_default'] else 'off'}): "
        f"{'agrees' if rule['agrees'] else 'DISAGREES'} with the measurement",
        file=file,
    )
