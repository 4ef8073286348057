"""Printing of every ``springfem bench`` result: a title, the machine, one table, notes.

Each benchmark's printer names its columns (:func:`print_table`); the machine line
(:func:`machine_line`) is the same for all, so every timing is printed beside the load
average it was measured under.

Examples
--------
>>> _f(None, "6.2f"), _f(1.5, "6.2f")
('     -', '  1.50')
>>> print_table("demo", None, [("case", "name", "<6"), ("ms", lambda r: 1e3 * r["s"], ">6.1f")],
...             [{"name": "a", "s": 0.0123}], notes=["note: one row"])
demo
  case       ms
  a        12.3
  note: one row
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from typing import Any

#: A column: header, the row's key or a function of the row, and its format spec (the
#: header is aligned and padded as the spec's alignment and width say).
Column = tuple[str, str | Callable[[dict], Any], str]


def _f(v, fmt: str) -> str:
    """``v`` formatted, or ``-`` right-aligned to the width of ``fmt``."""
    if v is not None:
        return format(v, fmt)
    width = fmt.lstrip("<>^").split(".")[0].rstrip("dfsegx")
    return format("-", f">{width}") if width.isdigit() else "-"


def machine_line(m: dict) -> str:
    """CPUs, numba threads and the load average before and after the timing."""
    return (
        f"machine: {m.get('cpus')} CPUs, {m.get('numba_threads')} numba threads "
        f"({m.get('threading_layer')}, OMP_WAIT_POLICY {m.get('omp_wait_policy')}); load "
        f"average {m.get('load_average_before', m.get('load_average'))} before, "
        f"{m.get('load_average_after', m.get('load_average'))} after"
    )


def print_table(
    title: str,
    machine: dict | None,
    columns: Sequence[Column],
    rows: Sequence[dict],
    notes: Sequence[str] = (),
    file=None,
    above: Sequence[str] = (),
) -> None:
    """Print ``title``, the machine line, the lines ``above``, the table of ``rows`` and the
    notes on ``file`` (default stdout); a ``None`` cell prints as ``-``."""
    file = file or sys.stdout
    print(title, file=file)
    for line in ([machine_line(machine)] if machine is not None else []) + list(above):
        print(f"  {line}", file=file)
    width = [spec.split(".")[0].rstrip("dfsegx,") for _, _, spec in columns]
    print("  " + " ".join(format(h, w) for (h, _, _), w in zip(columns, width)), file=file)
    for r in rows:
        cells = [_f(get(r) if callable(get) else r[get], spec) for _, get, spec in columns]
        print("  " + " ".join(cells), file=file)
    for note in notes:
        print(f"  {note}", file=file)


def print_forces(res: dict, file=None) -> None:
    """Print a :func:`studies.bench.bench_forces` result."""
    q, notes = res["ratios"], []
    notes.append(
        f"/FEM: median per-round time ratio to the neo-Hookean FEM kernel of the same "
        f"precision and threads (> 1: slower); oracle / specification kernel "
        f"{_f(q.get('oracle_over_seed_float64'), '.1f')}x (kernel == oracle to "
        f"{res['kernel_vs_oracle_max_rel_diff']:.1e})"
    )
    for k, v in q.items():
        if k.startswith("threads_speedup"):
            eff = q.get(f"threads_cpu_efficiency[{k[16:-1]}]")
            notes.append(f"all threads vs one, {k[16:-1]}: {v:.2f}x wall; serial/parallel CPU "
                         f"time {_f(eff, '.2f')} (1 = threads add no work)")  # fmt: skip
    rule = res.get("threads_rule")
    if rule and rule["speedup"] is not None:
        verdict = "agrees" if (rule["speedup"] > 1.0) == rule["default_parallel"] else "DISAGREES"
        notes.append(
            f"threads rule (springmodel.spring_kernel: parallel from {rule['min_elements']} "
            f"elements): {'parallel' if rule['default_parallel'] else 'serial'} at "
            f"{res['n_tets']} tets; measured {rule['speedup']:.2f}x: the rule {verdict}"
        )
    notes += [f"note: {n}" for n in res["notes"]]
    title = (f"bench forces: {res['n_tets']} tets, {res['n_nodes']} nodes, {res['rounds']} "
             f"interleaved rounds; spring options {res['spring_options']}")  # fmt: skip
    above = [
        f"read bandwidth {res['bandwidth_bytes_per_s'] / 1e9:.1f} GB/s (numpy sum of "
        "256 MB); medians over rounds"
    ]
    columns = [("case", "name", "<66"), ("M/s wall", "mtets_per_s_wall", ">8.2f"),
               ("M/s cpu", "mtets_per_s_cpu", ">8.2f"), ("/FEM", "ratio_to_fem", ">6.2f"),
               ("B/el", "bytes_per_element", ">5d"),
               ("limit M/s", "limit_mtets_per_s", ">9.0f")]  # fmt: skip
    print_table(title, res["machine"], columns, res["rows"], notes, file, above)


def print_step(res: dict, file=None) -> None:
    """Print a :func:`studies.bench.bench_step` result."""
    q = res["ratios"]
    columns = [("system", "name", "<40"), ("ms/step", lambda r: 1e3 * r["step_seconds"], ">9.2f"),
               ("forces ms", lambda r: 1e3 * r["forces_seconds"], ">9.2f"),
               ("update ms", lambda r: 1e3 * r["update_seconds"], ">9.2f"),
               ("step/forces", "step_over_forces", ">11.2f"),
               ("M tets/s", "mtets_per_s", ">9.2f")]  # fmt: skip
    print_table(
        f"bench step: {res['n_tets']} tets, {res['n_nodes']} nodes, {res['rounds']} "
        f"interleaved rounds; spring options {res['spring_options']}",
        res["machine"], columns, res["rows"],
        [f"spring / explicit-FEM cost per step: {q['spring_over_fem_serial']:.2f} serial, "
         f"{q['spring_over_fem_parallel']:.2f} parallel (> 1: the spring model is slower); "
         "update = step - forces per round (same round)"], file,
    )  # fmt: skip


def print_threads(res: dict, file=None) -> None:
    """Print a :func:`studies.bench_threads.bench_threads` result."""
    rule = res["rule"]
    columns = [("tets", "tets", ">8"), ("kernel", "kernel", "<18"),
               ("M/s 1 thread", "mtets_per_s_serial", ">12.2f"),
               ("M/s all", "mtets_per_s_parallel", ">9.2f"), ("speed-up", "speedup", ">8.2f"),
               ("CPU 1/all", "cpu_ratio", ">9.2f")]  # fmt: skip
    print_table(
        f"bench threads: {res['rounds']} interleaved rounds, float64", res["machine"], columns,
        res["rows"],
        [f"speed-up: median per-round serial/parallel wall time (> 1: threads faster); rule "
         f"(springmodel.spring_kernel): parallel from {rule['min_elements']} elements "
         f"(default {'on' if rule['parallel_by_default'] else 'off'}): "
         f"{'agrees' if rule['agrees'] else 'DISAGREES'} with the measurement"], file,
    )  # fmt: skip


def print_lockfree(res: dict, file=None) -> None:
    """Print a :func:`studies.bench_lockfree.bench_lockfree` result."""
    ms = ">8.3f"
    columns = [("case", "case", "<44"), ("wall ms", lambda r: 1e3 * r["seconds"], ms),
               ("/ P1-NH step", "over_p1_nh_step", ">12.2f"),
               ("cpu ms", lambda r: 1e3 * r["cpu_seconds"], ms),
               ("/ P1-NH", "cpu_over_p1_nh", ">7.2f")]  # fmt: skip
    notes = ["(cpu / P1-NH: against P1-NH's case of the same kind and threads; parts and FEM "
             "against its serial force pass)"]  # fmt: skip
    if "solves" in res:
        s = res["solves"]
        notes.append(f"static solves, {s['rounds']} interleaved round(s), load average "
                     f"{s['machine'].get('load_average')}:")  # fmt: skip
        notes += [f"  {r['model']:24s} {r['seconds']:9.2f} s {r['over_p1_nh']:8.2f}x "
                  f"{','.join(r['status'])}" for r in s["rows"]]  # fmt: skip
    print_table(
        f"bench lockfree: organ {res['n_tets']:,} tets, {res['n_nodes']:,} nodes; "
        f"{res['rounds']} interleaved rounds of {res['steps_per_timing']} steps; nodal "
        f"strain on {res['virtual_elements']:,} virtual elements"
        f"{' (grouped)' if res['grouped_nodal_strain'] else ''}",
        res["machine"], columns, res["rows"], notes, file,
    )  # fmt: skip


def print_tissue(res: dict, file=None) -> None:
    """Print a :func:`studies.bench_tissue.bench_tissue` result."""
    from .bench_tissue import PHASES, SCENES

    shown = [p for p in (*PHASES, "newton") if any(p in r["phase_seconds"] for r in res["rows"])]
    columns = [
        ("case", lambda r: f"{r['scene']} {r['label']}", "<44"),
        ("dofs", "dofs", ">6"),
        ("its", "iterations", ">4"),
        ("wall s", "wall_seconds", ">7.2f"),
        ("cpu s", "cpu_seconds", ">7.2f"),
        ("/mixed", "ratio_to_mixed", ">6.2f"),
        *((p[:9], lambda r, p=p: r["phase_seconds"].get(p), ">9.2f") for p in shown),
    ]
    notes = [
        "medians over rounds; /mixed: median per-round wall-time ratio to the scene's "
        "P2/P1 mixed solve (> 1: slower); phases: medians of each solve's own phase table"
    ]
    q = res["quadrature"]
    for key, agree in res["agreement"].items():
        notes.append(
            f"NGSolve vs ours, {SCENES[key]}: probes agree to "
            f"{', '.join(f'{k} {v:.1e}' for k, v in agree.items())} (relative); time "
            f"NGSolve/ours {res['ratios'][f'ngsolve_over_ours[{key}]']:.2f} wall, "
            f"{res['ratios'][f'ngsolve_over_ours_cpu[{key}]']:.2f} CPU (tets: degree "
            f"{q['tet_degree']}, {q['tet_points']} points; pressure triangles: degree "
            f"{q['pressure_triangle_degree']}, {q['pressure_triangle_points']} points)"
        )
    print_table(
        f"bench tissue: {res['rounds']} interleaved rounds; beam divisions {res['divisions']}, "
        f"ventricle size {res['size_mm']:g} mm", res["machine"], columns, res["rows"],
        notes + [f"note: {n}" for n in res["notes"]], file,
    )  # fmt: skip
