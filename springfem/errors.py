"""Typed errors shared by both models and the CLI (exit codes of docs/contract.rst#exit-codes).

Every error is one line; :func:`format_ids` names the offending elements or nodes in it.

Examples
--------
>>> str(MeshError(f"mesh: zero-volume tets {format_ids([3, 7])}"))
'mesh: zero-volume tets 3, 7'
>>> MeshError.exit_code, SolverError.exit_code
(2, 3)
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np


def format_ids(ids: Iterable | np.ndarray, limit: int = 8) -> str:
    """Element or node ids as they appear in an error message, the first ``limit`` of them.

    Parameters
    ----------
    ids
        Integer ids, shape ``(k,)``; or index tuples, shape ``(k, d)`` (one row per id,
        e.g. from :func:`numpy.argwhere` over a batch of vectors), shown as tuples.
    limit
        How many to show; when there are more, the total count follows.

    Returns
    -------
    str
        ``"3, 7, 9"`` or ``"0, 1, 2 … (12 in all)"``.

    Examples
    --------
    >>> format_ids(range(12), limit=3)
    '0, 1, 2 … (12 in all)'
    >>> format_ids([[0, 1], [2, 0]])
    '(0, 1), (2, 0)'
    """
    idx = np.asarray(ids)
    if idx.ndim == 2:
        items = [str(tuple(int(v) for v in row)) for row in idx]
    else:
        items = [str(int(i)) for i in idx.ravel()]
    shown = ", ".join(items[:limit])
    return shown + (f" … ({len(items)} in all)" if len(items) > limit else "")


class SpringFemError(Exception):
    """Base class of the errors the CLI turns into one clear line.

    Parameters
    ----------
    message
        The line: what is wrong and where (file, key, element ids).

    Attributes
    ----------
    exit_code
        The CLI's exit code for this error (1: internal).
    """

    exit_code = 1


class InputError(SpringFemError, ValueError):
    """Bad input: a scene key, a mesh file, a region or a probe (exit code 2).

    Parameters
    ----------
    message
        One line naming what is wrong and where.
    """

    exit_code = 2


class SceneError(InputError):
    """A scene file is malformed: names the file and the key.

    Parameters
    ----------
    message
        ``"<file>: <section>.<key>: <what is wrong>"``.
    """


class MeshError(InputError):
    """A mesh is unusable: names the file and the element or node ids.

    Parameters
    ----------
    message
        ``"<file>: <what is wrong> <ids>"`` (ids by :func:`format_ids`).
    """


class SolverError(SpringFemError, RuntimeError):
    """A solve failed: diverged, blew up, singular (exit code 3).

    Parameters
    ----------
    message
        What failed, where and when (step, iteration, element).
    state
        The last good state, if any (e.g. a displacement array), so callers can write it.
    load_factor
        The load factor of ``state`` when the solve stepped the load and stopped part way
        (a partial result at that load), else ``None``.
    """

    exit_code = 3

    def __init__(self, message: str, state: object | None = None, load_factor: float | None = None):
        super().__init__(message)
        self.state = state
        self.load_factor = load_factor


class OutputError(SpringFemError, OSError):
    """An output cannot be written: a full disk, a read-only or locked folder (exit code 4).

    What was written before stays whole (every writer replaces its file atomically).

    Parameters
    ----------
    message
        One line naming the file or folder and why.
    """

    exit_code = 4
