"""FEM reference options: what a scene's ``[fem]`` section sets.

:func:`parse_fem_options` validates the section (registered with the core, so
:func:`springfem.scene.load_scene` checks it on load); :meth:`FemOptions.of` reads it
from a scene.

Examples
--------
>>> FemOptions().order, FemOptions().linear_solver  # the defaults
(1, 'auto')
>>> parse_fem_options(TableReader({"order": 2}, "[fem]", "scene.toml")).order
2
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal, get_args

from springfem.scene import Scene, TableReader, register_section

LinearSolver = Literal["auto", "direct", "amg"]
Solver = Literal["static", "explicit", "implicit"]
Precision = Literal["float64", "mixed", "float32"]
Formulation = Literal["displacement", "mixed", "nodal-volume", "nodal-strain", "mini"]
Geometry = Literal["straight", "curved"]
#: The formulations on nodal volumes (``[fem] stabilisation`` applies to them).
NODAL_FORMULATIONS = ("nodal-volume", "nodal-strain")

#: Default ``[fem] stabilisation`` of ``formulation = "nodal-volume"``: the smallest share
#: that takes Land's ventricle to full load (docs/fem.rst#nodal-volume-tetrahedra).
STABILISATION = 1e-4
#: Default ``[fem] strain_stabilisation`` of ``formulation = "nodal-strain"``; its volumetric
#: share defaults to ``strain_stabilisation * mu / kappa`` (docs/fem.rst#nodal-strain-tetrahedra).
STRAIN_STABILISATION = 0.3
#: The highest tetrahedron quadrature degree offered (scikit-fem's rules go further).
MAX_INTORDER = 8


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
    solver
        ``static`` (Newton), or a time integration of the P1 FEM
        (:class:`reference_fem.explicit.ExplicitFem`): ``explicit`` (symplectic Euler) or
        ``implicit`` (backward Euler with the analytic tangent); both need ``t_end`` or
        ``steps``.
    t_end, steps, dt, mass_damping
        End time (s) or number of steps, time step (default half the critical step) and
        mass-proportional damping (1/s) of a dynamic solve.
    precision
        Explicit force kernel: ``float64``, ``mixed`` (float32 constants, float64
        arithmetic) or ``float32``.
    formulation
        ``displacement``; ``mixed``: Taylor–Hood P2 displacement / P1 pressure (needed
        for ``incompressible = true`` materials, order 2); ``nodal-volume``: linear tets
        with the volumetric energy on nodal volumes (order 1,
        :mod:`reference_fem.nodal_volume`); ``nodal-strain``: nodal volumes and the law's
        element part blended with its value on nodal-averaged strain (order 1,
        :mod:`reference_fem.nodal_strain`); ``mini``: P1-bubble / P1 pressure (order 1,
        :mod:`reference_fem.mini`).
    stabilisation
        ``nodal-volume`` and ``nodal-strain``: the share of the volumetric energy kept per
        element, in [0, 1] (0: pure nodal averaging, 1: plain P1); ``None`` is the
        formulation's default: 1e-4 for nodal-volume, ``strain_stabilisation * mu / kappa``
        (an element volumetric stiffness of that share of the shear modulus) for nodal-strain.
    strain_stabilisation
        ``nodal-strain`` only: the share of the law's element part measured on the
        element's own strain, in [0, 1] (1: the nodal-volume formulation).
    intorder
        Degree of the tetrahedron quadrature (scikit-fem's ``intorder``); ``None``: the
        default of :func:`reference_fem.space.default_intorder` (1 point for P1, 4 points
        for P2). An exponential anisotropic law whose fibres turn inside the element
        (``rule-based`` or ``land-ellipsoid`` axes, taken at the quadrature points) needs
        more: Land's problem 3 takes ``intorder = 6`` (15 points, exact to degree 5;
        docs/verification.rst#land-problem-3-fibres).
    geometry
        ``straight`` (straight-sided tets, the default) or ``curved``: order 2 on a mesh of
        the ``ellipsoid`` generator, with the P2 edge nodes of the endo- and epicardial
        facets on the true ellipsoids (isoparametric tets,
        :func:`springfem.ellipsoid.curved_edge_nodes`;
        docs/verification.rst#land-problem-3-fibres).
    """

    order: int = 1
    linear_solver: LinearSolver = "auto"
    tol: float = 1e-10
    max_iter: int = 25
    load_steps: int = 1
    solver: Solver = "static"
    t_end: float | None = None
    steps: int | None = None
    dt: float | None = None
    mass_damping: float = 0.0
    precision: Precision = "float64"
    formulation: Formulation = "displacement"
    stabilisation: float | None = None
    strain_stabilisation: float = STRAIN_STABILISATION
    intorder: int | None = None
    geometry: Geometry = "straight"

    @property
    def volumetric_share(self) -> float:
        """``stabilisation``, else nodal-volume's default :data:`STABILISATION`."""
        return STABILISATION if self.stabilisation is None else self.stabilisation

    @classmethod
    def choices(cls, name: str) -> tuple[str, ...]:
        """Valid string values of the option ``name`` (empty for non-string options)."""
        kinds = {
            "linear_solver": LinearSolver,
            "solver": Solver,
            "precision": Precision,
            "formulation": Formulation,
            "geometry": Geometry,
        }
        return get_args(kinds[name]) if name in kinds else ()

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
    for key in ("solver", "precision", "formulation", "geometry"):
        if r.has(key):
            kw[key] = r.get(key, "str", choices=FemOptions.choices(key))
    for key in ("tol", "t_end", "dt"):
        if r.has(key):
            kw[key] = r.get(key, "float", positive=True)
    if r.has("mass_damping"):
        kw["mass_damping"] = r.get("mass_damping", "float", nonneg=True)
    for key in ("max_iter", "load_steps", "steps"):
        if r.has(key):
            kw[key] = r.get(key, "int", positive=True)
    if r.has("intorder"):
        kw["intorder"] = r.get("intorder", "int", positive=True)
        if kw["intorder"] > MAX_INTORDER:
            raise r.fail("intorder", f"must be at most {MAX_INTORDER}, got {kw['intorder']}")
    for key, forms in (
        ("stabilisation", NODAL_FORMULATIONS),
        ("strain_stabilisation", ("nodal-strain",)),
    ):
        if r.has(key):
            kw[key] = r.get(key, "float", nonneg=True)
            if kw[key] > 1.0:
                raise r.fail(key, f"must lie in [0, 1], got {kw[key]}")
            if kw.get("formulation") not in forms:
                names = " or ".join(f'"{f}"' for f in forms)
                raise r.fail(key, f"applies to formulation = {names}")
    form, order = kw.get("formulation", "displacement"), kw.get("order", 1)
    if form in NODAL_FORMULATIONS + ("mini",) and order != 1:
        raise r.fail("order", f'formulation = "{form}" is for linear tets: order 1, not {order}')
    if kw.get("geometry") == "curved" and order != 2:
        raise r.fail("geometry", f'"curved" is for quadratic tets: order 2, not {order}')
    if kw.get("solver", "static") != "static" and "t_end" not in kw and "steps" not in kw:
        raise r.fail("solver", f"{kw['solver']!r} needs fem.t_end or fem.steps")
    r.finish()
    return FemOptions(**kw)


register_section("fem", parse_fem_options)
