"""The result contract: the same fields for every model (docs/contract.rst#result-fields).

A :class:`Result` is written as ``result.json`` (atomically) next to a VTU file with the
displacement and per-element data for ParaView.

Examples
--------
>>> from springfem.mesh import box_mesh
>>> m = box_mesh((1.0, 1.0, 1.0), (1, 1, 1))
>>> u = 0.1 * m.points * [1.0, 0.0, 0.0]  # stretch x by 10 %
>>> round(volume_summary(m, u)["relative_change"], 12)
0.1
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .files import atomic_write_text, jsonable, remove_stale_temp_files
from .mesh import TetMesh, displacement_gradients, write_vtu

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
        Solver outcome. A dynamic (timed) run has no convergence: ``converged`` is false
        and ``status`` says "end of run at t = …" and whether it reached rest.
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
    status: str = ""
    """``converged``, ``end of run at t = … s after N steps: at rest|still moving``, or
    ``stopped …`` (a time or step cap); empty when the model does not say."""

    def to_dict(self) -> dict[str, Any]:
        """The fields as plain Python (see :func:`~springfem.files.jsonable`).

        Returns
        -------
        dict
        """
        return jsonable(asdict(self))

    def to_json(self) -> str:
        """The fields as indented JSON with sorted keys (the ``result.json`` text).

        Returns
        -------
        str
        """
        return json.dumps(self.to_dict(), indent=2, sort_keys=True)


def volume_summary(mesh: TetMesh, u: np.ndarray) -> dict[str, float]:
    """Initial and final (deformed) mesh volume and their relative change.

    Parameters
    ----------
    mesh
        The mesh at rest.
    u
        Nodal displacement, ``(n, 3)`` or flat ``(3 n,)``.

    Returns
    -------
    dict
        ``initial``, ``final`` and ``relative_change`` (``(final - initial) / initial``).
    """
    v0 = float(mesh.volumes().sum())
    v1 = float(mesh.volumes(mesh.points + np.asarray(u).reshape(-1, 3)).sum())
    return {"initial": v0, "final": v1, "relative_change": (v1 - v0) / v0}


def frame_cell_data(scene, u: np.ndarray) -> dict[str, np.ndarray]:
    """The anisotropy fields of a VTU: frames, fibre stretch and (rule-based) depth.

    Parameters
    ----------
    scene
        A :class:`~springfem.scene.Scene` (its frames and mesh).
    u
        ``(n, 3)`` or flat vertex displacement.

    Returns
    -------
    dict
        ``fiber``, ``sheet`` (unit vectors at rest, ``(m, 3)``), ``fiber_stretch``
        ``|F f|`` with ``F`` the tet's linear (vertex) deformation gradient, and
        ``transmural_depth`` when the mesh has it (``[axes] type = "rule-based"``).

    Examples
    --------
    >>> from springfem.mesh import box_mesh
    >>> from types import SimpleNamespace
    >>> m = box_mesh((1.0, 1.0, 1.0), (1, 1, 1))
    >>> s = SimpleNamespace(mesh=m, frames=np.tile(np.eye(3), (m.n_tets, 1, 1)))
    >>> d = frame_cell_data(s, 0.2 * m.points * [1.0, 0.0, 0.0])  # 20 % along the fibre
    >>> np.round(d["fiber_stretch"], 12).tolist() == [1.2] * m.n_tets
    True
    """
    mesh = scene.mesh
    F = np.eye(3) + displacement_gradients(mesh.points, mesh.tets, u)
    f = np.asarray(scene.frames)[:, 0]
    out = {
        "fiber": f,
        "sheet": np.asarray(scene.frames)[:, 1],
        "fiber_stretch": np.linalg.norm(np.einsum("kij,kj->ki", F, f), axis=1),
    }
    if "transmural_depth" in mesh.cell_data:
        out["transmural_depth"] = np.asarray(mesh.cell_data["transmural_depth"])
    return out


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

    Parameters
    ----------
    out_dir
        Output folder (created; stale temporary files of killed writers are removed).
    result
        What goes into the JSON file.
    mesh
        The mesh of the VTU file.
    displacement
        Nodal ``(n, 3)`` on the mesh's vertices (point data ``displacement``).
    cell_data, point_data
        More per-tet and per-node arrays for the VTU file.
    stem
        File name without extension.

    Returns
    -------
    tuple of pathlib.Path
        The JSON and the VTU file.
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
    curve = result.info.get("cavity", {}).get("pressure_volume")
    if curve:
        from .cardiac import write_pressure_volume

        write_pressure_volume(out / f"{stem}_pressure_volume", curve, result.scene)
    return js, vtu
