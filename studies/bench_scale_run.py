"""One case of ``springfem bench scale`` in a child process under caps, and what it left.

:func:`run_case` starts :mod:`studies.bench_scale_case` under a memory cap (``RLIMIT_AS``)
and a time cap, reads its stage lines and its peak RSS (``os.wait4``: that child's alone);
:func:`classify` says what the case came to (solved, failed, or did not fit in time or
memory); :func:`organ_scene_file` makes an organ mesh of the family once, in a child under
the same memory cap.
"""

from __future__ import annotations

import contextlib
import os
import resource
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from .bench_scale_fit import SOLVED

#: Seconds a case may take to start, warm up and load its mesh beyond its time cap, and
#: to time its explicit step and stop after the cap.
SETUP_SECONDS = 180.0
GRACE_SECONDS = 60.0
#: The status of a case that did not fit (``: time``, ``: memory``, ``: predicted``).
DID_NOT_FIT = "did not fit"


def organ_scene_file(folder: Path, tets: int, max_memory: float) -> Path:
    """The organ scene of about ``tets`` tets in ``folder`` (made in a child process under
    the memory cap when it is not there yet).

    Parameters
    ----------
    folder
        The meshes folder.
    tets
        Tets asked for.
    max_memory
        Bytes of address space gmsh may use.

    Returns
    -------
    Path
    """
    folder = Path(folder)
    path = folder / f"organ-{tets}.toml"
    if path.exists() and (folder / f"organ-{tets}.msh").exists():
        return path
    folder.mkdir(parents=True, exist_ok=True)
    code = (
        "import sys; from springfem.mesh.organ import organ_scene; "
        "organ_scene(sys.argv[1], tets=int(sys.argv[2]))"
    )
    subprocess.run([sys.executable, "-c", code, str(folder), str(tets)], env=_child_env(),
                   check=True, preexec_fn=_limit(max_memory), timeout=1800)  # fmt: skip
    return path


def _child_env() -> dict[str, str]:
    """The environment of a child: this checkout first on the path, one BLAS thread."""
    env = dict(os.environ)
    root = str(Path(__file__).resolve().parents[1])
    env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
    env.setdefault("OPENBLAS_NUM_THREADS", "1")
    env.setdefault("OMP_WAIT_POLICY", "passive")
    env.setdefault("MPLBACKEND", "Agg")
    return env


def _limit(max_memory: float) -> Callable[[], None]:
    def set_limit() -> None:
        cap = int(max_memory)
        resource.setrlimit(resource.RLIMIT_AS, (cap, cap))

    return set_limit


@dataclass
class CaseResult:
    """What :func:`run_case` got from the child: its stage lines, exit, peak RSS, and whether
    it was stopped for time."""

    stages: dict[str, dict]
    returncode: int
    peak_rss: int
    killed_for_time: bool
    stderr_tail: str
    wall: float


def run_case(
    scene: Path,
    model: str,
    warmup: Path | None,
    max_time: float,
    max_memory: float,
    step_only: bool = False,
) -> CaseResult:
    """Run one case (:mod:`studies.bench_scale_case`) in a child process under the caps.

    The child's static solve stops itself at ``max_time``
    (:func:`~springfem.mechanics.limits.solve_limits`); it is killed when it has not started
    within :data:`SETUP_SECONDS` beyond that, or has not ended :data:`GRACE_SECONDS` past it.

    Parameters
    ----------
    scene
        The case's scene file.
    model
        The model.
    warmup
        The warm-up scene.
    max_time
        Seconds of the static solve.
    max_memory
        Bytes of address space (``RLIMIT_AS``).
    step_only
        Time the explicit step only (``--step-only``).

    Returns
    -------
    CaseResult
    """
    import json

    cmd = [sys.executable, "-m", "studies.bench_scale_case", str(scene), model,
           "--cap", f"{max_time:g}"] + (["--warmup", str(warmup)] if warmup else [])  # fmt: skip
    cmd += ["--step-only"] if step_only else []
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=_child_env(), preexec_fn=_limit(max_memory),
                            start_new_session=True)  # fmt: skip
    stages: dict[str, dict] = {}
    tail: list[str] = []

    def read_out() -> None:
        assert proc.stdout is not None
        for line in proc.stdout:
            try:
                rec = json.loads(line)
                stages[rec.pop("stage")] = {**rec, "at": time.perf_counter()}
            except (ValueError, KeyError, AttributeError):
                continue

    def read_err() -> None:
        assert proc.stderr is not None
        for line in proc.stderr:
            tail.append(line.rstrip())
            del tail[:-20]

    readers = [threading.Thread(target=f, daemon=True) for f in (read_out, read_err)]
    for r in readers:
        r.start()
    killed = False
    status = 0
    usage = None
    try:
        while True:
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            now = time.perf_counter()
            ready = stages.get("ready", {}).get("at")
            late = (now - t0 > max_time + SETUP_SECONDS) if ready is None else (
                now - ready > max_time + GRACE_SECONDS)  # fmt: skip
            if late and not killed:
                killed = True
                os.killpg(proc.pid, signal.SIGKILL)
            time.sleep(0.1)
    except BaseException:  # stopped (Ctrl-C, SIGTERM of a timeout): the case goes too
        with contextlib.suppress(OSError):
            os.killpg(proc.pid, signal.SIGKILL)
            os.wait4(proc.pid, 0)
        raise
    for r in readers:
        r.join(timeout=5)
    proc.returncode = os.waitstatus_to_exitcode(status)
    return CaseResult(stages, proc.returncode, int(usage.ru_maxrss) * 1024, killed,
                      "\n".join(tail[-5:]), time.perf_counter() - t0)  # fmt: skip


def classify(res: CaseResult, max_time: float, max_memory: float) -> tuple[str, str]:
    """A case's status and message from what its child left.

    ``ok``, ``implausible``, ``partial`` or ``failed`` as :func:`studies.models.run` gives it;
    ``did not fit: time`` when the static solve was stopped at (or killed past) the time
    cap; ``did not fit: memory`` when the child ran out of memory (a ``MemoryError``, or a
    crash with its peak RSS near the cap or an allocation failure on stderr).

    Parameters
    ----------
    res
        The child's result.
    max_time, max_memory
        The caps.

    Returns
    -------
    tuple of (str, str)
    """
    memory_words = ("memoryerror", "cannot allocate", "bad_alloc", "out of memory",
                    "unable to allocate", "failed to allocate")  # fmt: skip
    static = res.stages.get("static")
    if static is not None:
        message = static.get("message", "")
        if static["status"] in SOLVED:
            return static["status"], message
        if static["seconds"] >= 0.9 * max_time:
            return f"{DID_NOT_FIT}: time", f"stopped at the {max_time:g} s cap"
        if any(w in message.lower() for w in memory_words):  # a solver that caught it
            return f"{DID_NOT_FIT}: memory", f"{message[:120]} (cap {max_memory / 1e9:g} GB)"
        return static["status"], message
    if res.killed_for_time:
        where = "static solve" if "ready" in res.stages else "set-up"
        return f"{DID_NOT_FIT}: time", f"killed past the {max_time:g} s cap in its {where}"
    err = res.stderr_tail.lower()
    if ("error" in res.stages and res.stages["error"].get("kind") == "memory") or any(
        w in err for w in memory_words
    ):
        return f"{DID_NOT_FIT}: memory", f"out of memory under the {max_memory / 1e9:g} GB cap"
    if res.returncode < 0 and res.peak_rss >= 0.7 * max_memory:
        return f"{DID_NOT_FIT}: memory", (
            f"killed by signal {-res.returncode} at {res.peak_rss / 1e9:.3g} GB "
            f"(cap {max_memory / 1e9:g} GB)"
        )
    last = res.stderr_tail.splitlines()[-1] if res.stderr_tail else ""
    return "failed", f"exit {res.returncode}: {last}"[:300]
