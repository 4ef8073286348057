"""FEM reference options: what a scene's ``[fem]`` section sets.

:func:`parse_fem_options` validates the section (registered with the core, so
:func:`springfem.scene.load_scene` checks it on load); :meth:`FemOptions.of` reads it
from a scene.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal, get_args

from springfem.scene import Scene, TableReader, register_section

LinearSolver = Literal["auto", "direct", "amg"]
Formulation = Literal["displacement", "mixed"]


@dataclass(frozen=True)
class FemOptions:
    """FEM reference settings: a scene's ``[fem]`` section.

    Attributes
    ----------
    order
        1 (P1, linear tets) or 2 (P2, quadratic tets on the same vertices).
    linear_solver
        ``direct`` (SuperLU/UMFPACK), ``amg`` (CG + pyamg smoothed aggregation with
        rigid-body modes) or ``auto`` (direct below a size threshold).
    tol
        Newton tolerance on the relative residual norm.
    max_iter
        Newton iterations per load step.
    load_steps
        Initial number of load steps (adapted: cut back on divergence, grown on easy steps).
    formulation
        ``displacement``, or ``mixed``: Taylor–Hood P2 displacement / P1 pressure (issue 11;
        needed for ``incompressible = true`` materials).
    """

    order: int = 1
    linear_solver: LinearSolver = "auto"
    tol: float = 1e-10
    max_iter: int = 25
    load_steps: int = 1
    formulation: Formulation = "displacement"

    @classmethod
    def choices(cls, name: str) -> tuple[str, ...]:
        """Valid string values of the option ``name`` (empty for non-string options)."""
        if name == "formulation":
            return get_args(Formulation)
        return get_args(LinearSolver) if name == "linear_solver" else ()

    @classmethod
    def of(cls, scene: Scene) -> FemOptions:
        """The ``[fem]`` options of ``scene`` (defaults when the section is absent)."""
        return scene.section("fem", parse_fem_options)


def parse_fem_options(r: TableReader) -> FemOptions:
    """Validate a scene's ``[fem]`` table into :class:`FemOptions`.

    Parameters
    ----------
    r
        Reader over the table; every error names the file and key.

    Returns
    -------
    FemOptions
    """
    kw: dict[str, Any] = {}
    if r.has("order"):
        kw["order"] = r.get("order", "int", choices=(1, 2))
        if kw["order"] not in (1, 2):
            raise r.fail("order", f"must be 1 or 2, got {kw['order']}")
    if r.has("linear_solver"):
        kw["linear_solver"] = r.get(
            "linear_solver", "str", choices=FemOptions.choices("linear_solver")
        )
    if r.has("formulation"):
        kw["formulation"] = r.get("formulation", "str", choices=FemOptions.choices("formulation"))
    for key in ("tol",):
        if r.has(key):
            kw[key] = r.get(key, "float", positive=True)
    for key in ("max_iter", "load_steps"):
        if r.has(key):
            kw[key] = r.get(key, "int", positive=True)
    r.finish()
    return FemOptions(**kw)


register_section("fem", parse_fem_options)
