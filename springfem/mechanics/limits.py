"""Caps on a solve: wall time and time steps (``--max-time``, ``--max-steps``), memory
(``max_memory``: :mod:`.memory`), and the interrupt (Ctrl-C).

:func:`solve_limits` sets them for every solve started inside its block; the per-solve
context (:class:`~springfem.mechanics.context.SolveContext`) checks them at every force
evaluation, and :class:`Deadline` gives a solve without a context (the FEM's Newton) the
same time cap. A stopped solve raises :class:`SolveStopped` (exit code 3).

A cap must hold wherever the solve is, also inside a long assembly, factorisation or
Krylov solve. Three mechanisms, innermost first:

- cooperative: :func:`checkpoint` raises :class:`SolveStopped` once the deadline of the
  innermost :meth:`Deadline.watch` block has passed; the Newton loop, the line search, the
  Krylov iterations and the assembly call it;
- abandonable: :func:`interruptible` runs one long C call (a sparse factorisation; SuperLU
  and PARDISO release the GIL) in a worker thread and waits for it in short slices, so
  the cap and Ctrl-C (``KeyboardInterrupt``) reach the main thread while it runs; a stopped
  solve leaves the call to finish in the background, its result unused;
- watchdog: a :meth:`Deadline.watch` block with a cap starts a timer thread that, when
  the solve is still running :data:`WATCHDOG_GRACE` seconds past the cap, interrupts the
  main thread (``_thread.interrupt_main``) between two Python bytecodes; the solve turns
  the interrupt into :class:`SolveStopped` (:meth:`Deadline.stopped`).

The solver that watches (the FEM's :func:`reference_fem.newton.solve_nonlinear`) catches
:class:`SolveStopped` and ``KeyboardInterrupt`` and raises :class:`SolveStopped` with its
last converged state and load factor.

Examples
--------
>>> with solve_limits(max_steps=10):
...     LIMITS["max_steps"]
10
"""

from __future__ import annotations

import _thread
import contextlib
import threading
import time
from collections.abc import Callable, Iterator

import numpy as np

from springfem.errors import SpringFemError


class SolveStopped(SpringFemError, RuntimeError):
    """A solve ended by a cap (:func:`solve_limits`): wall time or time steps (exit code 3).

    Not a :class:`~springfem.errors.SolverError`, so no solver mistakes it for a failed
    step to retry or fall back from.

    Parameters
    ----------
    message
        ``stopped after N s / N steps at residual R``.
    state
        The positions ``(n, 3)`` at the stop (the FEM: the last converged vertex
        displacements).
    load_factor
        The load factor of ``state`` when the solve stepped the load (``None`` otherwise).
    """

    exit_code = 3

    def __init__(
        self, message: str, state: np.ndarray | None = None, load_factor: float | None = None
    ):
        super().__init__(message)
        self.state = state
        self.load_factor = load_factor


LIMITS: dict[str, float | None] = {"max_time": None, "max_steps": None, "max_memory": None}
#: What the time cap of :data:`LIMITS` is (``why`` of :func:`solve_limits`).
CAP_REASON: dict[str, str | None] = {"why": None}
#: Seconds past the cap after which the watchdog interrupts the main thread.
WATCHDOG_GRACE = 2.0
#: Seconds between two looks of :func:`interruptible` at the cap and at Ctrl-C.
POLL = 0.05
_WATCHED: list[Deadline] = []  # the innermost watched deadline last
_ABANDONED: list[threading.Thread] = []  # workers of interruptible calls left running


@contextlib.contextmanager
def solve_limits(
    max_time: float | None = None,
    max_steps: int | None = None,
    why: str | None = None,
    max_memory: float | None = None,
) -> Iterator[None]:
    """Cap every solve started inside the block: wall time, time steps and memory.

    A :class:`SolveContext` created inside takes a deadline ``max_time`` seconds after its
    first force evaluation (which includes the one-time compilation of the force kernels,
    seconds on a busy machine); every force evaluation past it (or past ``max_steps`` time
    steps of an explicit, relaxation or implicit loop) raises :class:`SolveStopped`. One
    check in the force evaluation every solver goes through caps all solver loops alike.

    Parameters
    ----------
    max_time
        Seconds per solve (``None``: no cap).
    max_steps
        Time steps per solve (``None``: no cap; Newton iterations are capped by
        ``max_iter``).
    why
        What the time cap is, for the message of a stop (default ``the --max-time cap of
        N s``; a study's runner: its budget).

    Yields
    ------
    None
        The block runs with the caps set; the previous caps come back after it.

    Examples
    --------
    >>> with solve_limits(max_time=5.0):
    ...     LIMITS["max_time"]
    5.0
    >>> LIMITS["max_time"] is None
    True
    """
    saved, saved_why = dict(LIMITS), CAP_REASON["why"]
    LIMITS.update(max_time=max_time, max_steps=max_steps)
    if max_memory is not None:
        LIMITS["max_memory"] = float(max_memory)
    CAP_REASON["why"] = why
    try:
        yield
    finally:
        LIMITS.update(saved)
        CAP_REASON["why"] = saved_why


class Deadline:
    """The :func:`solve_limits` time cap for a solve that runs no :class:`SolveContext`.

    The FEM's Newton iterates on its own DOF vector; it starts one of these with the solve
    and checks it once per Newton iteration.

    Attributes
    ----------
    max_time
        The cap in seconds (``None``: none), read from :data:`LIMITS` when created.
    start
        ``time.monotonic()`` when created.

    Examples
    --------
    >>> with solve_limits(max_time=0.0):
    ...     d = Deadline()
    >>> try:
    ...     d.check("1 Newton iterations", 0.5)
    ... except SolveStopped as exc:
    ...     print(str(exc).split(" at ")[1])
    relative residual 0.5 (the --max-time cap of 0 s)
    """

    def __init__(self) -> None:
        self.max_time = LIMITS["max_time"]
        self.why = cap_reason(self.max_time)
        self.start = time.monotonic()
        self.progress = "start"  # what has been done (for the message of a stop)
        self.fired = False  # the watchdog interrupted the main thread

    def expired(self) -> bool:
        """Whether the cap has passed."""
        return self.max_time is not None and time.monotonic() - self.start > self.max_time

    def stopped(self, interrupted: bool = False) -> SolveStopped:
        """The :class:`SolveStopped` of this solve now (by the cap, or by Ctrl-C).

        Parameters
        ----------
        interrupted
            A ``KeyboardInterrupt`` arrived: Ctrl-C, unless the watchdog sent it.

        Returns
        -------
        SolveStopped
            Its message says after how long, where (:attr:`progress`) and why.
        """
        elapsed = time.monotonic() - self.start
        if interrupted and not self.fired and not self.expired():
            why = "interrupted (Ctrl-C)"
        else:
            why = self.why
        return SolveStopped(f"stopped after {elapsed:.3g} s / {self.progress} ({why})")

    @contextlib.contextmanager
    def watch(self) -> Iterator[Deadline]:
        """Make this the deadline :func:`checkpoint` checks, with a watchdog for the cap.

        Yields
        ------
        Deadline
            ``self``.
        """
        _WATCHED.append(self)
        lock, active = threading.Lock(), [True]
        timer = None
        if self.max_time is not None and threading.current_thread() is threading.main_thread():
            remaining = self.max_time - (time.monotonic() - self.start) + WATCHDOG_GRACE

            def fire() -> None:
                with lock:
                    if active[0]:
                        self.fired = True
                        _thread.interrupt_main()

            timer = threading.Timer(max(0.0, remaining), fire)
            timer.daemon = True
            timer.start()
        try:
            yield self
        finally:
            with lock:
                active[0] = False
            if timer is not None:
                timer.cancel()
            _WATCHED.remove(self)

    def check(self, what: str, residual: float, state: np.ndarray | None = None) -> None:
        """Raise :class:`SolveStopped` once the cap has passed.

        Parameters
        ----------
        what
            What has been done so far (``"12 Newton iterations"``), for the message.
        residual
            The current relative residual.
        state
            The last good state, handed to the caller in the exception.
        """
        self.progress = what
        if self.max_time is None:
            return
        elapsed = time.monotonic() - self.start
        if elapsed > self.max_time:
            raise SolveStopped(
                f"stopped after {elapsed:.3g} s / {what} at relative residual {residual:.3g} "
                f"({self.why})",
                state=state,
            )


def cap_reason(max_time: float | None) -> str:
    """What stopped a solve at ``max_time``: :func:`solve_limits`'s ``why``, else the cap.

    Examples
    --------
    >>> cap_reason(5.0)
    'the --max-time cap of 5 s'
    """
    why = CAP_REASON["why"]
    return why if why else f"the --max-time cap of {max_time or 0:g} s"


def checkpoint() -> None:
    """Raise :class:`SolveStopped` when the innermost watched deadline has passed.

    Cheap (one clock read): long loops call it often. Outside a :meth:`Deadline.watch`
    block it does nothing.

    Raises
    ------
    SolveStopped
        The cap has passed (see :meth:`Deadline.stopped`).

    Examples
    --------
    >>> with solve_limits(max_time=0.0):
    ...     d = Deadline()
    >>> with d.watch():
    ...     try:
    ...         checkpoint()
    ...     except SolveStopped as exc:
    ...         print(str(exc).split("(")[1])
    the --max-time cap of 0 s)
    """
    if _WATCHED and _WATCHED[-1].expired():
        raise _WATCHED[-1].stopped()


def interruptible(fn: Callable, *args):
    """``fn(*args)`` in a worker thread, the caller waiting in slices of :data:`POLL` s.

    While it waits the caller runs :func:`checkpoint` and receives ``KeyboardInterrupt``,
    so neither the cap nor Ctrl-C waits for a long C call that releases the GIL (a sparse
    factorisation). A stopped call is abandoned: the worker (a daemon thread) finishes it
    and its result is dropped. Off the main thread ``fn`` runs directly.

    Parameters
    ----------
    fn
        The call.
    *args
        Its arguments.

    Returns
    -------
    object
        ``fn(*args)``; its exception is raised in the caller.

    Examples
    --------
    >>> interruptible(sum, [1, 2, 3])
    6
    """
    if threading.current_thread() is not threading.main_thread():
        return fn(*args)
    out: dict = {}

    def run() -> None:
        try:
            out["value"] = fn(*args)
        except BaseException as exc:  # noqa: BLE001 - handed to the caller
            out["error"] = exc

    worker = threading.Thread(target=run, daemon=True)
    worker.start()
    try:
        while worker.is_alive():
            worker.join(POLL)
            checkpoint()
    except BaseException:
        _ABANDONED.append(worker)
        raise
    if "error" in out:
        raise out["error"]
    return out["value"]


def abandoned_calls() -> bool:
    """Whether a call abandoned by :func:`interruptible` is still running.

    Memory such a call may still use (a PARDISO factor) must not be freed, also not at
    interpreter exit.

    Returns
    -------
    bool
        ``True`` while any abandoned worker is alive.
    """
    _ABANDONED[:] = [t for t in _ABANDONED if t.is_alive()]
    return bool(_ABANDONED)
