"""``springfem compare``: the spring model against FEM P1 and P2 on the same mesh.

:func:`compare_scene` runs the models, picks the reference (the finest FEM solution: P2,
neo-Hookean when the strains are large) and tabulates probe displacements, errors against
the reference, volume change, reactions, wall time and convergence.
Its output (sentences, figures, the ``springfem compare`` command) is in
:mod:`studies.compare_output`.

The models are those of :mod:`studies.models` (``spring``, ``P1``, ``P2``, and ``P1-NH``,
``P2-NH`` when the scene's law is neo-Hookean or its strains are large,
:data:`LARGE_STRAIN`; never for a tissue law; on a nearly incompressible scene the
locking-free methods too, with P2/P1 mixed as the reference of a hyperelastic law:
:mod:`studies.models`); any registered model may be asked for.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from reference_fem.fitting import is_tissue, tissue_note
from springfem.errors import InputError, SolverError
from springfem.model_api import ModelSolution as Solution
from springfem.scene import Scene

from . import metrics
from .metrics import max_principal_strain
from .models import (
    LARGE_STRAIN,
    formulation_notes,
    locking_free_models,
    locking_note,
    mixed_reference,
    reference_model,
    same_solves,
)
from .models import get as get_model
from .models import run as run_model
from .partial import partial_row

#: The models a comparison runs by default (neo-Hookean ones when strains are large).
MODELS = ("spring", "P1", "P2", "P1-NH", "P2-NH")

REFERENCE_PREFERENCE = ("fem-P2-mixed", "P2-NH", "P2", "P1-NH", "P1", "fem")
COMPONENTS = "xyz"


@dataclass
class Comparison:
    """The outcome of :func:`compare_scene`.

    Attributes
    ----------
    scene
        The scene that was solved.
    table
        One row per model (see :func:`comparison_table`).
    solutions
        Model name -> :class:`~springfem.model_api.ModelSolution` (only the models that succeeded).
    reference
        Name of the reference solution (the finest FEM solution).
    strain
        Max |principal Green–Lagrange strain| of the P1 linear solution (nan if not run).
    failures
        Model name -> error message of models that failed.
    notes
        Sentences about the choices made (why neo-Hookean was or was not run).
    partial
        Model name -> the state a failed model stopped at part way along its load
        (:func:`studies.solve.partial_solution`): reported in the table at its load
        factor, never ranked against the reference.
    implausible
        Model name -> why its solution is implausible
        (:func:`springfem.plausibility.check_solution`); it stays in ``solutions`` and
        its row's status is ``implausible``.
    extra
        The locking-free models added to the default ones on a nearly incompressible
        scene (their failure is a row of the table, not a failed comparison).
    """

    scene: Scene
    table: pd.DataFrame
    solutions: dict[str, Solution]
    reference: str
    strain: float = float("nan")
    failures: dict[str, str] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    partial: dict[str, Solution] = field(default_factory=dict)
    implausible: dict[str, str] = field(default_factory=dict)
    extra: tuple[str, ...] = ()

    @property
    def same_mesh_p1(self) -> str | None:
        """The P1 solution with the reference's law (for the spring model's *model* error)."""
        nh = self.reference.endswith("-NH") or (
            self.reference == "fem-P2-mixed" and self.scene.material.law == "neo-hookean"
        )
        name = "P1-NH" if nh else "P1"
        return name if name in self.solutions else None

    def error_field(self, name: str, against: str | None = None) -> np.ndarray:
        """Nodal error magnitude ``(n,)`` of ``name`` against ``against`` (the reference)."""
        ref = self.solutions[against or self.reference].u
        return metrics.nodal_error(self.solutions[name].u, ref)

    def errors(self, name: str, against: str | None = None) -> dict[str, float]:
        """Relative L2 and max nodal errors and relative probe errors of ``name``."""
        nan = float("nan")
        against = against or self.reference
        if name not in self.solutions or against not in self.solutions:
            return {"rel_l2": nan, "rel_max": nan}
        u, ref = self.solutions[name], self.solutions[against]
        out = {
            "rel_l2": metrics.relative_l2_error(u.u, ref.u),
            "rel_max": metrics.relative_max_error(u.u, ref.u),
        }
        for probe, err in metrics.probe_error(u.result.probes, ref.result.probes).items():
            out[f"probe:{probe}"] = err
        return out


# ------------------------------------------------------------------------------ solving


def compare_scene(
    scene: Scene,
    models: Sequence[str] | None = None,
    strain_limit: float = LARGE_STRAIN,
    log: Callable[[str], None] | None = None,
    allow_no_reference: bool = False,
    verbose: bool = False,
    locking_free: bool = True,
) -> Comparison:
    """Solve ``scene`` with the spring model and FEM and compare them.

    Parameters
    ----------
    scene
        The scene.
    models
        Model names from :data:`MODELS`; default: ``spring``, ``P1``, ``P2`` and, when the
        scene's law is neo-Hookean or the P1 strain exceeds ``strain_limit``,
        ``P1-NH`` and ``P2-NH``.
    strain_limit
        Large-strain threshold on :func:`max_principal_strain` of the P1 solution.
    log
        Called with one line per finished model (progress).
    allow_no_reference
        When every finite-strain reference failed, return the comparison with no
        reference (``reference = ""``, errors NaN) instead of raising.
    verbose
        Each model's solver progress on stderr.
    locking_free
        On a nearly incompressible scene, add the locking-free models to the default ones
        and make P2/P1 mixed the reference of a hyperelastic law
        (:mod:`studies.models`); ``False`` keeps the spring, P1 and P2 models alone.

    Returns
    -------
    Comparison
        Table, solutions and reference name.

    Raises
    ------
    SolverError
        When no FEM model succeeded, or (unless ``allow_no_reference``) every
        finite-strain reference failed: a small-strain solution is never ranked against
        in their place.
    """
    say = log or (lambda _msg: None)
    solutions: dict[str, Solution] = {}
    failures: dict[str, str] = {}
    notes: list[str] = []
    partial: dict[str, Solution] = {}
    implausible: dict[str, str] = {}

    def run(name: str) -> None:
        got = run_model(scene, name, verbose=verbose, check=True)
        if got.status == "implausible":
            implausible[name] = got.message
            say(f"  {name:<6} IMPLAUSIBLE: {got.message}")
        if not got.solved:
            failures[name] = got.message
            if got.status == "partial":
                partial[name] = got.solution
            say(f"  {name:<6} FAILED: {got.message}")
            return
        solutions[name] = got.solution
        say(f"  {name:<6} done in {got.seconds:.2f} s")

    strain = float("nan")
    asked = models is not None
    if models is None:
        run("P1")
        if "P1" in solutions:
            strain = max_principal_strain(scene, solutions["P1"].u)
        large = bool(strain > strain_limit)
        nh = scene.material.law == "neo-hookean" or large
        if is_tissue(scene):
            nh = False
            notes.append(tissue_note(scene))
        elif large and scene.material.law == "transverse-linear":
            nh = False
            notes.append(
                f"the P1 strain reaches {strain:.1%} (> {strain_limit:.0%}) but reference_fem "
                "has no anisotropic hyperelastic law: the reference is small-strain P2"
            )
        elif nh:
            why = [f"P1 strain {strain:.1%} > {strain_limit:.0%}"] if large else []
            if scene.material.law == "neo-hookean":
                why.append("the scene's law is neo-Hookean")
            notes.append(f"neo-Hookean P1/P2 run ({'; '.join(why)}); P2-NH is the reference")
        else:
            notes.append(f"small strains (max {strain:.2%} <= {strain_limit:.0%}): linear FEM")
        models = ["spring", "P1", "P2"] + (["P1-NH", "P2-NH"] if nh else [])
        ref = reference_model(scene, strain, strain_limit)  # the verdict's reference too
        models += [ref] if ref not in models else []
        base = list(models)
        models += [n for n in locking_free_models(scene) if locking_free and n not in models]
        same = same_solves(scene, models)
        models = [n for n in models if n not in same]  # e.g. P2 of a mixed tissue scene
        weighed = [n for n in locking_free_models(scene) if n in models or n in same]
        if weighed:
            mixed = mixed_reference(scene)
            name = same.get(mixed, mixed) if mixed else "P2"
            notes.append(locking_note(scene, weighed, name, mixed=mixed is not None))
        extra = tuple(n for n in models if n not in base)
    else:
        models = [get_model(n).name for n in models]  # one spelling, whatever was typed
        extra = ()
    notes += formulation_notes(scene, models)
    for name in models:  # validate names before any expensive solve
        why = get_model(name).applies(scene)
        if why is not None:
            raise InputError(why)
    for name in models:
        if name not in solutions and name not in failures:
            run(name)
    solutions = {n: solutions[n] for n in models if n in solutions}  # table order
    reference = choose_reference(models, solutions, failures, notes, tissue=is_tissue(scene))
    if asked and reference:
        notes.append(
            f"reference: {reference}, the finest FEM of the models asked for "
            f"({', '.join(models)}; preference {' > '.join(REFERENCE_PREFERENCE)})"
        )
    if reference is None:
        tried = [n for n in REFERENCE_PREFERENCE if n in models]
        if not any(n in solutions for n in tried):
            raise SolverError(
                f"{scene.name}: no FEM solution to compare against: "
                + "; ".join(f"{k}: {v}" for k, v in failures.items())
            )
        if not allow_no_reference:
            raise SolverError(f"{scene.name}: {notes[-1]}")
    cmp = Comparison(
        scene=scene,
        table=pd.DataFrame(),
        solutions=solutions,
        reference=reference or "",
        strain=strain,
        failures=failures,
        notes=notes,
        partial=partial,
        implausible=implausible,
        extra=extra,
    )
    cmp.table = comparison_table(cmp, list(models))
    return cmp


def choose_reference(
    models: Sequence[str],
    solutions: dict,
    failures: dict[str, str],
    notes: list[str],
    tissue: bool = False,
) -> str | None:
    """The reference: the finest solution of the strongest law that was run.

    P2/P1 mixed (``fem-P2-mixed``, the scene's own law) comes first. A finite-strain
    reference that failed is replaced only by another finite-strain one (P2-NH, then P1-NH;
    on a tissue scene P2 and P1, which solve the tissue law; said in a note), never by a
    small-strain solution; with none left the reference is ``None`` and a note says why.

    Parameters
    ----------
    models
        The models that were run.
    solutions, failures
        Their outcomes.
    notes
        Appended to.
    tissue
        The scene's law is a tissue law (P1 and P2 solve it).

    Returns
    -------
    str or None

    Examples
    --------
    >>> notes = []
    >>> choose_reference(["P1", "P2", "P1-NH", "P2-NH"], {"P1": 0, "P2": 0},
    ...                  {"P1-NH": "diverged", "P2-NH": "diverged"}, notes)
    >>> notes[-1][:45]
    'no finite-strain reference: P1-NH and P2-NH f'
    """
    finite = [n for n in ("fem-P2-mixed", "P2-NH", "P1-NH") if n in models]
    if finite and tissue:
        finite += [n for n in ("P2", "P1") if n in models]
    pool = finite or [n for n in REFERENCE_PREFERENCE if n in models]
    intended = pool[0] if pool else None
    reference = next((n for n in pool if n in solutions), None)
    if intended is not None and reference is not None and reference != intended:
        notes.append(
            f"the intended reference {intended} FAILED ({failures.get(intended, '')}); "
            f"the reference is {reference} (weaker: same law, coarser element)"
        )
    if reference is None and finite:
        notes.append(
            f"no finite-strain reference: {' and '.join(sorted(finite))} failed; errors are "
            "not computed (a small-strain solution would be no reference at these strains)"
        )
    return reference


# ------------------------------------------------------------------------------- table


def comparison_table(cmp: Comparison, models: Sequence[str]) -> pd.DataFrame:
    """One row per model: probes, errors against the reference, volume, reactions, time.

    A model that stopped part way along its load (``cmp.partial``) is reported at the load
    it reached: status ``partial``, its ``load factor`` (1 for the finished models), probes
    and volume, no errors (a state at a lower load is not compared with the reference).
    """
    ref_sol = cmp.solutions.get(cmp.reference) or next(iter(cmp.solutions.values()))
    ref = ref_sol.result
    main = {name: int(np.argmax(np.abs(u))) for name, u in ref.probes.items()}
    regions = list(ref.reactions)
    rows = []
    for name in models:
        row: dict[str, object] = {"model": name}
        sol = cmp.solutions.get(name)
        if sol is None and name in cmp.partial:
            rows.append(partial_row(row, cmp.partial[name].result, main))
            continue
        if sol is None:
            row.update({"status": "FAILED", "element": "", "law": "", "converged": False})
            rows.append(row)
            continue
        row["status"] = "implausible" if name in cmp.implausible else "ok"
        row["load factor"] = 1.0
        r = sol.result
        row["element"] = r.element
        row["law"] = r.law
        for probe, c in main.items():
            u = np.asarray(r.probes.get(probe, [np.nan] * 3))
            row[f"{probe} |u| (m)"] = float(np.linalg.norm(u))
            row[f"{probe} u{COMPONENTS[c]} (m)"] = float(u[c])
        err = cmp.errors(name)
        for probe in main:
            row[f"{probe} rel err"] = err.get(f"probe:{probe}", np.nan)
        row["rel L2 err"] = err["rel_l2"]
        row["rel max err"] = err["rel_max"]
        row["volume change"] = r.volume.get("relative_change", np.nan)
        for region in regions:
            row[f"|R| {region} (N)"] = float(np.linalg.norm(r.reactions.get(region, np.nan)))
        row["wall time (s)"] = r.wall_time
        row["iterations"] = r.iterations
        row["converged"] = bool(r.converged)
        rows.append(row)
    df = pd.DataFrame(rows)
    df.insert(1, "reference", df["model"] == cmp.reference)
    return df
