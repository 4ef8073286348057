"""``springfem bench scale``: the fitted laws, the case bookkeeping, and one tiny run.

No timing is asserted (docs/verification.rst#how-speed-is-measured). What is checked: the
log-log fit recovers exponents and coefficients that synthetic data were made with (exactly
without noise, to the noise's size with it); the laws' document has the cost model's exact
shape; a prediction from one or two sizes is what its rule computes by hand; a child's
stage lines are classified as the caps say; a run on two tiny organs with two cheap models
writes its table, figure and JSON with sizes increasing and times positive, and the report
shows that output without re-running it.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from studies.bench_scale import DID_NOT_FIT, CaseResult, classify, predict
from studies.bench_scale_fit import (
    cost_laws_document,
    evaluate,
    largest_tets,
    laws_table,
    model_laws,
    power_law,
)

SIZES = np.array([5e3, 3e4, 1.2e5, 5e5])


@pytest.mark.parametrize("a, b", [(0.3, 1.0), (2.5, 1.5), (4e8, 0.8), (1e-3, 0.37)])
def test_the_fit_recovers_exact_power_laws(a, b):
    got = power_law(SIZES, a * (SIZES / 1e4) ** b)
    assert got == pytest.approx((a, b), rel=1e-10)


def test_the_fit_recovers_exponents_under_noise():
    # 5 % multiplicative noise on 12 sizes over two decades: the exponent's standard error is
    # about 0.05 / (std of log N * sqrt 12) ~ 0.01; 0.05 is five of them
    rng = np.random.default_rng(3)
    n = np.geomspace(2e3, 5e5, 12)
    for b in (0.6, 1.2, 1.9):
        y = 7.0 * (n / 1e4) ** b * np.exp(rng.normal(0, 0.05, n.size))
        a_fit, b_fit = power_law(n, y)
        assert b_fit == pytest.approx(b, abs=0.05)
        assert a_fit == pytest.approx(7.0, rel=0.1)


def test_the_fit_refuses_what_has_no_law():
    with pytest.raises(ValueError, match="two or more"):
        power_law([1e4, 1e4], [1.0, 2.0])
    with pytest.raises(ValueError, match="positive"):
        power_law([1e4, 2e4], [1.0, 0.0])


def test_largest_tets_inverts_the_law():
    law = (3.0e8, 1.1)
    n = largest_tets(law, 24e9)
    assert evaluate(law, n) == pytest.approx(24e9, rel=1e-12)
    assert largest_tets((1.0, -0.2), 5.0) == np.inf


def _case(model, tets, status="ok", static=np.nan, step=np.nan, peak=np.nan, base=2.5e8):
    return {"model": model, "size": tets, "tets": tets, "status": status, "static (s)": static,
            "step (s)": step, "peak memory (bytes)": peak, "baseline (bytes)": base,
            "predicted static (s)": np.nan, "predicted memory (bytes)": np.nan,
            "load average": 1.0, "case wall (s)": 10.0, "message": ""}  # fmt: skip


def _synthetic_cases():
    """Model A: time 2 N^1.3, step 1e-3 N^1, memory 1e8 N^1.05 (N in 1e4 tets) over a
    baseline of 0.1 GB, all solved; model B: static only (no explicit form), solved at two
    sizes, did not fit at the third; model C: its 500k case measured over 24 GB; model D:
    solved at 5k only (its step timed at 30k as well)."""
    rows = []
    for n in SIZES:
        x = n / 1e4
        rows.append(_case("A", n, static=2 * x**1.3, step=1e-3 * x, peak=1e8 * x**1.05,
                          base=1e8))  # fmt: skip
        rows.append(_case("C", n, static=x, peak=1e9 * x))
    for n, status in zip(SIZES[:3], ("ok", "ok", f"{DID_NOT_FIT}: time"), strict=True):
        x = n / 1e4
        solved = status == "ok"
        rows.append(_case("B", n, status, static=5 * x**2 if solved else np.nan,
                          peak=3e9 * x if solved else 9e9))  # fmt: skip
    rows.append(_case("D", 5000, static=4.0, step=1e-3, peak=8e8))
    rows.append(_case("D", 30000, f"{DID_NOT_FIT}: time", step=6e-3, peak=2e9))
    return pd.DataFrame(rows)


def test_laws_of_synthetic_cases_and_the_cost_model_document():
    cases = _synthetic_cases()
    laws = model_laws(cases)
    assert laws["A"]["time"] == pytest.approx((2.0, 1.3))
    assert laws["A"]["step"] == pytest.approx((1e-3, 1.0))
    # A's 5k case (0.05 GB) is under twice the 0.1 GB baseline: the memory law is of the rest
    assert laws["A"]["memory sizes"] == [30000, 120000, 500000]
    assert laws["A"]["memory"] == pytest.approx((1e8, 1.05))
    assert laws["B"]["time"] == pytest.approx((5.0, 2.0))
    assert laws["B"]["step"] is None and laws["B"]["sizes"] == [5000, 30000]
    # D solved one size: its laws have the assumed exponents through that point; its step
    # was timed at two sizes, so it has a fitted step law
    assert laws["D"]["assumed"] == ["time", "memory"]
    assert laws["D"]["step"] == pytest.approx((2e-3, 1.0))
    assert laws["D"]["time"] == pytest.approx((4.0 / 0.5**1.5, 1.5))
    assert laws["D"]["memory"] == pytest.approx((8e8 / 0.5, 1.0))
    aliases = {"spring": "A"}
    doc = json.loads(json.dumps(cost_laws_document(laws, machine="test box", aliases=aliases)))
    assert set(doc) == {"machine", "date", "laws"} and doc["machine"] == "test box"
    assert doc["laws"]["spring"] == doc["laws"]["A"]
    assert doc["laws"]["D"]["sizes"] == [5000]
    assert set(doc["laws"]["A"]) == {"time", "memory", "step", "sizes"}
    assert set(doc["laws"]["B"]) == {"time", "memory", "sizes"}  # no explicit form: no step
    a, b = doc["laws"]["A"]["time"]
    a30 = cases[(cases["model"] == "A") & (cases["tets"] == 3e4)]["static (s)"].item()
    assert a * (3e4 / 1e4) ** b == pytest.approx(a30)
    table = laws_table(laws, cases).set_index("model")
    # A: 1e8 (N/1e4)^1.05 = 24e9 at N = 1e4 * 240^(1/1.05)
    assert table.at["A", "largest in 24 GB (tets)"] == pytest.approx(1e4 * 240 ** (1 / 1.05))
    assert table.at["A", "in 24 GB"].startswith("extrapolated")
    # C measured 50 GB at 500k and 12 GB at 120k: the largest measured under 24 GB
    assert table.at["C", "largest in 24 GB (tets)"] == 120000
    assert table.at["C", "in 24 GB"] == "measured"
    assert table.at["B", "first did not fit (tets)"] == 120000
    assert table.at["B", "largest solved (tets)"] == 30000


def test_prediction_from_one_and_from_two_sizes():
    one = [_case("m", 1e4, static=2.0, peak=6e8, base=2e8)]
    t, m = predict(one, 4e4)  # one size: time N^1.5, memory above the baseline N^1
    assert t == pytest.approx(2.0 * 4**1.5) and m == pytest.approx(2e8 + 4e8 * 4)
    two = one + [_case("m", 4e4, static=2.0 * 4**1.2, peak=2e8 + 4e8 * 4**1.3, base=2e8)]
    t, m = predict(two, 1.6e5)  # two sizes: the fitted exponents 1.2 and 1.3
    assert t == pytest.approx(2.0 * 16**1.2) and m == pytest.approx(2e8 + 4e8 * 16**1.3)
    flat = [_case("m", 1e4, static=2.0, peak=3e8), _case("m", 4e4, static=2.0, peak=3e8)]
    t, _ = predict(flat, 1.6e5)  # a fitted exponent below 1 is raised to 1
    assert t == pytest.approx(2.0 * 4)
    assert all(np.isnan(predict([_case("m", 1e4, status="failed")], 4e4)))


def _result(stages, returncode=0, peak=1e9, killed=False, err=""):
    return CaseResult(stages, returncode, int(peak), killed, err, 1.0)


def test_a_case_is_classified_by_what_its_child_left():
    cap, mem = 100.0, 4e9
    ok = {"ready": {}, "static": {"status": "ok", "seconds": 3.0, "message": ""}}
    assert classify(_result(ok), cap, mem)[0] == "ok"
    capped = {"ready": {}, "static": {"status": "partial", "seconds": 99.5, "message": "x"}}
    assert classify(_result(capped), cap, mem)[0] == f"{DID_NOT_FIT}: time"
    failed = {"ready": {}, "static": {"status": "failed", "seconds": 2.0, "message": "diverged"}}
    assert classify(_result(failed), cap, mem) == ("failed", "diverged")
    caught = {"ready": {}, "static": {"status": "failed", "seconds": 2.0,
                                      "message": "Unable to allocate 3.1 GiB"}}  # fmt: skip
    assert classify(_result(caught), cap, mem)[0] == f"{DID_NOT_FIT}: memory"
    assert classify(_result({"ready": {}}, -9, killed=True), cap, mem)[0] == f"{DID_NOT_FIT}: time"
    memory = {"ready": {}, "error": {"kind": "memory"}}
    assert classify(_result(memory, 4), cap, mem)[0] == f"{DID_NOT_FIT}: memory"
    crashed = _result({"ready": {}}, -11, peak=3.9e9)
    assert classify(crashed, cap, mem)[0] == f"{DID_NOT_FIT}: memory"
    assert classify(_result({"ready": {}}, -11, peak=5e8, err="boom"), cap, mem)[0] == "failed"


def test_a_quick_run_on_tiny_organs_writes_table_figure_and_laws(tmp_path, monkeypatch):
    from studies.cli import main
    from studies.html import write_index
    from studies.runner import write_report

    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "1")
    out, laws_json = tmp_path / "report" / "scale", tmp_path / "cost_laws.json"
    code = main(["bench", "scale", "--sizes", "500,1500", "--models", "P1,mass-spring",
                 "--max-time", "120", "--max-memory", "4", "--out", str(out),
                 "--meshes", str(tmp_path / "meshes"), "--cost-laws", str(laws_json)])  # fmt: skip
    assert code == 0
    cases = pd.read_csv(out / "cases.csv")
    assert sorted(cases["model"].unique()) == ["P1", "mass-spring"]
    for _, rows in cases.groupby("model"):
        assert (rows["status"] == "ok").all()
        assert np.all(np.diff(rows["tets"].to_numpy()) > 0)  # small to large
        assert (rows["static (s)"] > 0).all() and (rows["step (ms)"] > 0).all()
        assert (rows["peak memory (GB)"] >= rows["baseline (GB)"]).all()
        assert (rows["peak memory (GB)"] < 4).all()
    doc = json.loads(laws_json.read_text())
    assert doc == json.loads((out / "cost_laws.json").read_text())
    for name in ("P1", "mass-spring"):
        law = doc["laws"][name]
        assert set(law) == {"time", "memory", "step", "sizes"}
        assert law["sizes"] == sorted(law["sizes"]) and len(law["sizes"]) == 2
        assert law["time"][0] > 0 and law["memory"][0] > 0 and law["step"][0] > 0
    assert (out / "scale.png").stat().st_size > 10_000
    assert len(pd.read_csv(out / "laws.csv")) == 2
    # the report shows it as written: REPORT.md and index.html of the folder above
    write_report([], out.parent, quick=False)
    report = (out.parent / "REPORT.md").read_text()
    assert "## Scale benchmark" in report and "scale/scale.png" in report
    assert "| mass-spring" in report
    page = write_index(out.parent, "t").read_text()
    assert "Scale benchmark" in page and "data:image/png;base64," in page


def test_a_model_stops_at_the_first_size_it_does_not_fit(tmp_path, monkeypatch):
    """Driven by fake cases: ``fast`` solves every size; ``slow`` runs out of time at the
    second size and has its explicit step timed alone at the third; ``broken`` fails at
    the first size and is not run again; ``big`` is predicted over the memory cap."""
    from pathlib import Path

    from studies import bench_scale, bench_scale_output

    calls = []

    def fake_case(scene, name, warmup, max_time, max_memory, step_only=False):
        n = int(Path(scene).stem.split("-")[1])
        calls.append((name, n, step_only))
        stages = {"warmup": {"rss": 2e8}, "ready": {"tets": n}, "step": {"seconds": n * 1e-7}}
        x = n / 1e4
        if name == "broken":
            stages["static"] = {"status": "failed", "seconds": 1.0, "message": "diverged"}
        elif name == "slow" and n > 1000:
            stages["static"] = {"status": "partial", "seconds": max_time, "message": "capped"}
        elif name == "big":
            stages["static"] = {"status": "ok", "seconds": 0.1, "message": ""}
            return CaseResult(stages, 0, int(2e8 + 2e10 * x), False, "", 1.0)
        else:
            stages["static"] = {"status": "ok", "seconds": x, "message": ""}
        if step_only:
            del stages["static"]
        return CaseResult(stages, 0, int(2e8 + 1e8 * x), False, "", 1.0)

    monkeypatch.setattr(bench_scale, "run_case", fake_case)
    monkeypatch.setattr(
        bench_scale, "organ_scene_file", lambda folder, n, cap: tmp_path / f"organ-{n}.toml"
    )
    monkeypatch.setattr(bench_scale_output, "write_outputs", lambda *a, **k: {})
    settings = bench_scale.ScaleSettings(
        sizes=(1000, 4000, 16000),
        models=["fast", "slow", "broken", "big"],
        max_time=10.0,
        max_memory=4e9,
        out=tmp_path,
    )
    cases = bench_scale.bench_scale(settings, log=lambda _line: None).set_index(["model", "size"])
    assert (cases.loc["fast", "status"] == "ok").all()
    assert cases.at[("slow", 4000), "status"] == f"{DID_NOT_FIT}: time"
    assert cases.at[("slow", 16000), "status"] == f"{DID_NOT_FIT}: after a smaller size"
    assert cases.at[("slow", 16000), "step (s)"] == pytest.approx(16000 * 1e-7)
    assert ("slow", 16000, True) in calls  # its step alone
    assert cases.at[("broken", 1000), "status"] == "failed"
    assert cases.at[("broken", 4000), "status"] == "not run: failed at a smaller size"
    assert [c for c in calls if c[0] == "broken"] == [("broken", 1000, False)]
    # big: 2.2 GB at 1k tets over a 0.2 GB baseline: 4k is predicted at 0.2 + 2 * 4 GB,
    # over the 4 GB cap, and not run
    assert cases.at[("big", 4000), "status"] == f"{DID_NOT_FIT}: predicted"
    assert cases.at[("big", 4000), "predicted memory (bytes)"] == pytest.approx(8.2e9)
    assert [c for c in calls if c[0] == "big"] == [("big", 1000, False)]
