"""Floating-point warnings counted and summarised once, instead of a flood of raw lines.

A failing solve can raise dozens of numpy ``RuntimeWarning`` lines (``overflow encountered
in exp``, ``invalid value encountered in divide``) before the solver states what happened.
:func:`counted_warnings` collects them inside its block (a :class:`collections.Counter` of
their messages, numbers removed), and :func:`summary` turns the count into one line.
Warnings of other categories pass through untouched.

Examples
--------
>>> import numpy as np
>>> with counted_warnings() as seen:
...     _ = np.exp(np.array([1000.0, 2000.0]))
...     _ = np.array([0.0]) / 0.0
>>> head, parts = summary(seen).split(": ")
>>> head
'2 floating-point warnings while solving'
>>> parts
'overflow encountered in exp (1), invalid value encountered in divide (1)'
>>> summary({}) is None
True
"""

from __future__ import annotations

import contextlib
import re
import warnings
from collections import Counter
from collections.abc import Iterator, Mapping


@contextlib.contextmanager
def counted_warnings() -> Iterator[Counter]:
    """Count the ``RuntimeWarning`` messages raised inside the block (and show none).

    Yields
    ------
    collections.Counter
        Message (numbers replaced by ``N``) -> how many times; filled as the block runs.
    """
    seen: Counter = Counter()
    shown = warnings.showwarning

    def record(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, RuntimeWarning):
            seen[re.sub(r"\d+(\.\d+)?", "N", str(message))] += 1
        else:
            shown(message, category, filename, lineno, file, line)

    with warnings.catch_warnings():
        warnings.simplefilter("always", RuntimeWarning)
        warnings.showwarning = record
        try:
            yield seen
        finally:
            warnings.showwarning = shown


def summary(seen: Mapping[str, int]) -> str | None:
    """One line for the counted warnings, most frequent first (``None`` when there were none).

    Parameters
    ----------
    seen
        The counter of :func:`counted_warnings`.

    Returns
    -------
    str or None
    """
    total = sum(seen.values())
    if not total:
        return None
    parts = ", ".join(f"{m} ({n})" for m, n in Counter(seen).most_common())
    return f"{total} floating-point warnings while solving: {parts}"
