"""Cases of the scaling study: the benchmark block, one explicit-step and one static case."""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from springfem.scene import scene_from_dict

from .. import models
from ..scenes import StudyScene, case_scene

TORSION = "energy"
REPEATS = 5
VERSION = 2


@dataclass(frozen=True)
class Settings:
    """Target tet counts of the explicit-step and static-solve series.

    Parameters
    ----------
    step
        Tet counts of the explicit-step series.
    static
        Tet counts of the static-solve series.
    neo_max
        Largest tet count of the neo-Hookean Newton solve.
    """

    step: tuple[int, ...] = (1_000, 3_000, 10_000, 30_000, 100_000, 200_000)
    static: tuple[int, ...] = (1_000, 3_000, 10_000, 30_000, 100_000)
    neo_max: int = 30_000  # the neo-Hookean Newton solve at 1e5 tets alone costs ~20 s

    @classmethod
    def full(cls) -> Settings:
        """Up to 200,000 tets."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """Up to 100,000 tets (explicit) and 10,000 (static)."""
        return cls(step=(1_000, 10_000, 100_000), static=(1_000, 3_000, 10_000), neo_max=10_000)


def bench_table(n_tets: int = 100_000) -> dict:
    """The table of the benchmark block: 2:1:1 with about ``n_tets`` tets (six per
    hexahedron), clamped at ``x_min`` and pulled down at ``x_max``, FEM P1 with AMG.

    Examples
    --------
    >>> bench_table(1_000)["mesh"]["divisions"]
    [8, 4, 4]
    """
    k = max(1, round((n_tets / 12.0) ** (1.0 / 3.0)))
    return {
        "name": f"bench-{12 * k**3}",
        "mesh": {"generator": "box", "size": [2.0, 1.0, 1.0], "divisions": [2 * k, k, k]},
        "material": {"law": "linear", "E": 1.0e4, "nu": 0.3},
        "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
        "load": [{"type": "traction", "region": "x_max", "value": [0.0, 0.0, -1.0]}],
        "probe": [{"name": "tip", "point": [2.0, 0.5, 0.5]}],
        "fem": {"order": 1, "linear_solver": "amg"},
        "spring": {"torsion": TORSION},
    }


def bench_scene(n_tets: int, role: str) -> StudyScene:
    """The benchmark block of about ``n_tets`` tets as a study scene serving ``role``."""
    table = bench_table(n_tets)
    return StudyScene(table["name"], table, roles=(role,), params={"n_tets": n_tets})


def bundled_scenes(p: Settings) -> list[StudyScene]:
    """The blocks of the explicit-step (``step``) and static-solve (``static``) series."""
    return [bench_scene(n, "step") for n in p.step] + [bench_scene(n, "static") for n in p.static]


def _clock():
    return time.perf_counter(), time.process_time()


def _since(t):
    return time.perf_counter() - t[0], time.process_time() - t[1]


def step_case(case: dict) -> dict:
    """Set-up and per-step cost of the spring model and the explicit P1 FEM (serial)."""
    from ..bench import step_costs
    from ..timing import median, median_ratio

    scene = case_scene(case)
    t = _clock()
    spring = models.SPRING.system(scene)
    spring_setup = _since(t)
    t = _clock()
    fem = models.P1_NH.system(scene)  # the explicit P1 FEM, neo-Hookean
    fem_setup = _since(t)
    steps = int(np.clip(2_000_000 // scene.mesh.n_tets, 5, 200))
    systems = {"spring": spring, "fem": fem}
    samples = step_costs(systems, steps, case["repeats"])  # interleaved, shuffled
    out = {
        "tets": scene.mesh.n_tets,
        "nodes": scene.mesh.n_points,
        "steps": steps,
        "spring_setup_wall": spring_setup[0],
        "spring_setup_cpu": spring_setup[1],
        "fem_setup_wall": fem_setup[0],
        "fem_setup_cpu": fem_setup[1],
    }
    for name in systems:
        out[f"{name}_step_wall"] = median(samples, name) / steps
        out[f"{name}_step_cpu"] = median(samples, name, "cpu") / steps
    out["ratio_cpu"] = median_ratio(samples, "spring", "fem", "cpu")
    return out


def _static_solve(scene, method: str):
    """A static solve by a model of :data:`STATIC_METHODS` (the spring model: static Newton)."""
    if method == "spring":
        from springmodel.model import solve_spring

        opts = replace(models.SPRING.spring_options(scene), solver="static", tol=1e-8)
        return solve_spring(scene, opts, parallel=False)
    import reference_fem

    fem_scene, order, law = models.get(method).fem_settings(scene)
    return reference_fem.solve(fem_scene, order=order, law=law)


_WARM: set[str] = set()


def static_case(case: dict) -> dict:
    """One static solve (from the scene, set-up included) by one method."""
    method = case["method"]
    if method not in _WARM:  # imports and compilation are not part of the cost
        _static_solve(scene_from_dict(bench_table(100)), method)
        _WARM.add(method)
    scene = case_scene(case)
    t = _clock()
    sol = _static_solve(scene, method)
    wall, cpu = _since(t)
    if method == "spring":
        linear_solver = getattr(sol.info, "linear_solver", "")
    else:
        linear_solver = str(sol.result.info.get("linear_solver", ""))
    return {
        "tets": scene.mesh.n_tets,
        "wall": wall,
        "cpu": cpu,
        "dofs": 3 * scene.mesh.n_points,
        "iterations": sol.result.iterations,
        "tip": sol.result.probes["tip"],
        "linear_solver": linear_solver,
    }


STATIC_METHODS = {
    "spring": "spring model, static Newton",
    "P1": "FEM P1 linear, static",
    "P1-NH": "FEM P1 neo-Hookean, Newton",
}


def grids(scenes: list[StudyScene], p: Settings) -> tuple[list[dict], list[dict]]:
    """The explicit-step and static-solve cases of the blocks (roles ``step``, ``static``;
    no neo-Hookean FEM above ``p.neo_max`` tets).
    """
    step_cases = [
        s.case("scaling", VERSION, kind="step", repeats=REPEATS, torsion=TORSION)
        for s in scenes
        if s.serves("step")
    ]
    static_cases = [
        s.case("scaling", VERSION, kind="static", method=m, torsion=TORSION)
        for s in scenes
        if s.serves("static")
        for m in STATIC_METHODS
        if not (m == "P1-NH" and s.params["n_tets"] > p.neo_max)
    ]
    return step_cases, static_cases
