"""The result contract: the same fields for every model (DESIGN §6).

A :class:`Result` is written as ``result.json`` (atomically) next to a VTU file with the
displacement and per-element data for ParaView.
"""

from __future__ import annotations

import json
import os
import re
import tempfile
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .mesh import TetMesh, write_vtu

TIMING_FIELDS = ("wall_time",)


@dataclass
class Result:
    """Outcome of one solve.

    Attributes
    ----------
    scene, model, element, law
        What was solved: scene name, ``spring`` or ``fem``, element (``P1``, ``P2``,
        ``spring``), material law (and spring variant).
    counts
        ``nodes``, ``tets``, ``dofs``, ``fixed_dofs``.
    probes
        Probe name -> displacement ``[ux, uy, uz]``.
    volume
        ``initial``, ``final`` and ``relative_change`` of the mesh volume.
    reactions
        Fixed-region name -> total reaction force ``[Fx, Fy, Fz]`` (force the support
        exerts on the body).
    wall_time
        Seconds spent solving (excluding file output).
    converged, iterations
        Solver outcome.
    info
        Model-specific extras (e.g. time step, energy history, calibration mismatch).
    """

    scene: str
    model: str
    element: str
    law: str
    counts: dict[str, int]
    probes: dict[str, list[float]]
    volume: dict[str, float]
    reactions: dict[str, list[float]]
    wall_time: float
    converged: bool
    iterations: int
    info: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return _jsonable(asdict(self))

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2, sort_keys=True)


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
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
    """Write ``text`` to ``path`` via a temporary file in the same folder and a rename."""
    path = Path(path)
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
    writer process is still alive are kept. Returns the files removed.
    """
    removed = []
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


def safe_filename(name: str, limit: int = 80) -> str:
    """``name`` as one file or folder name that stays inside the folder it is joined to.

    Path separators (``/``, ``\\``), drive colons and non-printable characters become
    ``_``, leading dots are dropped (no ``.`` or ``..``, no hidden folders), and the result
    is cut to ``limit`` characters (``scene`` if nothing is left). Scene names pass through
    it when a scene is loaded, so ``out/<name>-<model>`` never leaves ``out``.

    Examples
    --------
    >>> safe_filename("../../etc/x"), safe_filename("/abs"), safe_filename("Liver (coarse)")
    ('_.._etc_x', '_abs', 'Liver (coarse)')
    """
    text = "".join(c if c.isprintable() and c not in "/\\:" else "_" for c in name)
    return text.lstrip(".")[:limit] or "scene"


def volume_summary(mesh: TetMesh, u: np.ndarray) -> dict[str, float]:
    """Initial and final (deformed) mesh volume and their relative change."""
    v0 = float(mesh.volumes().sum())
    v1 = float(mesh.volumes(mesh.points + np.asarray(u).reshape(-1, 3)).sum())
    return {"initial": v0, "final": v1, "relative_change": (v1 - v0) / v0}


def write_result(
    out_dir: str | os.PathLike,
    result: Result,
    mesh: TetMesh,
    displacement: np.ndarray,
    cell_data: dict[str, np.ndarray] | None = None,
    point_data: dict[str, np.ndarray] | None = None,
    stem: str = "result",
) -> tuple[Path, Path]:
    """Write ``<stem>.json`` and ``<stem>.vtu`` into ``out_dir`` (both atomically).

    ``displacement`` is nodal ``(n, 3)`` on the mesh's vertices.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    remove_stale_temp_files(out)
    vtu = out / f"{stem}.vtu"
    pdata = {"displacement": np.asarray(displacement).reshape(-1, 3)}
    pdata.update(point_data or {})
    write_vtu(vtu, mesh, point_data=pdata, cell_data=cell_data)
    js = out / f"{stem}.json"
    atomic_write_text(js, result.to_json() + "\n")
    return js, vtu
