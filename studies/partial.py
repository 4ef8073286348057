"""A solve that stopped part way along its load, reported at the load it reached.

A static solve that steps the load and stops (Newton gave up) raises a
:class:`~springfem.errors.SolverError` with the last converged state and its
``load_factor``; :func:`partial_solution` turns it into a
:class:`~springfem.model_api.ModelSolution`
marked ``partial`` (probes, volume, ventricle cavity at that load) and :func:`partial_row`
into a comparison-table row.

Examples
--------
>>> import numpy as np
>>> from springfem.errors import SolverError
>>> from springfem.mesh import box_mesh
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({"mesh": {"generator": "box", "size": [1, 1, 1],
...     "divisions": [1, 1, 1]}, "material": {"law": "linear", "E": 1e4, "nu": 0.3},
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}]})
>>> u = np.zeros((scene.mesh.n_points, 3))
>>> sol = partial_solution(scene, "spring", SolverError("stopped", state=u, load_factor=0.5))
>>> sol.result.status, sol.result.info["load_factor"]
('partial', 0.5)
>>> partial_solution(scene, "spring", SolverError("singular")) is None  # no state
True
"""

from __future__ import annotations

import numpy as np

from springfem.errors import SolverError
from springfem.result import Result
from springfem.scene import Scene

from .solve import Solution, state_result

#: Displacement components by index, for the table's column names.
COMPONENTS = "xyz"


def partial_solution(
    scene: Scene, model: str, exc: SolverError, wall_time: float = float("nan")
) -> Solution | None:
    """The state a load-stepped solve stopped at, as a :class:`Solution` marked partial.

    Parameters
    ----------
    scene
        The scene that was solved.
    model
        ``spring`` or ``fem`` (the result's model).
    exc
        The solve's error: ``state`` the displacement ``(n, 3)`` at ``load_factor``.
    wall_time
        Seconds the solve ran.

    Returns
    -------
    Solution or None
        Probes, volume (and cavity, on a ventricle) at the load reached, ``status``
        ``partial``, ``info["load_factor"]``; ``None`` when the error has no state or no
        load factor (it did not stop part way along a load path).
    """
    load_factor = getattr(exc, "load_factor", None)
    if load_factor is None or exc.state is None:
        return None
    u = np.asarray(exc.state, dtype=float).reshape(-1, 3)
    if u.shape[0] != scene.mesh.n_points or not np.isfinite(u).all():
        return None
    res = state_result(scene, model, u, exc, "partial", "partial", wall_time=wall_time)
    return Solution(res, u)


def partial_row(row: dict, r: Result, main: dict[str, int]) -> dict:
    """The comparison-table row of a model that stopped at ``r.info["load_factor"]``.

    Parameters
    ----------
    row
        The row so far (``model``), updated.
    r
        The partial result (:func:`partial_solution`).
    main
        Probe name -> the component shown (the reference's largest).

    Returns
    -------
    dict
        ``row`` with status ``partial``, load factor, probes, volume change and wall time.
    """
    row.update({"status": "partial", "load factor": r.info["load_factor"], "element": r.element})
    row["law"] = r.law
    for probe, c in main.items():
        u = np.asarray(r.probes.get(probe, [np.nan] * 3))
        row[f"{probe} |u| (m)"] = float(np.linalg.norm(u))
        row[f"{probe} u{COMPONENTS[c]} (m)"] = float(u[c])
    row["volume change"] = r.volume.get("relative_change", np.nan)
    row["wall time (s)"] = r.wall_time
    row["converged"] = False
    return row
