"""Caps and interrupts hold wherever a solve is: a cooperative checkpoint, a long C call
abandoned by :func:`interruptible` (the cap and ``KeyboardInterrupt`` reach the caller while
the call runs), and the watchdog that interrupts a pure-Python loop that never checks.

The latencies asserted are the mechanism's function (a cap must stop within seconds), with
margins of seconds over the tenths the mechanism needs, for a busy machine."""

from __future__ import annotations

import _thread
import threading
import time

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from springfem.mechanics.limits import (
    POLL,
    WATCHDOG_GRACE,
    Deadline,
    SolveStopped,
    checkpoint,
    interruptible,
    solve_limits,
)


def capped(seconds: float) -> Deadline:
    with solve_limits(max_time=seconds):
        return Deadline()


def test_checkpoint_is_silent_before_the_cap_and_outside_a_watch():
    d = capped(60.0)
    with d.watch():
        checkpoint()  # before the cap: nothing
    late = capped(0.0)
    checkpoint()  # not watched: nothing, even though ``late`` has expired
    assert late.expired()


@pytest.mark.skipif(
    threading.current_thread() is not threading.main_thread(),
    reason="signals reach the main thread only (a test runner may use another)",
)
def test_interruptible_abandons_a_long_call_that_releases_the_gil():
    """``time.sleep`` stands for a factorisation in C (SuperLU and PARDISO release the GIL):
    a 0.3 s cap stops a 30 s call after 0.3 s plus one poll."""
    d = capped(0.3)
    t0 = time.monotonic()
    with d.watch(), pytest.raises(SolveStopped, match="--max-time cap of 0.3 s"):
        interruptible(time.sleep, 30.0)
    assert time.monotonic() - t0 < 0.3 + 20 * POLL + 2.0


def test_interruptible_returns_the_value_and_raises_the_error():
    A = sp.csc_matrix(np.array([[2.0, 1.0], [1.0, 3.0]]))
    lu = interruptible(spla.splu, A)
    assert np.allclose(A @ lu.solve(np.ones(2)), 1.0)
    with pytest.raises(RuntimeError, match="singular"):
        interruptible(spla.splu, sp.csc_matrix((2, 2)))


@pytest.mark.skipif(
    threading.current_thread() is not threading.main_thread(),
    reason="signals reach the main thread only (a test runner may use another)",
)
def test_ctrl_c_reaches_the_caller_during_a_long_call(python_sigint):
    """A ``KeyboardInterrupt`` (Ctrl-C, simulated from another thread) arrives while the
    caller waits for the worker, not after the 30 s call."""
    threading.Timer(0.3, _thread.interrupt_main).start()
    t0 = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        interruptible(time.sleep, 30.0)
    assert time.monotonic() - t0 < 0.3 + 2.0


@pytest.mark.skipif(
    threading.current_thread() is not threading.main_thread(),
    reason="signals reach the main thread only (a test runner may use another)",
)
def test_watchdog_interrupts_a_loop_that_never_checks(python_sigint):
    """A busy Python loop without checkpoints: the watchdog interrupts the main thread
    WATCHDOG_GRACE after the cap; the solve turns it into SolveStopped by the cap."""
    d = capped(0.2)
    t0 = time.monotonic()
    with pytest.raises(KeyboardInterrupt), d.watch():
        while time.monotonic() - t0 < 30.0:
            sum(range(1000))
    elapsed = time.monotonic() - t0
    assert d.fired and 0.2 + WATCHDOG_GRACE - 0.1 < elapsed < 0.2 + WATCHDOG_GRACE + 2.0
    assert "--max-time cap of 0.2 s" in str(d.stopped(interrupted=True))


def test_watchdog_is_cancelled_when_the_solve_ends_in_time():
    d = capped(0.1)
    with d.watch():
        pass
    time.sleep(0.1 + WATCHDOG_GRACE + 0.3)  # no KeyboardInterrupt arrives
    assert not d.fired
    assert "interrupted (Ctrl-C)" in str(capped(60.0).stopped(interrupted=True))
