"""Typed access to one table of a scene: every problem is one line naming file and key.

Examples
--------
>>> r = TableReader({"E": 1.0e3, "valeu": 2}, "load[0]", "s.toml", keys=("E", "value"))
>>> r.get("E", "float", positive=True)
1000.0
>>> r.get("value", "float")
Traceback (most recent call last):
...
springfem.errors.SceneError: s.toml: load[0].valeu: unknown key; did you mean 'value'?
"""

from __future__ import annotations

import difflib
import math
import numbers
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import numpy as np

from ..errors import SceneError

#: Largest magnitude of a number in a scene. SI values of soft-tissue problems are many
#: orders of magnitude inside it, and products of three such numbers (a volume, a force
#: times a length) stay finite in float64.
MAX_MAGNITUDE = 1e100
#: Smallest non-zero magnitude of a number in a scene (cubes stay normal float64 numbers).
MIN_MAGNITUDE = 1e-100
#: Largest integer in a scene (divisions, steps, iterations).
MAX_INT = 2**31 - 1


#: How close a misspelt key must be to a known one to be suggested (:mod:`difflib` ratio).
SUGGEST_CUTOFF = 0.75


def suggestion(word: str, known: Iterable[str]) -> str | None:
    """The known word closest to a misspelt ``word``, or ``None`` if none is close.

    Parameters
    ----------
    word
        What the scene says.
    known
        The words valid there.

    Returns
    -------
    str or None
        The closest of ``known`` with a :class:`difflib.SequenceMatcher` ratio of at least
        :data:`SUGGEST_CUTOFF`, ignoring case (``Loaded`` finds ``loaded``).

    Examples
    --------
    >>> suggestion("valeu", ["value", "type", "region"]), suggestion("xyz", ["value"])
    ('value', None)
    >>> suggestion("Loaded", ["loaded", "fixed"])
    'loaded'
    """
    spelled = {k.lower(): k for k in sorted(known, reverse=True)}
    close = difflib.get_close_matches(word.lower(), sorted(spelled), n=1, cutoff=SUGGEST_CUTOFF)
    return spelled[close[0]] if close else None


def is_number(v: Any) -> bool:
    """A real number that is not a bool (numpy scalars of a programmatic table count).

    Parameters
    ----------
    v
        A table value.

    Returns
    -------
    bool
        True for ``int``, ``float`` and numpy integer/float scalars.

    Examples
    --------
    >>> is_number(np.int64(3)), is_number(True), is_number("1")
    (True, False, False)
    """
    return isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_))


#: Called with ``(reader, key, kind, choices)`` for every key a parser asks a reader for
#: (``kind`` ``None`` for a :meth:`TableReader.has` test): how
#: :mod:`springfem.scene.reference` reads the accepted keys off the parsers.
ASK_RECORDERS: list[Callable[[TableReader, str, str | None, Any], None]] = []


class TableReader:
    """Typed access to one TOML table with error messages naming file and key.

    Every key the parser asks for (:meth:`get`, :meth:`has`) becomes known; a key of the
    table that is never asked for is unknown (:meth:`finish`), and a misspelt key is named
    with the known key it is closest to.

    Parameters
    ----------
    table
        The table (a ``dict``); anything else is a :class:`SceneError`.
    where
        The table's name in messages (``material``, ``load[0]``; empty for the top level).
    file
        The scene file's name in messages.
    keys
        Every key valid in the table, if the parser declares them: then a missing required
        key is matched against the table's invalid keys only (a valid key asked for later
        is never taken for a misspelling).
    root
        The whole scene's table, for a section whose defaults depend on another section
        (the ``[spring]`` element on the ``[material]`` law); ``None`` if not known.
    """

    def __init__(
        self,
        table: Any,
        where: str,
        file: str,
        keys: Iterable[str] | None = None,
        root: Mapping[str, Any] | None = None,
    ):
        if not isinstance(table, dict):
            raise SceneError(f"{file}: {where} must be a table")
        self.t, self.where, self.file, self.root = table, where, file, root
        self.used: set[str] = set()
        self.keys = None if keys is None else frozenset(keys)
        self.known: set[str] = set(self.keys or ())

    def _key(self, key: str) -> str:
        key = _key_label(key)
        return f"{self.where}.{key}" if self.where else key

    def fail(self, key: str, msg: str) -> SceneError:
        """The error for ``key``: ``"<file>: <where>.<key>: <msg>"``.

        Parameters
        ----------
        key
            The offending key.
        msg
            What is wrong with it.

        Returns
        -------
        SceneError
            To be raised by the caller.
        """
        return SceneError(f"{self.file}: {self._key(key)}: {msg}")

    def has(self, key: str) -> bool:
        """Whether the table holds ``key`` (which becomes a known key).

        Parameters
        ----------
        key
            The key.

        Returns
        -------
        bool
        """
        self.known.add(key)
        for record in ASK_RECORDERS:
            record(self, key, None, None)
        return key in self.t

    def missing(self, key: str) -> SceneError:
        """The error for a required ``key`` that is absent, naming a misspelling of it.

        Parameters
        ----------
        key
            The required key (not in the table).

        Returns
        -------
        SceneError
            ``"<key>: missing (required)"``, or ``"<typo>: unknown key; did you mean
            '<key>'?"`` when an invalid key of the table is close to it (only when the
            valid ``keys`` are declared).
        """
        self.used.add(key)
        self.known.add(key)
        if self.keys is None:
            return self.fail(key, "missing (required)")
        typo = suggestion(key, set(self.t) - self.keys)
        if typo is not None:
            return self.fail(typo, f"unknown key; did you mean {key!r}?")
        return self.fail(key, "missing (required)")

    def get(
        self,
        key: str,
        kind: str,
        default: Any = ...,
        choices=None,
        positive=False,
        nonneg=False,
        length=None,
    ):
        """The value of ``key``, checked and converted to ``kind``.

        Parameters
        ----------
        key
            The key.
        kind
            ``str``, ``bool``, ``float``, ``int``, ``vec`` (float array) or ``ivec`` (int
            array).
        default
            Returned when the key is absent; without it the key is required.
        choices
            Valid strings (``str`` only).
        positive, nonneg
            Sign required of a number (``positive`` also of every vector entry).
        length
            Required length of a vector.

        Returns
        -------
        str, bool, float, int or numpy.ndarray
            The checked value (a required key misspelt in the table is named with its
            suggestion).
        """
        self.used.add(key)
        self.known.add(key)
        for record in ASK_RECORDERS:
            record(self, key, kind, choices)
        if key not in self.t:
            if default is ...:
                raise self.missing(key)
            return default
        v = self.t[key]
        if kind == "str":
            if not isinstance(v, str):
                raise self.fail(key, f"must be a string, got {type(v).__name__}")
            if choices is not None and v not in choices:
                raise self.fail(key, f"{_show(v)} is not one of {', '.join(map(str, choices))}")
            return v
        if kind == "bool":
            if not isinstance(v, bool):
                raise self.fail(key, f"must be true or false, got {_show(v)}")
            return v
        if kind in ("float", "int"):
            if not is_number(v):
                raise self.fail(key, f"must be a number, got {type(v).__name__}")
            if kind == "int" and not isinstance(v, numbers.Integral):
                raise self.fail(key, f"must be an integer, got {_show(v)}")
            self._check_number(key, v, kind == "int", positive, nonneg, v)
            return float(v) if kind == "float" else int(v)  # numpy scalars become Python
        if kind in ("vec", "ivec"):
            if not isinstance(v, list) or (length is not None and len(v) != length):
                n = f"{length} " if length else ""
                raise self.fail(key, f"must be a list of {n}numbers, got {_show(v)}")
            for x in v:
                if not is_number(x):
                    raise self.fail(key, f"must be a list of numbers, got {_show(v)}")
                if kind == "ivec" and not isinstance(x, numbers.Integral):
                    raise self.fail(key, f"must be a list of integers, got {_show(v)}")
                self._check_number(key, x, kind == "ivec", positive, False, v, "entries ")
            return np.array(v, dtype=np.int64 if kind == "ivec" else float)
        raise AssertionError(kind)

    def _check_number(self, key, x, integer, positive, nonneg, shown, what="") -> None:
        """Finite, within :data:`MAX_MAGNITUDE` (or :data:`MAX_INT`), sign as required."""
        if not math.isfinite(x):
            raise self.fail(key, f"{what}must be finite, got {_show(shown)}")
        if positive and x <= 0:
            raise self.fail(key, f"{what}must be positive, got {_show(shown)}")
        if nonneg and x < 0:
            raise self.fail(key, f"{what}must not be negative, got {_show(shown)}")
        if integer and abs(x) > MAX_INT:
            raise self.fail(key, f"{what}must be at most {MAX_INT}, got {_show(shown)}")
        if not integer and abs(x) > MAX_MAGNITUDE:
            raise self.fail(key, f"{what}must lie within ±{MAX_MAGNITUDE:g}, got {_show(shown)}")
        if not integer and x != 0 and abs(x) < MIN_MAGNITUDE:
            raise self.fail(
                key,
                f"{what}must be 0 or at least {MIN_MAGNITUDE:g} in magnitude, got {_show(shown)}",
            )

    def finish(self) -> None:
        """Raise :class:`SceneError` for the first key no parser asked for (with a suggestion).

        Returns
        -------
        None
        """
        extra = sorted(set(self.t) - self.used)
        if extra:
            near = suggestion(extra[0], self.known - set(self.t))
            hint = f"; did you mean {near!r}?" if near else ""
            raise self.fail(extra[0], "unknown key" + hint)


def _key_label(key: str) -> str:
    """A key as written in a message: quoted when it holds spaces or control characters."""
    return key if key and key.isprintable() and not any(c.isspace() for c in key) else repr(key)


def _show(value: Any, limit: int = 60) -> str:
    """``repr`` of a scene value, cut to ``limit`` characters (one readable line)."""
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 1] + "…"
