"""Files that are never half-written: atomic writes, safe names, stale temporary files.

Every output is written to a temporary file in the target's folder and renamed over the
target, so a reader sees the old file or the new one, never a part. A writer killed
mid-write leaves only its temporary file, which :func:`remove_stale_temp_files` clears.

Examples
--------
>>> import tempfile, pathlib
>>> folder = pathlib.Path(tempfile.mkdtemp())
>>> atomic_write_text(folder / "a.json", "{}")
>>> (folder / "a.json").read_text(), remove_stale_temp_files(folder)
('{}', [])
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from .errors import InputError, OutputError


def jsonable(obj: Any) -> Any:
    """``obj`` with numpy arrays and scalars turned into plain Python, ready for :mod:`json`.

    Parameters
    ----------
    obj
        Nested dicts, lists and tuples of numbers, strings, numpy arrays and scalars.

    Returns
    -------
    object
        The same structure with lists for arrays and tuples, ``float``/``int``/``bool``
        for numpy scalars, ``str`` keys, and ``None`` for non-finite floats (JSON has no
        ``NaN``).

    Examples
    --------
    >>> jsonable({"u": np.array([1.0, np.nan]), 2: (np.int64(3), np.bool_(True))})
    {'u': [1.0, None], '2': [3, True]}
    """
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, (np.floating,)):
        return float(obj)
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if isinstance(obj, float) and not np.isfinite(obj):
        return None
    return obj


def atomic_write_text(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` to ``path`` via a temporary file in the same folder and a rename.

    Parameters
    ----------
    path
        The target (its folder is created). Readers see the old content or the new, never
        a part; a failed write leaves the old content.
    text
        UTF-8 text.

    Returns
    -------
    None

    Raises
    ------
    OutputError
        The disk is full (or over quota, or read-only): one line, the old content kept.
    """
    path = Path(path)
    try:
        _write_atomically(path, text)
    except OSError as exc:
        if exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EROFS):
            raise OutputError(
                f"cannot write {path}: {os.strerror(exc.errno)}; what was written before is "
                "kept whole"
            ) from None
        raise


def _write_atomically(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    # the writer's pid in the name lets remove_stale_temp_files tell a killed writer's
    # leftovers from a live writer's file
    fd, tmp = tempfile.mkstemp(
        dir=path.parent, prefix=f".{path.name}.", suffix=f".{os.getpid()}.tmp"
    )
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


# Temporary files of the atomic writers, with the writing process's id: atomic_write_text
# (".<name>.<random>.<pid>.tmp"), studies.tables.save_figure (".<stem>.<pid>.tmp.png") and
# mesh.write_vtu ("<name>.tmp-<pid>.vtu").
_TEMP_PATTERNS = (
    re.compile(r"^\..+\.(\d+)\.tmp$"),
    re.compile(r"^\..+\.(\d+)\.tmp\.png$"),
    re.compile(r"^.+\.tmp-(\d+)\.vtu$"),
)


def _process_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True  # exists (another user's) or can't tell: keep the file
    return True


def remove_stale_temp_files(folder: str | os.PathLike) -> list[Path]:
    """Delete temporary files that writers killed mid-write left in ``folder``.

    A writer interrupted by SIGKILL or a power cut can't clean up; its temporary file
    (never the target: targets are replaced by an atomic rename) stays behind. Files whose
    writer process is still alive are kept.

    Parameters
    ----------
    folder
        The folder to clear (a missing folder is fine).

    Returns
    -------
    list of pathlib.Path
        The files removed.
    """
    removed: list[Path] = []
    try:
        entries = list(Path(folder).iterdir())
    except (FileNotFoundError, NotADirectoryError):
        return removed
    for p in entries:
        for pattern in _TEMP_PATTERNS:
            m = pattern.match(p.name)
            if m and not _process_alive(int(m.group(1))):
                try:
                    p.unlink()
                    removed.append(p)
                except FileNotFoundError:
                    pass
                break
    return removed


def output_folder(command: str, name: str) -> Path:
    """The default output folder of a command: ``out/<command>-<name>``, one rule for all.

    Parameters
    ----------
    command
        The command (``solve``, ``compare``, ``verdict``, ``study``, ``sweep``).
    name
        What it ran on: the scene's name (with the model for ``solve``), or the sweep's.

    Returns
    -------
    pathlib.Path

    Examples
    --------
    >>> output_folder("compare", "../liver").as_posix()  # stays inside out/
    'out/compare-_liver'
    """
    return Path("out") / f"{command}-{safe_filename(name)}"


def safe_filename(name: str, limit: int = 80) -> str:
    """``name`` as one file or folder name that stays inside the folder it is joined to.

    Path separators (``/``, ``\\``), drive colons and non-printable characters become
    ``_``, leading dots are dropped (no ``.`` or ``..``, no hidden folders), and the result
    is cut to ``limit`` characters (``scene`` if nothing is left). Scene names pass through
    it when a scene is loaded, so ``out/<name>-<model>`` never leaves ``out``.

    Parameters
    ----------
    name
        Any string.
    limit
        Longest result.

    Returns
    -------
    str
        A non-empty, printable name without separators or leading dots.

    Examples
    --------
    >>> safe_filename("../../etc/x"), safe_filename("/abs"), safe_filename("Liver (coarse)")
    ('_.._etc_x', '_abs', 'Liver (coarse)')
    """
    text = "".join(c if c.isprintable() and c not in "/\\:" else "_" for c in name)
    return text.lstrip(".")[:limit] or "scene"


# Folders this process holds the lock of: path -> [open lock file descriptor, depth].
_LOCKED: dict[Path, list[int]] = {}


@contextlib.contextmanager
def folder_lock(folder: str | os.PathLike, what: str = "run") -> Iterator[None]:
    """Hold ``folder`` inside the block: a second process that asks for it is refused.

    Two sweeps or studies writing their cases into one folder would race on the same
    files; the lock (``fcntl.flock`` on ``folder/.lock``, released by the kernel when the
    holder exits, even by SIGKILL) makes the second one stop with one line instead. The
    same process may take it again inside the block (the blocks nest).

    Parameters
    ----------
    folder
        The folder (created if missing).
    what
        What holds it, for the message (``sweep``, ``study``).

    Raises
    ------
    InputError
        Another live process holds the folder.

    Examples
    --------
    >>> import tempfile
    >>> folder = tempfile.mkdtemp()
    >>> with folder_lock(folder), folder_lock(folder):  # this process again: fine
    ...     pass
    """
    import fcntl

    path = Path(folder).resolve()
    held = _LOCKED.get(path)
    if held is None:
        path.mkdir(parents=True, exist_ok=True)
        fd = os.open(path / ".lock", os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.read(fd, 32).decode(errors="replace").strip() or "?"
            os.close(fd)
            raise InputError(
                f"{path}: another {what} (pid {holder}) is writing its cases here; wait "
                "for it to finish or choose another --out"
            ) from None
        os.ftruncate(fd, 0)
        os.write(fd, str(os.getpid()).encode())
        held = _LOCKED[path] = [fd, 0]
    held[1] += 1
    try:
        yield
    finally:
        held[1] -= 1
        if held[1] == 0:
            del _LOCKED[path]
            os.close(held[0])  # releases the flock
