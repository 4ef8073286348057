"""Reliability: a study killed with SIGKILL resumes without losing or redoing work.

A tiny study (:class:`studies.cache.CaseCache` + :func:`studies.tables.write_table`, the
mechanism every study uses) runs in a subprocess that is killed three times:

1. while case ``BLOCK_AT`` is computing (the case waits forever);
2. inside an atomic write, after the data and before the rename (``os.fsync`` hangs);
3. at an arbitrary moment of a free run (most of whose time goes to the atomic writes, so
   the kill usually lands in one).

After each kill every cache entry must parse and hold the right result (no half-written
file). A final rerun must compute exactly the cases without an entry, remove the
temporary files the killed writers left, and write tables byte-identical to those of an
uninterrupted run in a fresh folder.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from springfem.files import atomic_write_text, remove_stale_temp_files

ROOT = Path(__file__).resolve().parents[2]
N_CASES = 40
BLOCK_AT = 12

STUDY = """\
import math, os, sys, time
from pathlib import Path

import pandas as pd

from studies.cache import CaseCache
from studies.tables import write_table

root, log = Path(sys.argv[1]), sys.argv[2]
block_at = int(os.environ.get("RESUME_BLOCK_AT", "-1"))
block_write = int(os.environ.get("RESUME_BLOCK_WRITE", "-1"))
if block_write >= 0:  # the block_write-th file write hangs between data and rename
    real_fsync, calls = os.fsync, [0]

    def fsync(fd):
        if calls[0] == block_write:
            Path(log + ".writing").touch()
            while True:
                time.sleep(1)
        calls[0] += 1
        real_fsync(fd)

    os.fsync = fsync
cases = [{"study": "resume", "n": i, "h": 1.0 / (i + 1)} for i in range(N)]


def work(case):
    with open(log, "a") as fh:  # one short O_APPEND write per started case
        fh.write(f"{case['n']}\\n")
    if case["n"] == block_at:
        while True:  # stands for a long case: killed here
            time.sleep(1)
    h = case["h"]
    value = math.fsum(math.sin(k * h) / (k + 1) for k in range(500))
    return {"n": case["n"], "h": h, "value": value, "series": [h, h * h, math.nan]}


results = CaseCache(root / ".cache", "resume").run(cases, work, progress=False)
rows = [{"n": r["n"], "h": r["h"], "value": r["value"]} for r in results]
write_table(pd.DataFrame(rows), root / "resume" / "table")
""".replace("N)", f"{N_CASES})")


def expected(n: int) -> dict:
    """The result of case ``n``, computed here independently of the cache."""
    import math

    h = 1.0 / (n + 1)
    value = math.fsum(math.sin(k * h) / (k + 1) for k in range(500))
    return {"n": n, "h": h, "value": value, "series": [h, h * h, None]}  # NaN -> null


def start(script: Path, root: Path, log: Path, block_at=-1, block_write=-1) -> subprocess.Popen:
    env = dict(
        os.environ,
        RESUME_BLOCK_AT=str(block_at),
        RESUME_BLOCK_WRITE=str(block_write),
        PYTHONPATH=str(ROOT),
    )
    return subprocess.Popen(
        [sys.executable, str(script), str(root), str(log)],
        cwd=ROOT,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )


def entries(root: Path) -> list[Path]:
    d = root / ".cache" / "resume"
    return sorted(d.glob("*.json")) if d.is_dir() else []


def wait_for(proc: subprocess.Popen, cond, what: str, timeout: float = 120.0) -> None:
    t_end = time.monotonic() + timeout
    while not cond():
        if proc.poll() is not None:
            raise AssertionError(f"study exited ({proc.returncode}) before {what}")
        if time.monotonic() > t_end:
            proc.kill()
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.002)


def log_lines(log: Path) -> list[int]:
    return [int(x) for x in log.read_text().split()] if log.exists() else []


def check_entries(root: Path) -> set[int]:
    """Every cache entry parses and holds the right result; returns the finished cases."""
    done = set()
    for p in entries(root):
        data = json.loads(p.read_text())  # a half-written file would fail here
        n = data["case"]["n"]
        assert data["result"] == expected(n), p
        done.add(n)
    return done


def temp_files(root: Path) -> list[Path]:
    return [p for p in root.rglob("*") if ".tmp" in p.name]


@pytest.fixture(scope="module")
def script(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("study") / "study_resume.py"
    path.write_text(STUDY)
    return path


def test_killed_study_resumes_without_recomputing(script, tmp_path):
    root, log = tmp_path / "killed", tmp_path / "killed.log"

    # 1. killed while case BLOCK_AT computes: cases before it are finished and kept
    proc = start(script, root, log, block_at=BLOCK_AT)
    wait_for(proc, lambda: BLOCK_AT in log_lines(log), f"case {BLOCK_AT} to start")
    proc.send_signal(signal.SIGKILL)
    assert proc.wait(timeout=60) == -signal.SIGKILL
    assert check_entries(root) == set(range(BLOCK_AT))

    # 2. killed inside the atomic write of the third case it finishes: the data is in a
    #    temporary file, the entry itself does not exist (not half of it)
    proc = start(script, root, log, block_write=2)
    writing = Path(str(log) + ".writing")
    wait_for(proc, writing.exists, "the blocked write")
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=60)
    tmp = temp_files(root)
    assert len(tmp) == 1 and tmp[0].read_text().startswith("{")
    assert check_entries(root) == set(range(BLOCK_AT + 2))  # its case has no entry yet

    # 3. a free run, killed at an arbitrary moment (usually inside an atomic write; on a
    #    very busy machine the run may even finish first, which must be fine too)
    n_log = len(log_lines(log))
    proc = start(script, root, log)
    t_end = time.monotonic() + 120
    while len(log_lines(log)) <= n_log + 3 and proc.poll() is None and time.monotonic() < t_end:
        time.sleep(0.002)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=60)
    second = log_lines(log)[n_log:]
    assert second and not set(second) & set(range(BLOCK_AT)), "finished cases recomputed"
    done = check_entries(root)
    assert set(range(BLOCK_AT)) <= done <= set(range(N_CASES))

    # 4. the rerun computes exactly the missing cases and cleans up
    n_log = len(log_lines(log))
    proc = start(script, root, log)
    assert proc.wait(timeout=300) == 0, proc.stderr.read().decode()
    third = log_lines(log)[n_log:]
    assert sorted(third) == sorted(set(range(N_CASES)) - done)
    assert check_entries(root) == set(range(N_CASES))
    assert temp_files(root) == []

    # 5. the tables equal those of an uninterrupted run, byte for byte
    fresh, fresh_log = tmp_path / "fresh", tmp_path / "fresh.log"
    proc = start(script, fresh, fresh_log)
    assert proc.wait(timeout=300) == 0, proc.stderr.read().decode()
    assert log_lines(fresh_log) == list(range(N_CASES))
    for ext in ("csv", "md"):
        table = root / "resume" / f"table.{ext}"
        assert table.read_bytes() == (fresh / "resume" / f"table.{ext}").read_bytes()


def test_stale_temp_files_of_dead_writers_are_removed(tmp_path):
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        check=True,
        capture_output=True,
        text=True,
    )
    dead_pid = int(dead.stdout)  # that process has exited
    live_pid = os.getpid()
    names = {
        f".table.csv.abc123.{dead_pid}.tmp": False,
        f".fig.{dead_pid}.tmp.png": False,
        f"result.vtu.tmp-{dead_pid}.vtu": False,
        f".table.csv.xyz789.{live_pid}.tmp": True,  # a live writer's file is kept
        "table.csv": True,
        "notes.tmp.txt": True,  # not a writer's temporary file
    }
    for name in names:
        (tmp_path / name).write_text("x")
    removed = remove_stale_temp_files(tmp_path)
    assert sorted(p.name for p in removed) == sorted(n for n, keep in names.items() if not keep)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(n for n, k in names.items() if k)


def test_atomic_write_leaves_old_content_when_the_writer_fails(tmp_path, monkeypatch):
    target = tmp_path / "a.json"
    target.write_text("old")

    def boom(fd):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", boom)
    with pytest.raises(OSError):
        atomic_write_text(target, "new content")
    assert target.read_text() == "old" and list(tmp_path.iterdir()) == [target]
