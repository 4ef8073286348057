"""``springfem bench lockfree``: the locking-free models against P1-NH on an organ mesh.

On a liver-shaped gmsh organ of about ``--tets`` tets (:func:`springfem.mesh.organ.organ_scene`,
neo-Hookean, nu = 0.49, gravity), interleaved rounds (:mod:`studies.timing`) of

- the explicit step (forces + symplectic-Euler update) and the bare force pass of the
  stabilised spring element (``spring-stabilised``) and of explicit P1-NH, serial and on all
  threads, and the parts of the spring element's pass (its element kernel, the nodal strain,
  the nodal volume);
- the internal force of nodal-strain P1 (``fem-P1-nodal-strain``: the Newton solve's force,
  numpy; it has no explicit system);
- with ``--solves K``, ``K`` interleaved rounds of the static solves of the three models.

Ratios are medians of per-round ratios against P1-NH: wall time against its serial step, CPU
time against its case of the same kind (less sensitive to other processes on a shared
machine); the machine's load average is printed beside them.
"""

from __future__ import annotations

import tempfile

from springfem.model_api import declared

from .bench import STEP_COUNT, step_and_force_cases
from .timing import deformed_state, median, median_ratio, timed

DEFAULT_TETS = 5000
#: The models compared, the reference last.
MODELS = ("spring-stabilised", "fem-P1-nodal-strain", "P1-NH")


def organ(n_tets: int):
    """The organ scene of about ``n_tets`` tets (written to a temporary folder, loaded)."""
    from springfem.mesh.organ import organ_scene
    from springfem.scene import load_scene

    with tempfile.TemporaryDirectory() as folder:
        return load_scene(organ_scene(folder, tets=n_tets))


def bench_lockfree(n_tets: int = DEFAULT_TETS, repeats: int = 7, solves: int = 0,
                   steps: int = STEP_COUNT) -> dict:  # fmt: skip
    """Explicit steps, force passes and (``solves > 0``) static solves, interleaved.

    Parameters
    ----------
    n_tets
        Approximate organ size.
    repeats
        Rounds of the steps and force passes.
    solves
        Rounds of the static solves (0: none).
    steps
        Steps (and force passes) per timing.

    Returns
    -------
    dict
        ``rows`` (per-step seconds and the ratio to P1-NH's serial step), ``solves``, the
        machine.
    """
    from reference_fem.explicit import ExplicitFem
    from reference_fem.solver import make_problem
    from springmodel.model import SpringModel
    from studies.models import get

    scene = organ(n_tets)
    spring = get("spring-stabilised")
    options = spring.spring_options(scene)
    systems = {
        "spring-stabilised, serial": SpringModel(scene, options, parallel=False),
        "spring-stabilised, parallel": SpringModel(scene, options, parallel=True),
        "P1-NH, serial": ExplicitFem(scene, law="neo-hookean", parallel=False),
        "P1-NH, parallel": ExplicitFem(scene, law="neo-hookean", parallel=True),
    }
    twin = systems["spring-stabilised, parallel"].nodal_strain
    if hasattr(twin, "average"):
        twin.average = _parallel_copy(twin.average)
    x = deformed_state(scene.mesh.points)
    cases = step_and_force_cases(systems, x, steps)
    sm = systems["spring-stabilised, serial"]
    parts = {
        "element kernel": lambda: sm.kernel.forces(x),
        "nodal strain": lambda: sm.nodal_strain.forces(x),
        "nodal volume": lambda: sm.nodal.term.forces(x),
    }
    for name, fn in parts.items():
        cases[f"spring-stabilised part: {name}"] = lambda fn=fn: [fn() for _ in range(steps)]
    fem_scene, order, law = get("fem-P1-nodal-strain").fem_settings(scene)
    problem = make_problem(fem_scene, order=order, law=law)
    u = (x - scene.mesh.points).ravel()
    cases["fem-P1-nodal-strain: internal force"] = lambda: [
        problem.internal_force(u) for _ in range(steps)
    ]
    samples, info = timed(cases, rounds=repeats)
    ref = "P1-NH, serial: step"
    rows = [
        {
            "case": name,
            "seconds": median(samples, name) / steps,
            "over_p1_nh_step": median_ratio(samples, name, ref),
            "cpu_seconds": median(samples, name, "cpu") / steps,
            "cpu_over_p1_nh": median_ratio(samples, name, _twin(name), "cpu"),
        }
        for name in cases
    ]
    out = {
        "benchmark": "lockfree",
        "n_tets": scene.mesh.n_tets,
        "n_nodes": scene.mesh.n_points,
        "rounds": repeats,
        "steps_per_timing": steps,
        "grouped_nodal_strain": bool(getattr(sm.nodal_strain, "grouped", False)),
        "virtual_elements": int(sm.nodal_strain.elements.n_elements),
        "rows": rows,
        "machine": info,
    }
    if solves > 0:
        out["solves"] = static_solves(scene, solves)
    return out


def _twin(name: str) -> str:
    """The P1-NH case a case's CPU time is compared with: the same kind (step or forces) and
    threads; P1-NH's serial force pass for the parts and the nodal-strain FEM."""
    for kind in ("step", "forces"):
        for threads in ("serial", "parallel"):
            if name.endswith(f"{threads}: {kind}"):
                return f"P1-NH, {threads}: {kind}"
    return "P1-NH, serial: forces"


def _parallel_copy(average):
    """A copy of a :class:`~springfem.mesh.nodal_average.NodalAverage` run on all threads."""
    from copy import copy

    twin = copy(average)
    twin.parallel = True
    return twin


def warm_up(scene) -> None:
    """One tangent and energy of every model at a deformed state: the compiled kernels of a
    Newton step are loaded (or compiled) before the first timed solve."""
    from reference_fem.solver import make_problem
    from studies.models import get

    x = deformed_state(scene.mesh.points)
    for name in MODELS:
        model = get(name)
        if declared(model, "spring_options", scene) is not None:
            system = model.system(scene)
            system.stiffness(x, 1.0)
            system.energy(x, 1.0)
            continue
        fem_scene, order, law = model.fem_settings(scene)
        problem = make_problem(fem_scene, order=order, law=law)
        problem.internal_force((x - scene.mesh.points).ravel(), tangent=True)


def static_solves(scene, rounds: int) -> dict:
    """Interleaved static solves of :data:`MODELS` (their wall times and ratios to P1-NH)."""
    from studies.models import run

    status: dict[str, list[str]] = {m: [] for m in MODELS}

    def solve(name):
        out = run(scene, name)
        status[name].append(out.status)

    cases = {name: (lambda name=name: solve(name)) for name in MODELS}
    warm_up(scene)
    samples, info = timed(cases, rounds=rounds, warmup=0)
    return {
        "rounds": rounds,
        "rows": [
            {
                "model": name,
                "seconds": median(samples, name),
                "over_p1_nh": median_ratio(samples, name, "P1-NH"),
                "status": sorted(set(status[name])),
            }
            for name in MODELS
        ],
        "machine": info,
    }
