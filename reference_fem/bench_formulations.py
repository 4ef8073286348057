"""The cost of one Newton iteration per formulation, timed in interleaved rounds.

One iteration is what :class:`~reference_fem.newton.FemStep` does each time: residual and
tangent (``assembly``), the linear solver's factorisation (``factorization``: LU or the AMG
hierarchy) and one solve. The formulations take turns within each round on the same scene,
so that a shared, noisy machine slows them alike; the medians over the rounds and their
ratios to the first formulation are reported with the load average
(docs/verification.rst#how-speed-is-measured). Run it as
``python -m reference_fem.bench_formulations [divisions] [all]`` (Cook's membrane,
neo-Hookean; ``all`` adds MINI and Taylor–Hood P2/P1).

Examples
--------
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({
...     "mesh": {"generator": "cook", "divisions": [2, 2, 1]},
...     "material": {"law": "neo-hookean", "E": 1.0, "nu": 0.49},
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}]})
>>> out = iteration_times(scene, {"P1": {"order": 1},
...                               "nodal": {"order": 1, "formulation": "nodal-volume"}}, 2)
>>> sorted(out["median"]), out["ratio"]["P1"]
(['P1', 'nodal'], 1.0)
"""

from __future__ import annotations

import os
import sys
import time

import numpy as np

from springfem.scene import Scene

from .solver import make_problem


def _with_fem(scene: Scene, fem: dict) -> Scene:
    """``scene`` with its ``[fem]`` section replaced by the table ``fem``."""
    from springfem.scene import TableReader

    from .options import parse_fem_options

    return scene.with_options(fem=parse_fem_options(TableReader(dict(fem), "fem", "<bench>")))


def _one_iteration(problem) -> dict[str, float]:
    u = np.zeros(problem.n_dofs)
    t0 = time.perf_counter()
    R, K, symmetric, _ = problem.residual_tangent(u, 1.0)
    t1 = time.perf_counter()
    factor = problem.linear_solver.factorize(K, problem.free, symmetric)
    factor.solve(-R)
    t2 = time.perf_counter()
    return {"assembly": t1 - t0, "factorization": t2 - t1, "total": t2 - t0}


def iteration_times(scene: Scene, formulations: dict[str, dict], rounds: int = 5) -> dict:
    """Median wall time of one Newton iteration per formulation, interleaved.

    Parameters
    ----------
    scene
        The scene (its mesh, law and constraints).
    formulations
        Name -> ``[fem]`` table (e.g. ``{"order": 1, "formulation": "nodal-volume"}``).
    rounds
        Rounds; each runs every formulation once, in turn.

    Returns
    -------
    dict
        ``median`` (name -> phase -> seconds), ``ratio`` (total time over the first
        formulation's), ``n_dofs`` per name, ``rounds`` and ``loadavg`` (before, after).
    """
    problems = {k: make_problem(_with_fem(scene, v)) for k, v in formulations.items()}
    load_before = os.getloadavg()
    times: dict[str, list[dict]] = {k: [] for k in problems}
    for _ in range(rounds):
        for name, problem in problems.items():
            times[name].append(_one_iteration(problem))
    median = {
        k: {ph: float(np.median([t[ph] for t in v])) for ph in v[0]} for k, v in times.items()
    }
    first = median[next(iter(median))]["total"]
    return {
        "median": median,
        "ratio": {k: round(v["total"] / first, 3) for k, v in median.items()},
        "n_dofs": {k: int(p.n_dofs) for k, p in problems.items()},
        "rounds": rounds,
        "loadavg": (load_before, os.getloadavg()),
    }


def main(argv: list[str] | None = None) -> None:  # pragma: no cover - a command
    """Print the interleaved timing on Cook's membrane (``divisions``, default 48 48 4;
    ``all``: MINI and Taylor–Hood too)."""
    from springfem.scene import scene_from_dict

    argv = sys.argv[1:] if argv is None else argv
    every = "all" in argv  # also MINI and Taylor-Hood
    div = [int(a) for a in argv if a.isdigit()][:3] or [48, 48, 4]
    scene = scene_from_dict(
        {
            "mesh": {"generator": "cook", "divisions": div},
            "material": {"law": "neo-hookean", "E": 240.565, "nu": 0.4999},
            "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
            "load": [{"type": "traction", "region": "x_max", "value": [0.0, 2.0, 0.0]}],
        }
    )
    forms: dict[str, dict] = {
        "P1": {"order": 1},
        "nodal-volume": {"order": 1, "formulation": "nodal-volume"},
        "nodal-strain": {"order": 1, "formulation": "nodal-strain"},
    }
    if every:
        forms.update(mini={"order": 1, "formulation": "mini"})
        forms.update(mixed={"order": 2, "formulation": "mixed"})
    out = iteration_times(scene, forms, rounds=7)
    print(f"Cook's membrane {div}: {scene.mesh.n_tets} tets, loadavg {out['loadavg']}")
    for k, v in out["median"].items():
        phases = ", ".join(f"{ph} {s:.3f} s" for ph, s in v.items())
        print(f"  {k:14s} dofs {out['n_dofs'][k]}: {phases}; ratio {out['ratio'][k]}")


if __name__ == "__main__":  # pragma: no cover
    main()
