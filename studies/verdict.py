"""The verdict on a scene: is the spring model good enough, and how fast is it against FEM?

:func:`verdict` runs every model of :mod:`studies.models` that applies to the scene against
its best reference (the finest FEM of the scene's law: P2, neo-Hookean P2 at large strain,
the scene's own formulation for tissue), and measures for each

- the error of its static solution against the reference (relative L2 over the vertices);
- the wall time of its static solve, after a warm-up solve of the model on a 12-tet box
  of the scene's material and options (so that imports, compiled kernels and solver
  set-up are not charged to whichever model runs first);
- for the models with an explicit form (the spring variants, the explicit P1 FEM), the cost
  of one explicit step (median of interleaved rounds) and the stable step ``2 / omega_max``,
  hence the cost of one simulated second, ``cost per step / stable step``.

It then names the cheapest model within the tolerance, for static solves and for explicit
dynamics separately, and says it in a plain sentence. A time budget caps each solve with the
time left; a reference that does not finish falls back to the next finest FEM among the
models weighed, with a note.
Models whose options resolve to the same element on this scene are solved once (a note says
which are the same).

Examples
--------
A block of transversely isotropic material in uniaxial stress (a uniform strain: P1 is
exact, and the exact spring element is P1's element at small strain):

>>> from studies.overrides import load_scene_with
>>> scene = load_scene_with("studies/scenes/stretch-cross.toml", ["mesh.divisions=[2, 2, 2]"])
>>> v = verdict(scene, tolerance=0.05, models=("spring-spec", "spring-exact", "P1", "P2"),
...             rounds=1)
>>> v.reference, v.static_pick in ("spring-exact", "P1")
('P2', True)
>>> bool(v.table.set_index("model").at["spring-spec", "within tolerance"])  # calibration
False
"""

from __future__ import annotations

import contextlib
import io
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from springfem.mechanics.limits import solve_limits
from springfem.scene import Scene

from . import fem_laws, metrics, models
from .compare import LARGE_STRAIN, max_principal_strain
from .timing import interleaved, median

#: Default tolerance: the largest relative L2 error a model may have to count.
TOLERANCE = 0.05
#: Explicit steps per timing of the step cost.
STEPS = 20
#: Cap of each model's warm-up solve (s).
WARM_UP_SECONDS = 10.0


@dataclass
class Verdict:
    """The outcome of :func:`verdict`.

    Attributes
    ----------
    scene
        The scene's name.
    tolerance
        The error tolerance.
    reference
        The reference model.
    table
        One row per model: status, error, static time, step cost, stable step, cost per
        simulated second, and whether it is within the tolerance.
    static_pick, dynamic_pick
        The cheapest model within the tolerance for static solves and for explicit
        dynamics (``None``: none qualifies).
    sentence
        The answer in words.
    notes
        What was skipped, merged or substituted, and why.
    """

    scene: str
    tolerance: float
    reference: str
    table: pd.DataFrame
    static_pick: str | None
    dynamic_pick: str | None
    sentence: str
    notes: list[str] = field(default_factory=list)


def candidate_models(scene: Scene) -> list[str]:
    """The primary models (:func:`studies.models.candidates`: :data:`~studies.models.PRIMARY`
    and the default plug-ins) that apply to ``scene``.

    Parameters
    ----------
    scene
        The scene.

    Returns
    -------
    list of str
    """
    out = []
    for m in map(models.get, models.candidates()):
        if m.name == "fem" or m.applies(scene) is not None:
            continue
        if m.kind == "spring" and not _spring_builds(m, scene):
            continue
        out.append(m.name)
    return out


def _spring_builds(m: models.Model, scene: Scene) -> bool:
    """Whether the spring variant's options are valid for the scene's law (a stiffening
    needs a modulus the law gives, e.g.)."""
    try:
        opts = m.spring_options(scene)
    except (ValueError, TypeError):
        return False
    if opts.stiffening != "off" and opts.stiffening_modulus is None:
        return scene.material.law in ("guccione", "holzapfel-ogden")
    return True


def _same_element(scene: Scene, names: list[str]) -> dict[str, str]:
    """Spring models whose options resolve to the same element: name -> the first one."""
    seen: dict[Any, str] = {}
    alias = {}
    for n in names:
        m = models.get(n)
        if m.kind != "spring":
            continue
        key = repr(m.spring_options(scene))
        if key in seen:
            alias[n] = seen[key]
        else:
            seen[key] = n
    return alias


def reference_model(scene: Scene, p1_strain: float) -> str:
    """The scene's best reference: P2 of its law (neo-Hookean when it is or at large strain).

    Parameters
    ----------
    scene
        The scene.
    p1_strain
        The largest principal Green–Lagrange strain of its small-strain P1 solution.

    Returns
    -------
    str
    """
    if fem_laws.is_tissue(scene) or scene.material.law == "transverse-linear":
        return "P2"
    if scene.material.law == "neo-hookean" or p1_strain > LARGE_STRAIN:
        return "P2-NH"
    return "P2"


def _step_costs(scene: Scene, names: list[str], rounds: int) -> dict[str, tuple[float, float]]:
    """Per model with an explicit form: (seconds per explicit step, stable step)."""
    from springfem.mechanics import stable_time_step

    systems, dts = {}, {}
    for n in names:
        m = models.get(n)
        if m.kind == "fem" and m.order == 2:
            continue
        try:
            s = m.system(scene)
            dts[n] = stable_time_step(s)[0]
        except Exception:  # noqa: BLE001 - a model with no explicit form on this scene
            continue
        systems[n] = s
    if not systems:
        return {}

    def step(s):
        x, v = s.x0.copy(), np.zeros_like(s.x0)

        def run():
            for _ in range(STEPS):
                s.forces(x, v)

        return run

    samples = interleaved({n: step(s) for n, s in systems.items()}, rounds=rounds)
    return {n: (median(samples, n) / STEPS, dts[n]) for n in systems}


def verdict(
    scene: Scene,
    tolerance: float = TOLERANCE,
    budget: float | None = None,
    models: tuple[str, ...] | None = None,
    rounds: int = 5,
    log=None,
) -> Verdict:
    """The verdict on ``scene`` (see the module docstring).

    Parameters
    ----------
    scene
        The scene.
    tolerance
        Largest relative L2 error against the reference that counts as good enough.
    budget
        Seconds for the whole verdict (``None``: no cap); each solve gets the time left.
    models
        The models to weigh (default :func:`candidate_models`).
    rounds
        Interleaved rounds of the step-cost timing.
    log
        Called with one line per finished model.

    Returns
    -------
    Verdict
    """
    from . import models as registry

    say = log or (lambda _line: None)
    t0 = time.perf_counter()
    notes: list[str] = []
    names = list(models) if models is not None else candidate_models(scene)
    names = [registry.get(n).name for n in names]
    alias = _same_element(scene, names)
    for n, first in alias.items():
        notes.append(f"{n} is the same element as {first} on this scene: solved once")
    outcomes: dict[str, registry.Outcome] = {}

    def left() -> float | None:
        return None if budget is None else max(budget - (time.perf_counter() - t0), 1e-3)

    warm = warm_up_scene(scene)

    def run(name: str) -> registry.Outcome:
        if name in outcomes:
            return outcomes[name]
        if name in alias:
            outcomes[name] = run(alias[name])
            return outcomes[name]
        if warm is not None:  # its outcome and warnings do not matter
            cap = min(WARM_UP_SECONDS, left() or WARM_UP_SECONDS)
            with solve_limits(max_time=cap), contextlib.redirect_stderr(io.StringIO()):
                registry.run(warm, name)
        with solve_limits(max_time=left()):
            got = registry.run(scene, name)
        outcomes[name] = got
        say(f"  {name:<18} {got.status} in {got.seconds:.2f} s")
        return got

    p1 = run("P1")
    strain = max_principal_strain(scene, p1.u) if p1.ok else float("nan")
    ref = reference_model(scene, strain)
    preference = [ref] + [n for n in ("P2", "P2-NH", "P1-NH", "P1") if n in names]
    for cand in dict.fromkeys(preference):
        if registry.get(cand).applies(scene) is not None:
            continue
        if run(cand).ok:
            if cand != ref:
                why = outcomes[ref].message if ref in outcomes else "not run"
                notes.append(f"the reference {ref} did not finish ({why}); {cand} stands in")
            ref = cand
            break
    else:
        ref = ""
        notes.append("no FEM reference finished: errors are not computed")
    for n in names:
        run(n)
    u_ref = outcomes[ref].u if ref else None
    costs = _step_costs(scene, [n for n in names if outcomes[n].ok], rounds)
    rows = []
    for n in names:
        got = outcomes[n]
        err = (
            metrics.relative_l2_error(got.u, u_ref)
            if got.ok and u_ref is not None and n != ref
            else (0.0 if n == ref and got.ok else float("nan"))
        )
        step, dt = costs.get(n, (float("nan"), float("nan")))
        rows.append(
            {
                "model": n,
                "status": got.status,
                "rel L2 error": err,
                "static time (s)": got.solution.result.wall_time if got.ok else float("nan"),
                "step cost (s)": step,
                "stable step (s)": dt,
                "cost per simulated s": step / dt if np.isfinite(step) and dt > 0 else np.nan,
                "within tolerance": bool(got.ok and np.isfinite(err) and err <= tolerance),
                "message": got.message[:160],
            }
        )
    table = pd.DataFrame(rows)
    ok = table[table["within tolerance"] & (table["model"] != ref)]
    static_pick = _cheapest(ok, "static time (s)")
    dynamic_pick = _cheapest(ok, "cost per simulated s")
    sentence = _sentence(scene.name, table, ref, tolerance, static_pick, dynamic_pick)
    return Verdict(scene.name, tolerance, ref, table, static_pick, dynamic_pick, sentence, notes)


def warm_up_scene(scene: Scene) -> Scene | None:
    """A 12-tet box with ``scene``'s material, frame and model options, for warm-up solves.

    Parameters
    ----------
    scene
        The scene.

    Returns
    -------
    Scene or None
        The box (clamped at ``x_min``, a small traction at ``x_max``), or ``None`` when
        the scene's sections do not fit a box.
    """
    import copy

    from springfem.errors import SpringFemError
    from springfem.scene import scene_from_dict

    raw = copy.deepcopy(scene.raw)
    pts = scene.mesh.points
    size = np.maximum(pts.max(axis=0) - pts.min(axis=0), 1e-12)
    frame = scene.frames[0]
    mu = float(getattr(scene.material, "mu", 0.0) or 1.0)
    raw["name"] = f"{scene.name}-warm-up"
    raw["mesh"] = {"generator": "box", "size": size.tolist(), "divisions": [2, 1, 1]}
    raw["axes"] = {"type": "uniform", "fiber": frame[0].tolist(), "sheet": frame[1].tolist()}
    raw["boundary"] = [{"region": "x_min", "fix": ["x", "y", "z"]}]
    raw["load"] = [{"type": "traction", "region": "x_max", "value": [0.0, 0.0, -1e-4 * mu]}]
    for key in ("probe", "output"):
        raw.pop(key, None)
    try:
        return scene_from_dict(raw)
    except SpringFemError:
        return None


def _cheapest(rows: pd.DataFrame, column: str) -> str | None:
    rows = rows[np.isfinite(rows[column])]
    return None if rows.empty else str(rows.loc[rows[column].idxmin(), "model"])


def _spring_row(table: pd.DataFrame) -> pd.Series | None:
    """The most accurate spring model that solved."""
    s = table[table.model.str.startswith("spring") & (table.status == "ok")]
    s = s[np.isfinite(s["rel L2 error"])]
    return None if s.empty else s.loc[s["rel L2 error"].idxmin()]


def _sentence(
    name: str,
    table: pd.DataFrame,
    ref: str,
    tol: float,
    static_pick: str | None,
    dynamic_pick: str | None,
) -> str:
    """The verdict in words: the best spring model's error and speed against P1, the picks."""
    t = table.set_index("model")
    sp = _spring_row(table)
    parts = []
    if sp is not None and "P1" in t.index and t.at["P1", "status"] == "ok":
        m = sp["model"]
        step = sp["step cost (s)"] / t.at["P1", "step cost (s)"]
        stat = sp["static time (s)"] / t.at["P1", "static time (s)"]
        speed = f"{_times(step)} P1 per explicit step" if np.isfinite(step) else "no explicit step"
        parts.append(
            f"on {name} the best spring model ({m}) is {sp['rel L2 error']:.1%} off {ref} "
            f"(P1: {t.at['P1', 'rel L2 error']:.1%}), {speed} and {_times(stat)} P1 "
            "per static solve"
        )
    elif sp is None:
        parts.append(f"on {name} no spring model solved")
    within = f"within {tol:.0%} of {ref}"
    parts.append(
        f"{static_pick} is the cheapest {within} for a static solve"
        if static_pick
        else f"no model but the reference is {within} for a static solve"
    )
    if dynamic_pick:
        parts.append(f"{dynamic_pick} the cheapest for explicit dynamics (per simulated second)")
    else:
        parts.append("for explicit dynamics no model within it qualifies")
    return "; ".join(parts) + "."


def _times(ratio: float) -> str:
    """``1.5x slower than`` / ``2.0x faster than`` / ``as fast as``."""
    if not np.isfinite(ratio):
        return "?"
    if abs(ratio - 1.0) < 0.05:
        return "as fast as"
    return f"{ratio:.1f}x slower than" if ratio > 1 else f"{1 / ratio:.1f}x faster than"
