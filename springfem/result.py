"""The result contract: the same fields for every model (DESIGN §6).

A :class:`Result` is written as ``result.json`` (atomically) next to a VTU file with the
displacement and per-element data for ParaView.
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .files import atomic_write_text, jsonable, remove_stale_temp_files
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
        return jsonable(asdict(self))

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2, sort_keys=True)


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
