"""``springfem bench tissue``: the FEM's tissue solves of Land's beam and ventricle, by phase.

Cases (``--cases``; names ``<scene>-<form>``): for each of Land's beam
(``studies/scenes/land-beam.toml``, ``--divisions``) and ventricle
(``studies/scenes/land-ventricle.toml``, ``--size`` mm):

``P1``
    the displacement formulation on P1 with the spring model's penalty
    (:func:`reference_fem.fitting.tissue_scene`, the ``P1`` model of :mod:`studies.models`);
``P2``
    the same penalised displacement formulation on P2 (slow: stiff, many load cutbacks);
``mixed``
    the scene's own P2/P1 Taylor–Hood solve (the reference);
``ngsolve``
    the same mixed problem solved by NGSolve (:mod:`studies.ngsolve_peer`), when it imports.

The default set leaves out the two ``P2`` solves (each costs several mixed solves);
``--cases all`` runs everything, ``--cases beam`` one scene's cases.

Timing rules (:mod:`studies.timing`): every case runs once in every round, in a shuffled
order; figures are medians over rounds of wall and CPU time; a case's ratio to its scene's
mixed solve (and NGSolve's to ours) is the median of per-round ratios; the machine's load
average is printed beside them. Each solve's own phase table (``result.info
["phase_seconds"]``: assembly, factorization, solve, line search, predictor; ``setup`` is
the rest of the wall time: spaces, loads, post-processing) gives the per-phase medians.
Before the timed rounds, every form is solved once on a tiny beam (imports, caches).

Examples
--------
>>> select_cases("beam,ventricle-mixed", ngsolve=False)
['beam-P1', 'beam-P2', 'beam-mixed', 'ventricle-mixed']
>>> select_cases("default", ngsolve=False)
['beam-P1', 'beam-mixed', 'ventricle-P1', 'ventricle-mixed']
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from springfem.errors import InputError
from springfem.scene import Scene

from .timing import median, median_ratio, timed

#: Bundled scene of each scene key.
SCENES = {"beam": "land-beam", "ventricle": "land-ventricle"}
#: The forms, in table order.
FORMS = ("P1", "P2", "mixed", "ngsolve")
#: Forms of the default run (the penalised P2 solves are opt-in).
DEFAULT_FORMS = ("P1", "mixed", "ngsolve")
DEFAULT_REPEATS = 3
DEFAULT_SIZE = 4.0
DEFAULT_DIVISIONS = (30, 3, 3)
#: Phases of a Newton solve (:mod:`reference_fem.newton`), in table order.
PHASES = ("assembly", "factorization", "solve", "line search", "predictor", "setup")
#: What a form is, for the table.
FORM_LABELS = {
    "P1": "P1 displacement (penalty)",
    "P2": "P2 displacement (penalty)",
    "mixed": "P2/P1 mixed",
    "ngsolve": "NGSolve P2/P1 mixed",
}


def all_cases(ngsolve: bool = True) -> list[str]:
    """Every case name, ``<scene>-<form>``, in table order."""
    return [f"{s}-{f}" for s in SCENES for f in FORMS if ngsolve or f != "ngsolve"]


def select_cases(spec: str | None, ngsolve: bool = True) -> list[str]:
    """The cases a ``--cases`` value names (comma-separated case names, scene names,
    ``default`` or ``all``), in table order.

    Raises
    ------
    InputError
        An unknown name (the message lists the valid ones).
    """
    valid = all_cases(ngsolve=True)
    chosen: set[str] = set()
    for word in (spec or "default").split(","):
        word = word.strip()
        if word == "all":
            chosen.update(valid)
        elif word == "default":
            chosen.update(c for c in valid if c.split("-", 1)[1] in DEFAULT_FORMS)
        elif word in SCENES:
            chosen.update(c for c in valid if c.startswith(f"{word}-"))
        elif word in valid:
            chosen.add(word)
        else:
            raise InputError(
                f"bench tissue: unknown case {word!r}; valid: all, default, "
                f"{', '.join(SCENES)}, {', '.join(valid)}"
            )
    return [c for c in all_cases(ngsolve) if c in chosen]


def land_scenes(size: float = DEFAULT_SIZE, divisions=DEFAULT_DIVISIONS) -> dict[str, Scene]:
    """Land's beam at ``divisions`` and ventricle at element ``size`` (mm)."""
    from springfem.scene.loader import named_scene

    from .overrides import read_scene_table, scene_with_overrides

    sets = {
        "beam": [("mesh.divisions", [int(d) for d in divisions])],
        "ventricle": [("mesh.size", float(size))],
    }
    out = {}
    for key, name in SCENES.items():
        path = named_scene(Path(name))
        out[key] = scene_with_overrides(read_scene_table(path), sets[key], path)
    return out


def form_scene(scene: Scene, form: str) -> Scene:
    """The scene the FEM solves for a form (``P1``, ``P2`` or ``mixed``)."""
    from reference_fem.fitting import tissue_scene
    from reference_fem.options import FemOptions

    if form == "mixed":
        return scene
    p1 = tissue_scene(scene, 1)
    if form == "P1":
        return p1
    return p1.with_options(fem=replace(FemOptions.of(p1), order=2))


class _Case:
    """One timed solve; keeps the info of every call (phases, iterations, probes)."""

    def __init__(self, scene: Scene, form: str):
        self.scene, self.form = scene, form
        self.calls: list[dict] = []

    def __call__(self) -> None:
        t0 = time.perf_counter()
        if self.form == "ngsolve":
            from .ngsolve_peer import solve_mixed

            peer = solve_mixed(self.scene)
            wall = time.perf_counter() - t0
            self.calls.append({"wall": wall, "phases": {"newton": wall - peer.setup_seconds,
                               "setup": peer.setup_seconds}, "iterations": peer.iterations,
                               "probes": peer.probes, "dofs": peer.info["dofs"],
                               "info": peer.info})  # fmt: skip
            return
        import reference_fem

        sol = reference_fem.solve(self.scene)
        wall = time.perf_counter() - t0
        r = sol.result
        ph = dict(r.info.get("phase_seconds", {}))
        ph.pop("cpu_total", None)
        inside = ph.pop("total", 0.0)
        ph["setup"] = wall - sum(ph.values()) if inside else wall
        self.calls.append({"wall": wall, "phases": ph, "iterations": r.iterations,
                           "probes": r.probes, "dofs": r.counts["dofs"],
                           "info": {"intorder": r.info.get("intorder"),
                                    "load_steps": r.info.get("load_steps"),
                                    "direct_solver": r.info.get("direct_solver"),
                                    "factorizations": r.info.get("factorizations")}})  # fmt: skip


def warm_up(forms) -> None:
    """Solve each of ``forms`` once on a tiny beam (imports, caches), untimed."""
    tiny = land_scenes(divisions=(4, 1, 1))["beam"]
    for form in forms:
        _Case(tiny if form == "ngsolve" else form_scene(tiny, form), form)()


def agreement(ours: dict, peer: dict) -> dict[str, float]:
    """Per probe: ``max_i |u_peer - u_ours|_i / max_i |u_ours|_i``."""
    out = {}
    for name, u in ours.items():
        a, b = np.asarray(peer[name], dtype=float), np.asarray(u, dtype=float)
        out[name] = float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))
    return out


def bench_tissue(
    repeats: int = DEFAULT_REPEATS,
    cases: str | None = None,
    size: float = DEFAULT_SIZE,
    divisions=DEFAULT_DIVISIONS,
    warmup: bool = True,
) -> dict:
    """Interleaved timings of the tissue solves (module docstring).

    Parameters
    ----------
    repeats
        Rounds.
    cases
        ``--cases`` value (:func:`select_cases`).
    size, divisions
        Ventricle element size (mm) and beam divisions.
    warmup
        Solve every form once on a tiny beam first.

    Returns
    -------
    dict
        ``rows`` (one per case: medians, phases, ratio to the scene's mixed solve, probes),
        ``ratios``, ``agreement`` (NGSolve vs ours, per probe), ``machine``, ``notes``.
    """
    from .ngsolve_peer import available

    missing = available()
    names = select_cases(cases, ngsolve=missing is None)
    if not names:
        raise InputError("bench tissue: no case to run (NGSolve is not installed)")
    scenes = land_scenes(size, divisions)
    runs = {}
    for name in names:
        key, form = name.split("-", 1)
        s = scenes[key]
        runs[name] = _Case(s if form == "ngsolve" else form_scene(s, form), form)
    if warmup:
        warm_up([f for f in FORMS if any(n.endswith(f"-{f}") for n in names)])
    samples, info = timed(dict(runs.items()), rounds=repeats, warmup=0)
    rows = []
    for name, case in runs.items():
        key, form = name.split("-", 1)
        ref = f"{key}-mixed"
        phases = {p: float(np.median([c["phases"].get(p, 0.0) for c in case.calls]))
                  for p in sorted({p for c in case.calls for p in c["phases"]},
                                  key=lambda p: (PHASES + ("newton",)).index(p))}  # fmt: skip
        last = case.calls[-1]
        ratio = median_ratio(samples, name, ref) if ref in runs and ref != name else None
        rows.append(
            {
                "name": name,
                "scene": SCENES[key],
                "form": form,
                "label": FORM_LABELS[form],
                "tets": int(case.scene.mesh.n_tets),
                "dofs": int(last["dofs"]),
                "wall_seconds": median(samples, name),
                "cpu_seconds": median(samples, name, "cpu"),
                "phase_seconds": phases,
                "iterations": int(last["iterations"]),
                "ratio_to_mixed": ratio,
                "probes": last["probes"],
                "info": last["info"],
            }
        )
    ratios, agree = {}, {}
    for key in SCENES:
        ours, peer = f"{key}-mixed", f"{key}-ngsolve"
        if ours in runs and peer in runs:
            ratios[f"ngsolve_over_ours[{key}]"] = median_ratio(samples, peer, ours)
            ratios[f"ngsolve_over_ours_cpu[{key}]"] = median_ratio(samples, peer, ours, "cpu")
            agree[key] = agreement(runs[ours].calls[-1]["probes"], runs[peer].calls[-1]["probes"])
    notes = []
    if missing:
        notes.append(missing)
    left = [c for c in all_cases(missing is None) if c not in names]
    if left:
        notes.append(f"not run: {', '.join(left)} (--cases all runs every case)")
    return {
        "benchmark": "tissue",
        "rounds": repeats,
        "size_mm": float(size),
        "divisions": [int(d) for d in divisions],
        "rows": rows,
        "ratios": ratios,
        "agreement": agree,
        "quadrature": {
            "tet_degree": 2,
            "tet_points": 4,
            "pressure_triangle_degree": 4,
            "pressure_triangle_points": 6,
        },
        "notes": notes,
        "machine": info,
    }
