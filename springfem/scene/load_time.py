"""Loads as functions of time: the optional ``time`` table of a ``[[load]]``.

A load's value is multiplied by a factor ``g(t)``. The ``time`` table gives it as

- ``ramp = [t0, t1]``: 0 before ``t0``, rising linearly to 1 at ``t1``, then 1;
- ``hold = [t0, t1]``: 1 from ``t0`` until ``t1``, 0 before and after (a pulse);
- ``release = t``: 1 before ``t``, 0 from ``t`` on (the tool lets go);
- ``table = [[t, g], ...]``: piecewise linear through the points (times non-decreasing;
  two points at the same time make a jump), constant before the first and after the last.

``ramp``, ``hold`` and ``release`` may be combined: the factor is their product
(``{ ramp = [0, 0.05], release = 0.2 }`` pulls up over 50 ms, holds, and lets go at
0.2 s); ``table`` stands alone. Each becomes a :class:`TimeFunction`, a list of tables
whose values multiply. A jump is right-continuous (the new value holds from the jump's
time on); :meth:`TimeFunction.left` gives the value just before. A load without ``time``
has ``g = 1`` always. Static solves ignore the factor: they apply the full load.

Examples
--------
>>> g = parse_time({"ramp": [0.0, 0.1], "release": 0.2})
>>> [g(t) for t in (0.0, 0.05, 0.1, 0.15, 0.2, 0.3)]
[0.0, 0.5, 1.0, 1.0, 0.0, 0.0]
>>> g.left(0.2), g.jumps()
(1.0, [0.2])
>>> parse_time({"table": [[0, 0], [0.1, 1], [0.1, 3]]}, where="load[1]")(0.05)
0.5
>>> parse_time({"ramp": [0.2, 0.1]}, where="load[1]", file="s.toml")
Traceback (most recent call last):
...
springfem.errors.SceneError: s.toml: load[1].time.ramp: t1 is before t0: [0.2, 0.1]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .reader import MAX_MAGNITUDE, TableReader, _show, is_number

#: The keys of a ``time`` table.
TIME_KEYS = ("ramp", "hold", "release", "table")


@dataclass(frozen=True)
class TimeFunction:
    """A load factor ``g(t)``: the product of piecewise-linear tables.

    Parameters
    ----------
    tables
        Each a pair ``(times, values)`` of equal-length 1-d arrays, times non-decreasing
        (at most two equal times in a row: a jump), values held constant outside.
    """

    tables: tuple[tuple[np.ndarray, np.ndarray], ...]

    def __call__(self, t: float) -> float:
        """The factor at ``t``, right-continuous at a jump."""
        return float(np.prod([_table(ts, vs, t, right=True) for ts, vs in self.tables]))

    def left(self, t: float) -> float:
        """The factor just before ``t`` (equal to ``g(t)`` except at a jump)."""
        return float(np.prod([_table(ts, vs, t, right=False) for ts, vs in self.tables]))

    def jumps(self) -> list[float]:
        """The times where the factor jumps, ascending."""
        out = {float(t) for t in self.breakpoints() if self.left(t) != self(t)}
        return sorted(out)

    def breakpoints(self) -> list[float]:
        """Every time a table changes slope or value, ascending."""
        return sorted({float(t) for ts, _ in self.tables for t in ts})


def _table(ts: np.ndarray, vs: np.ndarray, t: float, right: bool) -> float:
    """Linear interpolation through ``(ts, vs)``; at a repeated time the last value holds
    from it on (``right``) or the first holds up to it."""
    i = int(np.searchsorted(ts, t, side="right" if right else "left"))
    if i == 0:
        return float(vs[0])
    if i == len(ts):
        return float(vs[-1])
    if right and ts[i - 1] == t:
        return float(vs[i - 1])
    if not right and ts[i] == t:
        return float(vs[i])
    w = (t - ts[i - 1]) / (ts[i] - ts[i - 1])
    return float((1.0 - w) * vs[i - 1] + w * vs[i])


def _time(x) -> bool:
    return is_number(x) and math.isfinite(x) and abs(x) <= MAX_MAGNITUDE


def parse_time_table(r: TableReader) -> TimeFunction:
    """Validate a load's ``time`` table (module docstring) into a :class:`TimeFunction`.

    Parameters
    ----------
    r
        Reader over the ``time`` table; every error names the file, the load and the key.

    Returns
    -------
    TimeFunction
    """
    given = [k for k in TIME_KEYS if r.has(k)]  # every key asked for: the reference lists them
    if not given:
        r.finish()
        raise r.fail("ramp", "a time table needs ramp, hold, release or table")
    if "table" in given and len(given) > 1:
        raise r.fail("table", "stands alone; ramp, hold and release combine with each other")
    tables = []
    for key in ("ramp", "hold"):
        if key in given:
            v = r.t[key]
            r.used.add(key)
            if not (isinstance(v, list) and len(v) == 2 and all(_time(x) for x in v)):
                raise r.fail(key, f"must be [t0, t1] (seconds), got {_show(v)}")
            t0, t1 = float(v[0]), float(v[1])
            if t1 < t0:
                raise r.fail(key, f"t1 is before t0: {_show(v)}")
            if key == "ramp":
                tables.append((np.array([t0, t1]), np.array([0.0, 1.0])))
            else:
                tables.append((np.array([t0, t0, t1, t1]), np.array([0.0, 1.0, 1.0, 0.0])))
    if "release" in given:
        t = r.get("release", "float")
        tables.append((np.array([t, t]), np.array([1.0, 0.0])))
    if "table" in given:
        tables.append(_parse_points(r))
    r.finish()
    return TimeFunction(tuple(tables))


def _parse_points(r: TableReader) -> tuple[np.ndarray, np.ndarray]:
    """``table = [[t, g], ...]``: at least one pair, times non-decreasing, no triple time."""
    v = r.t["table"]
    r.used.add("table")
    pairs = isinstance(v, list) and len(v) > 0
    pairs = pairs and all(
        isinstance(p, list) and len(p) == 2 and all(_time(x) for x in p) for p in v
    )
    if not pairs:
        raise r.fail("table", f"must be a list of [t, factor] pairs (numbers), got {_show(v)}")
    ts = np.array([float(p[0]) for p in v])
    vs = np.array([float(p[1]) for p in v])
    if (np.diff(ts) < 0).any():
        i = int(np.flatnonzero(np.diff(ts) < 0)[0])
        raise r.fail("table", f"times must not decrease: {ts[i]:g} then {ts[i + 1]:g}")
    if len(ts) > 2 and ((ts[2:] == ts[1:-1]) & (ts[1:-1] == ts[:-2])).any():
        raise r.fail("table", "at most two points may share a time (a jump)")
    return ts, vs


def parse_time(spec, where: str = "load[0]", file: str = "<scene>") -> TimeFunction:
    """Parse a plain ``time`` table (see :func:`parse_time_table`).

    Parameters
    ----------
    spec
        The table (a ``dict``).
    where
        The load's name in messages (``load[0]``).
    file
        The scene file's name in messages.

    Returns
    -------
    TimeFunction
    """
    return parse_time_table(TableReader(spec, f"{where}.time", file, keys=TIME_KEYS))
