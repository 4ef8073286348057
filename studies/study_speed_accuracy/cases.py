"""Cases of the speed-accuracy study: settings, the cantilever scenes, one timed solve."""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from springfem.errors import SolverError
from springfem.scene import Scene, scene_from_dict
from springmodel.options import SpringOptions

from ..compare import bundled_scene
from ..metrics import timoshenko_tip_deflection

#: The spring model's torsion law here: the energy-consistent one (conservative, so static
#: Newton has an analytic Hessian and explicit dynamics conserve energy).
TORSION = "energy"
#: Static / implicit tolerances (relative residual).
STATIC_TOL = 1e-8
IMPLICIT_TOL = 1e-6
STEP_REPEATS = 7
STEP_COUNT = 20

FEM_STATIC = {
    "fem-p1-linear": (1, "linear"),
    "fem-p1-neo-hookean": (1, "neo-hookean/coupled"),
    "fem-p2-linear": (2, "linear"),
    "fem-p2-neo-hookean": (2, "neo-hookean/coupled"),
}
#: The exact spring element of issue 10 (DESIGN §4b).
EXACT = {"volume": "axes", "torsion": "energy", "calibration": "exact"}
#: Methods of the exact element (points added to the seed model's).
EXACT_METHODS = ("spring-exact-static", "spring-exact-explicit")
LABELS = {
    "spring-exact-static": "exact spring element, static Newton",
    "spring-exact-explicit": "exact spring element, explicit to rest",
    "spring-static": "spring, static Newton",
    "spring-implicit": "spring, implicit to rest",
    "spring-explicit": "spring, explicit to rest",
    "fem-explicit-p1-neo-hookean": "explicit P1 FEM (neo-Hookean), to rest",
    "fem-p1-linear": "FEM P1 linear, static",
    "fem-p1-neo-hookean": "FEM P1 neo-Hookean, static",
    "fem-p2-linear": "FEM P2 linear, static",
    "fem-p2-neo-hookean": "FEM P2 neo-Hookean, static",
}
STYLE = {  # marker, colour
    "spring-exact-static": ("*", "tab:brown"),
    "spring-exact-explicit": ("*", "tab:gray"),
    "spring-static": ("o", "tab:red"),
    "spring-implicit": ("o", "tab:orange"),
    "spring-explicit": ("o", "tab:pink"),
    "fem-explicit-p1-neo-hookean": ("^", "tab:purple"),
    "fem-p1-linear": ("s", "tab:blue"),
    "fem-p1-neo-hookean": ("s", "tab:cyan"),
    "fem-p2-linear": ("D", "tab:green"),
    "fem-p2-neo-hookean": ("D", "tab:olive"),
}


@dataclass(frozen=True)
class Settings:
    """Meshes and solver settings of the speed-accuracy study.

    Parameters
    ----------
    meshes
        ``(nx, ny)`` cantilever meshes (``nx × ny × ny`` hexahedra) of the points.
    reference
        ``(nx, ny)`` of the fine P2 reference.
    explicit
        ``(tol, dt_safety)`` settings of the explicit runs.
    implicit
        Time-step factor of the implicit runs -> largest ``(nx, ny)`` it runs on.
    scene, scene_path
        A user scene table and its file (``study speed-accuracy --scene``; see :mod:`.scene`).
    scene_levels, scene_costly_levels
        Refinement levels of the user scene (1: its own mesh), and those of the costly
        points (explicit runs, neo-Hookean FEM).
    """

    meshes: tuple[tuple[int, int], ...] = ((10, 1), (20, 2), (40, 4))
    reference: tuple[int, int] = (60, 6)
    explicit: tuple[tuple[float, float], ...] = ((1e-3, 0.3), (1e-6, 0.3), (1e-6, 0.5))
    implicit: dict[float, tuple[int, int]] = field(
        default_factory=lambda: {100.0: (20, 2), 1e4: (40, 4)}
    )
    scene: dict | None = None
    scene_path: str | None = None
    scene_levels: tuple[int, ...] = (1, 2, 3)
    scene_costly_levels: tuple[int, ...] = (1, 2)

    @classmethod
    def full(cls) -> Settings:
        """Three meshes up to 40 × 4 × 4, reference 60 × 6 × 6."""
        return cls()

    @classmethod
    def for_scene(cls, table: dict, path: str | None = None, quick: bool = False) -> Settings:
        """Every method on a user scene's refinement levels (see :mod:`.scene`).

        Parameters
        ----------
        table
            The scene table.
        path
            The scene file.
        quick
            Levels 1-2 (costly points on level 1) instead of 1-3 (costly points on 1-2).

        Returns
        -------
        Settings
        """
        if quick:
            return cls(scene=table, scene_path=path, scene_levels=(1, 2),
                       scene_costly_levels=(1,))  # fmt: skip
        return cls(scene=table, scene_path=path)

    @classmethod
    def quick(cls) -> Settings:
        """Two meshes, reference 40 × 4 × 4."""
        return cls(
            meshes=((10, 1), (20, 2)),
            reference=(40, 4),
            explicit=((1e-6, 0.5),),
            implicit={100.0: (10, 1), 1e4: (20, 2)},  # dt factor -> largest mesh
        )


def cantilever_table(nx: int, ny: int) -> dict:
    """The bundled cantilever scene's table with ``nx x ny x ny`` hexahedra.

    Parameters
    ----------
    nx, ny
        Hexahedra along the beam and across it.

    Returns
    -------
    dict
        The table for :func:`springfem.scene.scene_from_dict`.

    Examples
    --------
    >>> cantilever_table(6, 1)["mesh"]["divisions"]
    [6, 1, 1]
    """
    return bundled_scene("cantilever", (nx, ny, ny))


def _scene(case: dict) -> Scene:
    scene = scene_from_dict(case["scene"])
    return scene.with_options(spring=replace(SpringOptions.of(scene), torsion=TORSION))


def timoshenko_tip(scene: Scene) -> float:
    """Timoshenko tip deflection (m, positive down) of the cantilever scene."""
    lo, hi = scene.mesh.bounding_box()
    L, b, h = (hi - lo).tolist()
    traction = scene.loads[0].value
    force = float(-traction[2]) * b * h
    return timoshenko_tip_deflection(force, L, b, h, scene.material.E, scene.material.nu)


def _solve(scene: Scene, method: str, setting: dict) -> tuple[np.ndarray, dict]:
    """Run one method on a scene: vertex displacement and solver facts."""
    if method in FEM_STATIC:
        import reference_fem

        order, law = FEM_STATIC[method]
        sol = reference_fem.solve(scene, order=order, law=law)
        return sol.u_vertices, {"iterations": sol.result.iterations}
    from springfem.mechanics import explicit_static, implicit, stable_time_step

    exact = EXACT if method.startswith("spring-exact") else {}
    if method in ("spring-static", "spring-exact-static"):
        from springmodel.model import solve_spring

        opts = replace(SpringOptions.of(scene), solver="static", tol=STATIC_TOL, **exact)
        sol = solve_spring(scene, opts, parallel=None)
        return sol.u, {"iterations": sol.result.iterations}
    if method == "fem-explicit-p1-neo-hookean":
        from reference_fem.explicit import ExplicitFem

        system = ExplicitFem(scene, law="neo-hookean")
    else:
        from springmodel.model import SpringModel

        opts = replace(SpringOptions.of(scene), **exact) if exact else None
        system = SpringModel(scene, opts, parallel=None)
    if method == "spring-implicit":
        dt = setting["dt_factor"] * stable_time_step(system)[0]
        traj = implicit(system, dt=dt, steps=5000, equilibrium_tol=IMPLICIT_TOL)
        if not traj.converged:
            raise SolverError(traj.message, state=traj.x - system.x0)
        return traj.x - system.x0, {"steps": traj.steps, "iterations": traj.iterations}
    info = explicit_static(
        system, tol=setting["tol"], dt_safety=setting["dt_safety"], max_steps=400_000
    )
    return info.x - system.x0, {"steps": info.steps, "dt": info.dt}


_WARM: set[str] = set()


def _warm_up(method: str, setting: dict) -> None:
    """Run a method once on a tiny mesh so compilation and imports are not timed."""
    if method in _WARM:
        return
    tiny = {"scene": cantilever_table(4, 1)}
    loose = dict(setting, tol=1e-2) if "tol" in setting else setting
    try:
        _solve(_scene(tiny), method, loose)
    except SolverError:
        pass
    _WARM.add(method)


def point_case(case: dict) -> dict:
    """One (method, mesh, setting) point: wall time from the scene to the answer, tip."""
    scene = _scene(case)
    _warm_up(case["method"], case["setting"])
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        u, facts = _solve(scene, case["method"], case["setting"])
    except SolverError as exc:
        msg = str(exc)
        status = "blew up" if "blew up" in msg or "inverted" in msg else "failed"
        return {
            "status": status,
            "seconds": time.perf_counter() - t0,
            "cpu_seconds": time.process_time() - c0,
            "message": msg[:240],
        }
    return {
        "status": "ok",
        "seconds": time.perf_counter() - t0,
        "cpu_seconds": time.process_time() - c0,
        "tip": scene.probe_displacements(u)["tip"],
        "tets": scene.mesh.n_tets,
        **facts,
    }


def reference_case(case: dict) -> dict:
    """The reference tip displacement: P2 linear on the finest mesh."""
    import reference_fem

    scene = _scene(case)
    sol = reference_fem.solve(scene, order=2, law="linear")
    return {
        "tip": sol.result.probes["tip"],
        "tets": scene.mesh.n_tets,
        "timoshenko": timoshenko_tip(scene),
    }


def step_count(n_tets: int) -> int:
    """Explicit steps per timed repeat: about 0.2 M element evaluations (>~10 ms)."""
    return int(np.clip(200_000 // max(n_tets, 1), STEP_COUNT, 500))


def step_cost_case(case: dict) -> dict:
    """Cost of one explicit step, spring model and explicit P1 FEM, measured alternately."""
    from reference_fem.explicit import ExplicitFem
    from springmodel.model import SpringModel

    from ..bench import step_costs
    from ..timing import median, median_ratio

    scene = _scene(case)
    systems = {"spring": SpringModel(scene, parallel=None), "fem": ExplicitFem(scene)}
    samples = step_costs(systems, case["steps"], case["repeats"])  # interleaved, shuffled
    out = {"tets": scene.mesh.n_tets}
    for name in systems:
        out[f"{name}_wall"] = median(samples, name) / case["steps"]
        out[f"{name}_cpu"] = median(samples, name, "cpu") / case["steps"]
    out["ratio_wall"] = median_ratio(samples, "spring", "fem")
    out["ratio_cpu"] = median_ratio(samples, "spring", "fem", "cpu")
    out["parallel"] = {
        k: bool(
            getattr(s, "parallel", False) or getattr(getattr(s, "kernel", None), "parallel", False)
        )
        for k, s in systems.items()
    }
    return out


def cases_for(p: Settings) -> list[dict]:
    """All (method, mesh, setting) points of a plan."""
    out = []
    for nx, ny in p.meshes:
        base = {
            "kind": "point",
            "mesh": [nx, ny],
            "scene": cantilever_table(nx, ny),
            "torsion": TORSION,
        }
        for method in FEM_STATIC:
            out.append({**base, "method": method, "setting": {}})
        out.append({**base, "method": "spring-static", "setting": {"tol": STATIC_TOL}})
        out.append({**base, "method": "spring-exact-static", "setting": {"tol": STATIC_TOL}})
        for factor, (mx, _) in p.implicit.items():
            if nx <= mx:
                out.append(
                    {
                        **base,
                        "method": "spring-implicit",
                        "setting": {"dt_factor": factor, "tol": IMPLICIT_TOL},
                    }
                )
        for tol, safety in p.explicit:
            for method in ("spring-explicit", "fem-explicit-p1-neo-hookean"):
                out.append({**base, "method": method, "setting": {"tol": tol, "dt_safety": safety}})
        tol, safety = p.explicit[-1]  # the exact element: the last explicit setting only
        out.append(
            {
                **base,
                "method": "spring-exact-explicit",
                "setting": {"tol": tol, "dt_safety": safety},
            }
        )
    return out
