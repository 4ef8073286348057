"""Cases of the stability study: the cantilever bar, one run per series, the settings."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from springfem.errors import SolverError
from springfem.scene import Scene, scene_from_dict
from springmodel.options import SpringOptions

from ..metrics import timoshenko_tip_deflection
from .critical_step import measure_critical_step

SPRING_VARIANTS = ("energy", "cosine")
#: The exact spring element of issue 10 (method ``spring-exact``; DESIGN §4b).
EXACT = {"torsion": "energy", "volume": "axes", "calibration": "exact"}


def spring_options(scene: Scene, method: str) -> SpringOptions:
    """The spring options of a method: ``spring-<torsion>`` or ``spring-exact``."""
    if method == "spring-exact":
        return replace(SpringOptions.of(scene), **EXACT)
    return replace(SpringOptions.of(scene), torsion=method.split("-", 1)[1])


def bar_table(
    nx: int = 20,
    ny: int = 2,
    nu: float = 0.3,
    traction: float = -0.1,
    law: str = "linear",
    torsion: str = "energy",
) -> dict[str, Any]:
    """The table of the cantilever bar (0.1 × 0.01 × 0.01 m, E = 10 kPa, clamped at x = 0,
    end traction along z).

    Parameters
    ----------
    nx, ny
        Hexahedra along the bar and across it (six tets each).
    nu
        Poisson's ratio.
    traction
        End traction (Pa, along z).
    law
        Material law.
    torsion
        The spring model's torsion law.

    Returns
    -------
    dict
        The table for :func:`springfem.scene.scene_from_dict`.

    Examples
    --------
    >>> bar_table(10, 1)["mesh"]["divisions"]
    [10, 1, 1]
    """
    return {
        "name": "stability-bar",
        "mesh": {
            "generator": "box",
            "size": [0.1, 0.01, 0.01],
            "divisions": [nx, ny, ny],
            "split": "six",
        },
        "material": {"law": law, "E": 1.0e4, "nu": nu, "density": 1000.0},
        "axes": {"fiber": [1.0, 0.0, 0.0], "sheet": [0.0, 1.0, 0.0]},
        "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
        "load": [{"type": "traction", "region": "x_max", "value": [0.0, 0.0, traction]}],
        "probe": [{"name": "tip", "point": [0.1, 0.005, 0.005]}],
        "spring": {"torsion": torsion},
    }


def bar_scene(
    nx: int = 20,
    ny: int = 2,
    nu: float = 0.3,
    traction: float = -0.1,
    law: str = "linear",
    torsion: str = "energy",
) -> Scene:
    """The cantilever bar of :func:`bar_table` as a validated scene.

    Parameters
    ----------
    nx, ny, nu, traction, law, torsion
        As for :func:`bar_table`.

    Returns
    -------
    Scene
    """
    return scene_from_dict(bar_table(nx, ny, nu, traction, law, torsion))


def _system(scene: Scene, method: str):
    """A MechanicalSystem for explicit runs: spring variants or the explicit P1 FEM."""
    if method.startswith("spring-"):
        from springmodel.model import SpringModel

        return SpringModel(scene, spring_options(scene, method))
    from reference_fem.explicit import ExplicitFem

    return ExplicitFem(scene, law=method.split("-", 1)[1])


def _inverted(scene: Scene, u: np.ndarray) -> int:
    return int((scene.mesh.volumes(scene.mesh.points + u.reshape(-1, 3)) <= 0).sum())


# ----------------------------------------------------------------------- critical step


def critical_step_case(case: dict) -> dict:
    """Predicted and measured critical explicit step of one method on one mesh."""
    scene = bar_scene(case["nx"], case["ny"], traction=0.0)
    system = _system(scene, case["method"])
    dt_pred, omega, ratio = measure_critical_step(system, case["steps"], case["bisections"])
    out = {"dt_pred": dt_pred, "dt_measured": ratio * dt_pred, "ratio": ratio}
    if ratio == 2.0:
        out["bounded"] = True
    elif ratio == ratio:  # not nan: bisected
        out["omega_max"] = omega
    return out


# -------------------------------------------------------------------------- max load


def load_case(case: dict) -> dict:
    """Static solve of the bar at one load factor by one method; what (if anything) fails."""
    scene = bar_scene(case["nx"], case["ny"], traction=-0.1 * case["factor"])
    method = case["method"]
    try:
        if method.startswith("spring-"):
            from springmodel.model import solve_spring

            sol = solve_spring(scene, spring_options(scene, method))
            u = sol.u
        else:
            import reference_fem

            sol = reference_fem.solve(scene, order=1, law=method.split("-", 1)[1])
            u = sol.u_vertices
    except SolverError as exc:
        return {"status": "diverged", "message": str(exc)[:160], "tip": float("nan")}
    inv = _inverted(scene, u)
    tip = float(-scene.probe_displacements(u)["tip"][2])
    if inv:
        return {
            "status": "inverted",
            "inverted": inv,
            "tip": tip,
            "message": f"{inv} inverted elements",
        }
    if method == "fem-linear" and tip > 0.1 * 0.1:
        # small-strain kinematics: a deflection beyond 10% of the length is not a solution
        # of the large-deformation problem, however well the linear system solves
        return {
            "status": "unphysical",
            "inverted": 0,
            "tip": tip,
            "message": "linear kinematics beyond tip/L = 0.1",
        }
    return {"status": "ok", "inverted": 0, "tip": tip, "message": ""}


# ----------------------------------------------------------------------- locking


def locking_case(case: dict) -> dict:
    """Tip deflection (normalised by Timoshenko) and volume change at one ν."""
    scene = bar_scene(case["nx"], case["ny"], nu=case["nu"])
    method = case["method"]
    if method in ("spring", "spring-exact"):
        from springmodel.model import solve_spring

        sol = solve_spring(scene, spring_options(scene, method) if method != "spring" else None)
        res, u = sol.result, sol.u
    else:
        import reference_fem

        sol = reference_fem.solve(scene, order=int(method[-1]), law="linear")
        res, u = sol.result, sol.u_vertices
    ref = timoshenko_tip_deflection(0.1 * 1e-4, 0.1, 0.01, 0.01, 1.0e4, case["nu"])
    return {
        "tip_ratio": -res.probes["tip"][2] / ref,
        "volume_change": res.volume["relative_change"],
        "inverted": _inverted(scene, u),
    }


# -------------------------------------------------------------------- failure map


def failure_map_case(case: dict) -> dict:
    """Damped explicit dynamics at (load factor, dt factor): ok, blew up or inverted."""
    from springfem.mechanics import explicit, stable_time_step

    scene = bar_scene(case["nx"], case["ny"], traction=-0.1 * case["factor"])
    system = _system(scene, case["method"])
    dt_crit, omega = stable_time_step(system)
    # critical damping of the lowest bending mode is far below omega_max; a mass damping
    # of ~omega_max/200 brings the bar near rest within the run
    try:
        traj = explicit(
            system,
            dt=case["dt_factor"] * dt_crit,
            steps=case["steps"],
            mass_damping=omega / 200.0,
            record_every=case["steps"],
        )
    except SolverError as exc:
        status = "inverted" if "inverted" in str(exc) else "blew up"
        return {"status": status, "message": str(exc)[:160]}
    inv = _inverted(scene, traj.x - system.x0)
    return {"status": "inverted" if inv else "ok", "inverted": inv}


@dataclass(frozen=True)
class Settings:
    """Grids of the stability study (bars of ``nx × ny × ny`` hexahedra).

    Parameters
    ----------
    dt_meshes, dt_steps, dt_bisections
        Meshes, run length and bisection count of the critical-time-step search.
    load_factors, load_mesh
        Load multiples and mesh of the largest-load series.
    nus, lock_mesh
        Poisson ratios and mesh of the locking series.
    map_loads, map_dt_factors, map_steps
        Load multiples, time-step factors and run length of the failure map (10 × 1 × 1).
    scene, scene_path
        A user scene table and its file (``study stability --scene``; see :mod:`.scene`).
    """

    dt_meshes: tuple[tuple[int, int], ...] = ((10, 1), (20, 2))
    dt_steps: int = 2000
    dt_bisections: int = 6
    load_factors: tuple[float, ...] = (1, 10, 100, 300, 1000, 3000, 10000, 30000)
    load_mesh: tuple[int, int] = (20, 2)
    nus: tuple[float, ...] = (0.3, 0.4, 0.45, 0.49, 0.495, 0.499)
    lock_mesh: tuple[int, int] = (40, 4)
    map_loads: tuple[float, ...] = (1, 100, 1000, 3000, 10000, 30000)
    map_dt_factors: tuple[float, ...] = (0.3, 0.6, 0.9, 1.0, 1.1, 1.5)
    map_steps: int = 3000
    scene: dict | None = None
    scene_path: str | None = None

    @classmethod
    def full(cls) -> Settings:
        """The report's grids."""
        return cls()

    @classmethod
    def for_scene(cls, table: dict, path: str | None = None, quick: bool = False) -> Settings:
        """The critical-step, largest-load and failure-map series on a user scene.

        Parameters
        ----------
        table, path
            The scene table and its file.
        quick
            Shorter runs, fewer load and time-step factors (see :mod:`.scene`).

        Returns
        -------
        Settings
        """
        from .scene import SCENE_FULL, SCENE_QUICK

        return cls(**(SCENE_QUICK if quick else SCENE_FULL), scene=table, scene_path=path)

    @classmethod
    def quick(cls) -> Settings:
        """Coarse grids: one mesh per series, fewer loads, factors and steps."""
        return cls(
            dt_meshes=((10, 1),),
            dt_steps=400,
            dt_bisections=4,
            load_factors=(1, 100, 1000, 3000, 10000),
            load_mesh=(10, 1),
            nus=(0.3, 0.45, 0.49, 0.499),
            lock_mesh=(20, 2),
            map_loads=(1, 1000, 10000),
            map_dt_factors=(0.5, 0.9, 1.1),
            map_steps=800,
        )


# ------------------------------------------------------------------------------ grids

#: Methods of the explicit series (critical step) and of the static largest-load series.
DYNAMIC_METHODS = (
    "spring-energy",
    "spring-cosine",
    "fem-neo-hookean",
    "fem-linear",
    "spring-exact",
)
LOAD_METHODS = ("spring-energy", "spring-cosine", "fem-linear", "fem-neo-hookean", "spring-exact")
LOCK_METHODS = ("fem-p1", "fem-p2", "spring", "spring-exact")
MAP_METHODS = ("spring-energy", "spring-cosine", "fem-neo-hookean")
#: Mesh of the failure map.
MAP_MESH = (10, 1)


def grids(q: Settings) -> dict[str, list[dict]]:
    """The cases of the four series.

    Parameters
    ----------
    q
        The study's settings.

    Returns
    -------
    dict
        ``dt``, ``load``, ``lock`` and ``map`` -> their cases (for
        :func:`critical_step_case`, :func:`load_case`, :func:`locking_case`,
        :func:`failure_map_case`).
    """
    dt = [
        {
            "kind": "dt",
            "method": m,
            "nx": nx,
            "ny": ny,
            "steps": q.dt_steps,
            "bisections": q.dt_bisections,
        }
        for m in DYNAMIC_METHODS
        for nx, ny in q.dt_meshes
    ]
    nx, ny = q.load_mesh
    load = [
        {"kind": "load", "method": m, "factor": f, "nx": nx, "ny": ny}
        for m in LOAD_METHODS
        for f in q.load_factors
    ]
    nx, ny = q.lock_mesh
    lock = [
        {"kind": "lock", "method": m, "nu": nu, "nx": nx, "ny": ny}
        for m in LOCK_METHODS
        for nu in q.nus
    ]
    nx, ny = MAP_MESH
    fmap = [
        {
            "kind": "map",
            "method": m,
            "factor": f,
            "dt_factor": d,
            "nx": nx,
            "ny": ny,
            "steps": q.map_steps,
        }
        for m in MAP_METHODS
        for f in q.map_loads
        for d in q.map_dt_factors
    ]
    return {"dt": dt, "load": load, "lock": lock, "map": fmap}
