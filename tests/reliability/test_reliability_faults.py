"""Faults at random: a sweep SIGKILLed at random moments, damaged case files, two writers
in one folder, a full disk.

The sweep runs the real :func:`studies.sweep.run_sweep` (folder lock, case cache with
checksums, atomic writes, tables) in a subprocess with a cheap case function whose result
is known here independently (``sqrt(E)``). After every kill each case file must parse, pass
its checksum and hold the right result, and no finished case may be lost; the final rerun
computes exactly the missing cases and writes the table of an uninterrupted run.
"""

from __future__ import annotations

import errno
import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from springfem.errors import InputError, OutputError
from studies.cache import checksum
from studies.sweep import run_sweep
from studies.sweep_file import parse_sweep

ROOT = Path(__file__).resolve().parents[2]
N_CASES = 60

SWEEP = """\
import math, os, sys, time
from pathlib import Path

from studies.sweep import run_sweep
from studies.sweep_file import parse_sweep

out, log = Path(sys.argv[1]), sys.argv[2]
hold = os.environ.get("FAULT_HOLD") == "1"


def work(task):
    E = task["values"]["material.E"]
    with open(log, "a") as fh:  # one short O_APPEND write per started case
        fh.write(f"{E}\\n")
    while hold:  # stands for a long case: the folder stays locked
        time.sleep(1)
    time.sleep(0.01)
    row = {"model": "P1", "status": "ok", "message": "", "value": math.sqrt(E)}
    return {"values": task["values"], "rows": [row], "seconds": 0.01}


spec = parse_sweep(SPEC)
run_sweep(spec, out, progress=False, figures=False, work=work)
"""


def spec_data() -> dict:
    grid = {"material.E": [1000.0 + i for i in range(N_CASES)]}
    return {"scene": "cantilever", "models": ["P1"], "grid": grid}


def start(script: Path, out: Path, log: Path, hold: bool = False) -> subprocess.Popen:
    env = dict(os.environ, PYTHONPATH=str(ROOT), FAULT_HOLD="1" if hold else "0")
    return subprocess.Popen(
        [sys.executable, str(script), str(out), str(log)],
        cwd=ROOT,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )


def finished(out: Path) -> set[float]:
    """The cases with a file; every file parses, passes its checksum and is right."""
    done = set()
    for p in sorted((out / "cases").glob("*.json")) if (out / "cases").is_dir() else []:
        entry = json.loads(p.read_text())  # a half-written file would fail here
        assert entry["sha256"] == checksum(entry["result"]), p
        E = entry["result"]["values"]["material.E"]
        assert entry["result"]["rows"][0]["value"] == math.sqrt(E), p
        done.add(E)
    return done


def started(log: Path) -> list[float]:
    return [float(x) for x in log.read_text().split()] if log.exists() else []


@pytest.fixture(scope="module")
def script(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("sweep") / "sweep_faults.py"
    path.write_text(SWEEP.replace("parse_sweep(SPEC)", f"parse_sweep({spec_data()!r})"))
    return path


@pytest.mark.parametrize(
    "moments", [pytest.param(3, id="3-moments"), pytest.param(20, id="20", marks=pytest.mark.slow)]
)
def test_sweep_killed_at_random_moments_loses_no_finished_case(script, tmp_path, moments):
    out, log = tmp_path / "out", tmp_path / "sweep.log"
    rng = np.random.default_rng(20261202)
    done: set[float] = set()
    kills = 0
    for _ in range(moments):
        n_log = len(started(log))
        proc = start(script, out, log)
        # a random moment once the sweep runs cases (imports take most of a start)
        t_end = time.monotonic() + 120
        while len(started(log)) == n_log and proc.poll() is None and time.monotonic() < t_end:
            time.sleep(0.002)
        time.sleep(float(rng.uniform(0.0, 0.1)))
        if proc.poll() is None:
            proc.send_signal(signal.SIGKILL)
            kills += 1
        proc.wait(timeout=60)
        now = finished(out)
        assert done <= now, "a finished case was lost"
        assert not set(started(log)[n_log:]) & done, "a finished case was computed again"
        done = now
        if len(done) == N_CASES:
            break
    assert kills == moments  # every moment fell inside the sweep
    n_log = len(started(log))
    proc = start(script, out, log)
    assert proc.wait(timeout=300) == 0, proc.stderr.read().decode()
    assert sorted(started(log)[n_log:]) == sorted(set(1000.0 + i for i in range(N_CASES)) - done)
    assert len(finished(out)) == N_CASES
    assert [p for p in out.rglob("*") if ".tmp" in p.name] == []  # leftovers removed
    table = pd.read_csv(out / "results.csv")
    assert np.allclose(table["value"], np.sqrt(table["material.E"]), rtol=0, atol=0)
    assert list(table["material.E"]) == [1000.0 + i for i in range(N_CASES)]


def _tiny_sweep() -> dict:
    return {"scene": "cantilever", "models": ["P1"],
            "grid": {"mesh.divisions": [[4, 1, 1]], "material.nu": [0.3, 0.4]}}  # fmt: skip


def test_damaged_case_files_are_recomputed_with_a_note(tmp_path, capsys):
    spec = parse_sweep(_tiny_sweep())
    first = run_sweep(spec, tmp_path, progress=False, figures=False)
    files = sorted((tmp_path / "cases").glob("*.json"))
    assert len(files) == 2
    text = files[0].read_text()
    files[0].write_text(text[: len(text) // 2])  # truncated
    entry = json.loads(files[1].read_text())
    entry["result"]["rows"][0]["probe:tip:uz"] *= 1.001  # corrupted, still valid JSON
    files[1].write_text(json.dumps(entry))
    capsys.readouterr()
    again = run_sweep(spec, tmp_path, progress=False, figures=False)
    assert (again.computed, again.cached) == (2, 0)
    notes = [line for line in capsys.readouterr().err.splitlines() if "damaged" in line]
    assert len(notes) == 2 and all("computed again" in n for n in notes)
    assert len(list((tmp_path / "cases").glob("*.json.damaged"))) == 2  # kept aside
    cols = [c for c in first.table.columns if c not in ("warm", "wall_time")]  # timings
    pd.testing.assert_frame_equal(again.table[cols], first.table[cols])


@pytest.mark.slow
def test_a_second_sweep_into_a_busy_folder_is_refused(script, tmp_path):
    out, log = tmp_path / "out", tmp_path / "sweep.log"
    proc = start(script, out, log, hold=True)  # holds the folder inside its first case
    try:
        t_end = time.monotonic() + 120
        while not started(log) and proc.poll() is None and time.monotonic() < t_end:
            time.sleep(0.01)
        assert started(log), proc.stderr.read().decode() if proc.poll() is not None else ""
        with pytest.raises(InputError, match=rf"another sweep \(pid {proc.pid}\)") as err:
            run_sweep(parse_sweep(_tiny_sweep()), out, progress=False, figures=False)
        assert "\n" not in str(err.value)
    finally:
        proc.kill()
        proc.wait(timeout=60)
    # the holder is gone: the kernel released its lock
    run = run_sweep(parse_sweep(_tiny_sweep()), out, progress=False, figures=False)
    assert run.computed == 2


def test_a_full_disk_fails_with_one_line_and_keeps_what_was_written(tmp_path, monkeypatch):
    spec = parse_sweep({**_tiny_sweep(), "grid": {"material.nu": [0.3, 0.35, 0.4]}})
    real = os.fsync
    calls = [0]

    def fsync(fd):  # the second case file's write finds the disk full
        calls[0] += 1
        if calls[0] == 2:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        real(fd)

    monkeypatch.setattr(os, "fsync", fsync)
    with pytest.raises(OutputError, match="No space left on device") as err:
        run_sweep(spec, tmp_path, progress=False, figures=False)
    assert "\n" not in str(err.value) and err.value.exit_code == 4
    monkeypatch.setattr(os, "fsync", real)
    files = list((tmp_path / "cases").glob("*.json"))
    assert len(files) == 1 and json.loads(files[0].read_text())["sha256"]  # whole
    assert [p for p in tmp_path.rglob("*") if ".tmp" in p.name] == []  # no half file
    again = run_sweep(spec, tmp_path, progress=False, figures=False)
    assert (again.computed, again.cached) == (2, 1)
