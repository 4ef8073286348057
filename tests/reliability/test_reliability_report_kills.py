"""Reliability: ``springfem report`` killed with SIGKILL at random moments loses nothing.

A quick report of one real study (``anisotropy``: FEM and spring solves, tables, a figure,
``REPORT.md``, ``index.html`` and the headline JSON) runs in a subprocess that is killed at
3 (the default selection) or 20 (``-m slow``) moments drawn uniformly over an
uninterrupted run's duration (seeded). After every kill each case-cache entry parses as
JSON (none is half-written), every report file that exists is whole, and no entry written
before the kill was written again (a finished case is never redone). A final run then
finishes, leaves no temporary file behind, and its headline numbers and tables equal those
of the uninterrupted run in a fresh folder (an independent run, not a stored value).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[2]
STUDY = "anisotropy"

SCRIPT = f"""\
import sys
from studies.runner import run_report
run_report(sys.argv[1], quick=True, names=({STUDY!r},))
"""


def start(out: Path) -> subprocess.Popen:
    env = dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg", PYVISTA_OFF_SCREEN="true")
    return subprocess.Popen(
        [sys.executable, "-c", SCRIPT, str(out)],
        cwd=ROOT,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )


def run_to_end(out: Path) -> float:
    t0 = time.perf_counter()
    proc = start(out)
    assert proc.wait(timeout=600) == 0, proc.stderr.read().decode()[-2000:]
    return time.perf_counter() - t0


def check_whole(out: Path) -> None:
    """No half-written file: cache entries and JSON outputs parse, REPORT.md is complete."""
    for p in (out / ".cache").rglob("*.json") if (out / ".cache").is_dir() else []:
        json.loads(p.read_text())
    for p in out.rglob("*.json"):
        if ".cache" not in p.parts and ".tmp" not in p.name:
            json.loads(p.read_text())
    report = out / "REPORT.md"
    if report.exists():
        text = report.read_text()
        assert text.startswith("# springfem report") and text.endswith("\n")
    index = out / "index.html"
    if index.exists():
        assert index.read_text().rstrip().endswith("</html>")


def headline(out: Path) -> dict:
    return json.loads((out / "headline-quick.json").read_text())[STUDY]


def entries(out: Path) -> dict[Path, int]:
    """The case-cache entries and their modification times."""
    cache = out / ".cache"
    return {p: p.stat().st_mtime_ns for p in cache.rglob("*.json")} if cache.is_dir() else {}


def tables(out: Path) -> dict[str, pd.DataFrame]:
    """The study's CSV tables, without the columns of measured times."""
    got = {}
    for p in sorted((out / STUDY).glob("*.csv")):
        df = pd.read_csv(p)
        got[p.name] = df[[c for c in df.columns if "time" not in c and "second" not in c]]
    return got


@pytest.mark.parametrize(
    "kills", [pytest.param(3, id="3-kills"), pytest.param(20, id="20", marks=pytest.mark.slow)]
)
def test_report_killed_at_random_moments_resumes_to_the_same_headline(tmp_path, kills):
    reference = tmp_path / "reference"
    duration = run_to_end(reference)
    out = tmp_path / "killed"
    moments = np.random.default_rng(7).uniform(0.0, duration, kills)
    finished_early = 0
    for t in moments:
        before = entries(out)
        proc = start(out)
        try:
            proc.wait(timeout=t)
            finished_early += 1  # the resumed run had less left to do than t
        except subprocess.TimeoutExpired:
            proc.send_signal(signal.SIGKILL)
            proc.wait(timeout=60)
        check_whole(out)
        after = entries(out)
        redone = [p.name for p, m in before.items() if after.get(p) != m]
        assert not redone, f"finished cases computed again: {redone}"
    before = entries(out)
    run_to_end(out)
    assert not [p for p in out.rglob("*") if ".tmp" in p.name], "stale temporary files"
    # the finished cases were read, not recomputed: their entries are untouched
    assert before and all(p.stat().st_mtime_ns == t for p, t in before.items())
    ref, got = headline(reference), headline(out)
    assert set(got) == set(ref)
    for key, value in ref.items():
        assert got[key] == pytest.approx(value, rel=1e-9, abs=1e-12), key
    want, have = tables(reference), tables(out)
    assert set(want) == set(have) and want
    for name, df in want.items():
        pd.testing.assert_frame_equal(have[name], df, check_exact=False, rtol=1e-9)
    assert finished_early < kills  # the kills landed inside a run
