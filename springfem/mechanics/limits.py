"""Caps on a solve: wall time and time steps (``--max-time``, ``--max-steps``).

:func:`solve_limits` sets them for every solve started inside its block; the per-solve
context (:class:`~springfem.mechanics.context.SolveContext`) checks them at every force
evaluation, and :class:`Deadline` gives a solve without a context (the FEM's Newton) the
same time cap. A stopped solve raises :class:`SolveStopped` (exit code 3).

Examples
--------
>>> with solve_limits(max_steps=10):
...     LIMITS["max_steps"]
10
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterator

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
        The positions ``(n, 3)`` at the stop.
    """

    exit_code = 3

    def __init__(self, message: str, state: np.ndarray | None = None):
        super().__init__(message)
        self.state = state


LIMITS: dict[str, float | None] = {"max_time": None, "max_steps": None}


@contextlib.contextmanager
def solve_limits(max_time: float | None = None, max_steps: int | None = None) -> Iterator[None]:
    """Cap every solve started inside the block: wall time and time steps.

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
    saved = dict(LIMITS)
    LIMITS.update(max_time=max_time, max_steps=max_steps)
    try:
        yield
    finally:
        LIMITS.update(saved)


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
        self.start = time.monotonic()

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
        if self.max_time is None:
            return
        elapsed = time.monotonic() - self.start
        if elapsed > self.max_time:
            raise SolveStopped(
                f"stopped after {elapsed:.3g} s / {what} at relative residual {residual:.3g} "
                f"(the --max-time cap of {self.max_time:g} s)",
                state=state,
            )
