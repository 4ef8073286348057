"""``springfem bench``: output structure, interleaving, ratio arithmetic (no timing asserts).

docs/verification.rst#how-speed-is-measured: timings are never asserted. What is checked: every case
runs once in every
round and the rounds are shuffled; medians and per-round ratios are computed from injected
fake timings as written by hand here; the benchmarks run on a tiny mesh, print their rows
and machine load, and their JSON holds every figure; the timed kernel equals the oracle.
"""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from studies import bench, bench_print
from studies.cli import main
from studies.timing import interleaved, median, median_difference, median_ratio


def fake_clock(durations):
    """A clock that advances by the given durations at every second reading."""
    t = itertools.count()
    state = {"now": 0.0, "d": iter(durations)}

    def clock():
        if next(t) % 2:  # the reading after a case: advance by its duration
            state["now"] += next(state["d"])
        return state["now"]

    return clock


def test_every_case_runs_once_per_round_in_shuffled_orders():
    calls = []
    cases = {n: (lambda n=n: calls.append(n)) for n in "abcde"}
    res = interleaved(cases, rounds=6, warmup=0, seed=1)
    assert len(calls) == 30
    rounds = [calls[5 * r : 5 * r + 5] for r in range(6)]
    assert all(sorted(r) == list("abcde") for r in rounds)  # each case once per round
    assert len({tuple(r) for r in rounds}) > 1  # the order changes between rounds
    for n in "abcde":
        assert [r.index(n) for r in rounds] == res[n]["order"]
        assert len(res[n]["wall"]) == len(res[n]["cpu"]) == 6


def test_ratios_are_medians_of_per_round_ratios():
    # round r (fixed order a, b): a takes A[r], b takes Bt[r]
    A = [1.0, 2.0, 4.0, 1.0, 8.0]
    Bt = [3.0, 2.0, 20.0, 2.0, 8.0]
    durations = [d for pair in zip(A, Bt, strict=True) for d in pair]
    cases = {"a": lambda: None, "b": lambda: None}
    res = interleaved(
        cases,
        rounds=5,
        warmup=0,
        seed=None,
        clock=fake_clock(durations),
        cpu_clock=fake_clock([2 * d for d in durations]),
    )
    assert res["a"]["wall"] == A and res["b"]["wall"] == Bt
    assert median(res, "a") == 2.0 and median(res, "b", "cpu") == 2 * 3.0
    # per-round ratios 3, 1, 5, 2, 1 -> median 2; the ratio of medians would be 3/2
    assert median_ratio(res, "b", "a") == 2.0
    assert median_ratio(res, "b", "a", "cpu") == 2.0
    assert median_difference(res, "b", "a") == 1.0  # differences 2, 0, 16, 1, 0


def test_force_rows_arithmetic():
    samples = {
        "fem": {"wall": [2.0, 2.0, 4.0], "cpu": [1.0, 1.0, 1.0]},
        "spring": {"wall": [3.0, 5.0, 4.0], "cpu": [2.0, 2.0, 2.0]},
    }
    meta = {
        "fem": {
            "kernel": "fem",
            "precision": "float64",
            "threads": "1",
            "bytes": 100,
            "fem": "fem",
        },
        "spring": {
            "kernel": "s",
            "precision": "float64",
            "threads": "1",
            "bytes": 200,
            "fem": "fem",
        },
    }
    rows = {r["name"]: r for r in bench.force_rows(samples, meta, m=1_000_000, bandwidth=1e10)}
    s = rows["spring"]
    assert s["mtets_per_s_wall"] == pytest.approx(1 / 4.0)  # median wall 4 s for 1 M tets
    assert s["mtets_per_s_cpu"] == pytest.approx(1 / 2.0)
    assert s["ratio_to_fem"] == pytest.approx(1.5)  # per-round 1.5, 2.5, 1.0
    assert s["limit_mtets_per_s"] == pytest.approx(1e10 / 200 / 1e6)
    assert rows["fem"]["ratio_to_fem"] == 1.0


@pytest.fixture(scope="module")
def forces_result():
    # float64 and serial only: the structure is the same for every precision and thread
    # count, and the parallel drivers are compiled per process (slow on a shared machine)
    return bench.bench_forces(200, repeats=2, precisions=("float64",), threads=("1",))


def test_bench_forces_structure(forces_result, capsys):
    res = forces_result
    names = {r["name"] for r in res["rows"]}
    assert {
        "FEM neo-Hookean float64 1",
        "FEM linear float64 1",
        "FEM transverse-linear float64 1",
        "FEM guccione float64 1",
        "FEM holzapfel-ogden float64 1",
        "spring linear/cosine/gradient float64 1",
        "spring numpy oracle",
    } == names
    by = {r["name"]: r for r in res["rows"]}
    assert by["FEM guccione float64 1"]["bytes_per_element"] == 10 * 8 + 16  # as isotropic
    assert by["FEM transverse-linear float64 1"]["bytes_per_element"] == 19 * 8 + 16
    for r in res["rows"]:
        assert r["wall_seconds"] > 0 and r["ratio_to_fem"] > 0
    seed = res["seed_row"]
    assert seed["bytes_per_element"] == 20 * 8 + 16
    assert seed["limit_mtets_per_s"] == pytest.approx(res["bandwidth_bytes_per_s"] / 176 / 1e6)
    assert res["kernel_vs_oracle_max_rel_diff"] < 1e-12
    assert any("Warp" in n for n in res["notes"])
    assert len(res["machine"]["load_average_before"]) == 3
    bench_print.print_forces(res)
    out = capsys.readouterr().out
    for text in ("interleaved rounds", "load average", "read bandwidth", "limit M/s", "Warp"):
        assert text in out, text
    json.dumps(res)  # every figure is JSON-serialisable


def test_bench_step_update_timed_in_the_same_round(capfd):
    assert main(["bench", "step", "--tets", "200", "--repeats", "2"]) == 0
    out = capfd.readouterr().out
    assert "spring model, serial" in out and "explicit P1 FEM neo-Hookean, serial" in out
    assert "step/forces" in out and "same round" in out


def test_bench_fem_and_bad_size(capfd):
    assert main(["bench", "fem", "--tets", "200"]) == 0
    out = capfd.readouterr().out
    assert "FEM bench" in out and "Newton iteration" in out
    assert main(["bench", "forces", "--tets", "0"]) == 2
    assert "--tets" in capfd.readouterr().err


def test_variants_cover_every_law():
    opts = bench.spring_variants()
    assert {o.axial for o in opts} == {"linear", "quadratic", "cubic", "stress-scaled"}
    assert {o.torsion for o in opts} == {"off", "angle", "cosine", "cubic", "energy"}
    assert {o.volume_form for o in opts if o.volume} == {"gradient", "spec"}
    assert any(not o.volume for o in opts) and any(o.volume_damping for o in opts)
    assert np.unique([bench.short_label(o) for o in opts]).size == len(opts)


def test_threads_rule_verdict_and_sizes():
    from studies.bench_threads import rule_agrees, sizes_up_to

    assert sizes_up_to(100_000) == [1000, 3000, 10000, 30000, 100000]
    assert sizes_up_to(10) == [1000]
    speed = {1000: 0.7, 3000: 0.95, 10000: 1.2, 30000: 1.6}  # threads win from 10k up
    assert rule_agrees(speed, 5000) and rule_agrees(speed, 10000)
    assert not rule_agrees(speed, 20000)  # serial at 10k, where threads were faster
    assert not rule_agrees(speed, 2000)  # parallel at 3k, where they were slower


def test_print_threads_names_the_rule_and_its_verdict(capsys):
    from studies.bench_print import print_threads

    mach = {"cpus": 2, "numba_threads": 2, "threading_layer": "omp", "omp_wait_policy": "p"}
    mach.update(load_average_before=[0.1, 0.1, 0.1], load_average_after=[0.2, 0.1, 0.1])
    row = {"tets": 1000, "kernel": "spring seed", "mtets_per_s_serial": 20.0,
           "mtets_per_s_parallel": 30.0, "speedup": 1.5, "cpu_ratio": 0.9}  # fmt: skip
    res = {"rounds": 3, "rows": [row], "machine": mach,
           "rule": {"parallel_by_default": True, "min_elements": 500, "agrees": True}}  # fmt: skip
    print_threads(res)
    out = capsys.readouterr().out
    for text in ("load average [0.1, 0.1, 0.1]", "spring seed", "1.50", "parallel from 500",
                 "agrees"):  # fmt: skip
        assert text in out, text
