"""Cases of the locking study: the methods, settings, the scenes at each Poisson ratio
(:func:`with_nu`), and one timed solve per case (``method``, ``nu``, ``factor``: its level).

Examples
--------
>>> beam = with_nu(StudyScene.bundled("land-beam"), 0.49)  # Guccione: mu = 10/3 kPa
>>> round(beam.table["material"]["kappa"], 2), "incompressible" in beam.table["material"]
(165.56, False)
>>> list(METHODS)[:3]
['P1', 'P1-nodal-volume', 'P1-nodal-strain']
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from reference_fem.options import FemOptions
from springfem.errors import InputError
from springfem.materials.tissue import TISSUE_LAWS
from springfem.mechanics.limits import CAP_REASON, LIMITS, solve_limits
from springfem.model_api import declared

from .. import models
from ..scenes import StudyScene
from ..study_convergence.levels import case_level

STUDY, VERSION = "locking", 2

#: The Poisson ratios of the study.
NUS = (0.3, 0.45, 0.49, 0.499, 0.4999)
#: A method is adequate within this relative error of the reference deflection.
TOLERANCE = 0.05
#: The reference method (its value on the finest level is the reference).
REFERENCE = "P2-mixed"


def _fem(name: str, label: str, order: int, formulation: str, **fem: Any) -> models.Model:
    """Register an FEM model of the scene's own law with ``[fem] formulation``."""
    return models.fem_variant(name, label, order, formulation, **fem)


def _spring(name: str, label: str, **changes: Any) -> models.Model:
    """Register a spring element: the exact element with ``changes``."""
    return models.spring_variant(
        name, label, coupling=True, element=True, **{**models.EXACT, **changes}
    )


#: FEM methods: (name, label, order, formulation); one line adds a formulation. A
#: formulation the FEM does not offer (``FemOptions.choices``) is left out.
FEM_METHODS = (
    ("P1", "FEM P1 (displacement)", 1, "displacement"),
    ("P1-nodal-volume", "FEM P1, nodal-averaged volume", 1, "nodal-volume"),
    ("P1-nodal-strain", "FEM P1, nodal-averaged strain", 1, "nodal-strain"),
    ("MINI", "FEM MINI (P1-bubble / P1)", 1, "mini"),
    ("P2", "FEM P2 (displacement)", 2, "displacement"),
    ("P2-mixed", "FEM P2/P1 Taylor–Hood", 2, "mixed"),
)
#: The study's spelling of the spring elements: the specification's (seed) element, the
#: exact element, + nodal volume, + nodal strain and nodal volume ("stabilised", with the
#: default stabilisations of :mod:`springmodel.options`), and for a tissue law the tissue
#: element (the law itself under homogeneous deformation) with the same stabilisation.
SPRING_METHODS = {
    "spring-spec": models.get("spring-spec"),
    "spring-exact": models.get("spring-exact"),
    "spring-nodal-volume": _spring(
        "spring-nodal-volume", "exact spring element, nodal volume", volume_average="nodal"
    ),
    "spring-stabilised": _spring(
        "spring-stabilised",
        "exact spring element, stabilised nodal strain + nodal volume",
        volume_average="nodal",
        strain_average="nodal",
    ),
    "spring-tissue-stabilised": models.spring_variant(
        "spring-tissue-stabilised",
        "tissue spring element, stabilised nodal strain + nodal volume",
        coupling=True,
        element=True,
        **{**models.TISSUE, "volume_average": "nodal", "strain_average": "nodal"},
    ),
}
#: Every method of the study, by name (the FEM ones whose formulation exists).
METHODS: dict[str, models.Model] = {
    **{
        name: _fem(f"fem-{name}", label, order, form)
        for name, label, order, form in FEM_METHODS
        if form in FemOptions.choices("formulation")
    },
    **SPRING_METHODS,
}
#: Methods on the mesh's own vertices (linear tets: P1-type FEM and the spring elements).
LINEAR_TETS = tuple(n for n, m in METHODS.items() if declared(m, "order") == 1)
#: Solves under this many seconds are timed as the median of three.
REPEAT_BELOW = 0.5
#: Why a case is not run when a method on the same kind of tets is within the tolerance
#: faster than the case's predicted time (:attr:`Settings.skip_costlier`).
COSTLIER = "it cannot be the cheapest"


@dataclass(frozen=True)
class Settings:
    """Poisson ratios, meshes and the solve cap of the locking study.

    ``nus`` (:data:`NUS` has two more); the level-1 divisions of Cook's membrane (``cook``)
    and Land's beam (``beam``; ``None``: left out) and their refinement ``factors`` (Cook's
    mesh is no box grid: powers of two) and ``beam_factors`` (1, 2, 3 reach Land's
    30x3x3); the ``methods`` of :data:`METHODS`; ``max_time``, the cap of one solve (the
    reference's is only the user's ``--max-time``); ``timed``: an untimed warm-up solve per
    method and the median of three under :data:`REPEAT_BELOW` s (``False``: one solve).
    ``prune`` skips a method's finer levels at a ν once a coarser one is within
    :data:`TOLERANCE`, and a level predicted over 1.5 × ``max_time`` (the quick preset does
    not: its headline, every headline method's finest level, must not depend on the
    machine's speed). ``skip_costlier`` skips a finer level that cannot be the cheapest of
    its kind of tets (:data:`LINEAR_TETS`, or quadratic): above all displacement P2 near
    incompressibility, which needs hundreds of Newton iterations there (274 on the quick
    beam's 486 tets at ν = 0.4999) where P2/P1 is more accurate and faster.
    ``finest_nus``: the ratios at which the methods run on the finest level (``None``:
    every one; the reference runs there at every ratio).
    """

    nus: tuple[float, ...] = (0.3, 0.49, 0.4999)
    cook: tuple[int, int, int] | None = (4, 4, 1)
    beam: tuple[int, int, int] | None = (10, 1, 1)
    factors: tuple[int, ...] = (1, 2, 4)
    beam_factors: tuple[int, ...] = (1, 2, 3)
    methods: tuple[str, ...] = field(default_factory=lambda: tuple(METHODS))
    max_time: float = 120.0
    timed: bool = True
    prune: bool = True
    skip_costlier: bool = True
    finest_nus: tuple[float, ...] | None = None

    @classmethod
    def full(cls) -> Settings:
        """Cook 4x4x1 refined x2, x4 (96 to 6,144 tets), the beam 10x1x1 to Land's 30x3x3; a
        120 s cap (nodal-strain P1 on the finest beam at ν = 0.4999 took 41 s alone, over
        60 s beside a second worker)."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """Cook 2x2x1 refined x2, x4 (24 to 1,536 tets), the beam 3x1x1 to 9x3x3; a 90 s
        cap (so that the headline does not depend on the machine's speed); the methods run
        on the finest level at ν = 0.4999 only (on these meshes the cheapest method is
        P2/P1 on a coarser level at every ν)."""
        return cls(cook=(2, 2, 1), beam=(3, 1, 1), max_time=90.0, prune=False,
                   finest_nus=(0.4999,))  # fmt: skip


def bundled_scenes(s: Settings) -> list[StudyScene]:
    """Cook's membrane (its shear modulus: Cook's 80.19 kPa) and Land's beam.

    Examples
    --------
    >>> [(x.label, x.params["probe"]) for x in bundled_scenes(Settings.quick())]
    [('cook-membrane', 'corner'), ('land-beam', 'tip')]
    """
    out = []
    if s.cook:
        # the file's E at nu = 0.4999 is Cook's mu = 80.19 kPa, the shear modulus held
        cook = StudyScene.bundled(
            "cook-membrane", {"mesh.divisions": list(s.cook), "material.nu": 0.4999}
        )
        out.append(_with_params(cook, probe="corner", component=1, factors=s.factors))
    if s.beam:
        beam = StudyScene.bundled("land-beam", {"mesh.divisions": list(s.beam)})
        out.append(_with_params(beam, probe="tip", component=2, factors=s.beam_factors))
    return out


def _with_params(sc: StudyScene, **params: Any) -> StudyScene:
    from dataclasses import replace

    return replace(sc, params={**sc.params, **params})


# ---------------------------------------------------------------------- the Poisson ratio


def shear_modulus(sc: StudyScene) -> float:
    """The scene's shear modulus, held while the study varies the bulk modulus (a tissue
    law: the mean shear modulus of its small-strain tangent)."""
    return float(sc.build().material.mu)


def with_nu(sc: StudyScene, nu: float) -> StudyScene:
    """The scene at Poisson ratio ``nu`` with its shear modulus ``mu`` held.

    An isotropic law gets ``E = 2 mu (1 + nu)`` and ``nu``; a tissue law the volumetric
    penalty ``kappa = 2 mu (1 + nu) / (3 (1 - 2 nu))`` of the isotropic equivalent (``mu``
    the mean shear modulus of its small-strain tangent, :func:`reference_fem.fitting.p1_penalty`),
    an incompressible one becoming nearly incompressible. An anisotropic linear law has no
    single Poisson ratio: :class:`~springfem.errors.InputError`.
    """
    from dataclasses import replace

    mat = sc.table.get("material", {})
    law = mat.get("law", "linear")
    if law not in (*TISSUE_LAWS, "linear", "neo-hookean"):
        raise InputError(
            f"study locking: the {law} law has no single Poisson ratio to vary; use an "
            "isotropic law (linear, neo-hookean) or a tissue law with a penalty"
        )
    mu = shear_modulus(sc)
    new = dict(mat)
    if law in TISSUE_LAWS:
        new.pop("incompressible", None)
        new["kappa"] = 2.0 * mu * (1.0 + nu) / (3.0 * (1.0 - 2.0 * nu))
    else:
        new["E"], new["nu"] = 2.0 * mu * (1.0 + nu), nu
    return replace(sc, table={**sc.table, "material": new})


def deflection_probe(sc: StudyScene) -> str:
    """The probe whose displacement the study compares (a bundled scene's, else the
    scene's first; a user's scene without a probe is refused in one line)."""
    probe = sc.params.get("probe")
    if probe:
        return str(probe)
    names = [p.get("name") for p in sc.table.get("probe", []) if isinstance(p, dict)]
    if not names:
        raise InputError(
            f"study locking: scene {sc.label} has no [[probe]]; add one at the point whose "
            "deflection to compare (e.g. the tip)"
        )
    return str(names[0])


def scene_methods(sc: StudyScene, s: Settings) -> list[str]:
    """The methods of ``s`` that apply to the scene (the tissue element: a tissue law)."""
    tissue = sc.table.get("material", {}).get("law") in TISSUE_LAWS
    return [m for m in s.methods
            if tissue or getattr(METHODS[m], "changes", {}).get("stiffening") != "law"]  # fmt: skip


def case_of(sc: StudyScene, s: Settings, method: str, nu: float, factor: int) -> dict[str, Any]:
    """The cache case of one method at one Poisson ratio and level."""
    cap = None if method == REFERENCE else s.max_time  # the reference: only the user's cap
    probe = deflection_probe(sc)
    return with_nu(sc, nu).case(STUDY, VERSION, method=method, nu=nu, factor=factor,
                                probe=probe, max_time=cap, timed=s.timed)  # fmt: skip


def cases(
    sc: StudyScene, s: Settings, factors: tuple[int, ...] | None = None
) -> list[dict[str, Any]]:
    """The scene's cases: every level, Poisson ratio and method (coarse levels first)."""
    factors = tuple(factors or sc.params.get("factors", s.factors))
    methods = scene_methods(sc, s)
    return [case_of(sc, s, m, nu, f) for f in factors for nu in s.nus for m in methods]


# ------------------------------------------------------------------------ predicted cost

#: Measured seconds per DOF of each method's static solve (Land's beam, Guccione, on
#: 1,620 tets, ``springfem study locking`` on the shared 2-core machine): what a plan
#: predicts from before the study has measured a method on the scene itself.
COST_PER_DOF = {
    "P1": 9e-4, "P1-nodal-volume": 2.6e-3, "P1-nodal-strain": 4.1e-3, "MINI": 1.3e-3,
    "P2": 3.0e-3, "P2-mixed": 1.4e-3, "spring-spec": 6.5e-4, "spring-exact": 4e-4,
    "spring-nodal-volume": 1.4e-3, "spring-stabilised": 2.9e-3,
    "spring-tissue-stabilised": 3.0e-3,
}  # fmt: skip

_COUNTS: dict[str, tuple[int, int, int]] = {}


def mesh_counts(case: dict[str, Any]) -> tuple[int, int, int]:
    """``(vertices, edges, tets)`` of a case's level-1 mesh (remembered per mesh)."""
    import json

    key = json.dumps([case["table"].get("mesh"), case.get("path"), case.get("mesh_digest")],
                     sort_keys=True, default=str)  # fmt: skip
    if key not in _COUNTS:
        from ..study_convergence.levels import refined_scene

        mesh = refined_scene(case["table"], case.get("path"), 1).mesh
        t = np.sort(mesh.tets, axis=1)
        pairs = np.concatenate([t[:, [a, b]] for a, b in ((0, 1), (0, 2), (0, 3), (1, 2),
                                                          (1, 3), (2, 3))])  # fmt: skip
        edges = len(np.unique(pairs, axis=0))
        _COUNTS[key] = (mesh.n_points, edges, mesh.n_tets)
    return _COUNTS[key]


def dofs(method: str, vertices: int, edges: int, tets: int) -> int:
    """The unknowns of ``method`` on a mesh: 3 per vertex (P1-type, spring), + 3 per edge
    (P2), + a pressure per vertex (Taylor–Hood), + 3 per tet and a pressure per vertex
    (MINI).

    Examples
    --------
    >>> dofs("P1", 10, 30, 20), dofs("P2-mixed", 10, 30, 20), dofs("MINI", 10, 30, 20)
    (30, 130, 100)
    """
    m = METHODS.get(method)
    form = declared(m, "settings", default={}).get("formulation", "")
    if declared(m, "order") == 2:
        return 3 * (vertices + edges) + (vertices if form == "mixed" else 0)
    if form == "mini":
        return 3 * (vertices + tets) + vertices
    return 3 * vertices


def estimate(case: dict[str, Any]) -> tuple[str, float, int]:
    """``(kind, DOFs, tets)`` of a case (kind: ``method@scene@nu``), for its predicted cost
    (DOFs × the method's cost per DOF, :class:`studies.budget.CostModel`); a level ``r`` has
    ``r³`` times the vertices, edges and tets of level 1."""
    v, e, t = mesh_counts(case)
    k = int(case["factor"]) ** 3
    kind = f"{case['method']}@{case['scene']}@{case['nu']:g}"
    return kind, float(dofs(case["method"], v * k, e * k, t * k)), t * k


# ------------------------------------------------------------------------------ a solve

#: Methods warmed up in this process (their first solve compiles kernels: not timed).
_WARM: set[tuple[str, str]] = set()


def _timed_run(model: models.Model, scene, warm_scene=None) -> models.Outcome:
    """The outcome of ``model`` on ``scene`` with a fair wall time: a method's first solve
    in the process is preceded by an untimed warm-up solve (on ``warm_scene``, the coarsest
    level: it loads or compiles the same kernels for a fraction of the cost), and solves
    under :data:`REPEAT_BELOW` s are the median of three."""
    key = (model.name, scene.material.law)
    if key not in _WARM:
        models.run(scene if warm_scene is None else warm_scene, model)
        _WARM.add(key)
    times: list[float] = []
    out = None
    while not times or (len(times) < 3 and max(times) < REPEAT_BELOW):
        again = models.run(scene, model)
        if not again.solved:
            return again
        out = again
        times.append(again.seconds)
    assert out is not None
    out.seconds = float(np.median(times))
    return out


def locking_case(case: dict[str, Any]) -> dict[str, Any]:
    """Solve one case: status, the probe's displacement, the wall time, the mesh size.

    The cap is the smaller of the case's ``max_time`` and the caller's (the user's
    ``--max-time`` caps every case, the reference's too). A solve that reaches it or fails
    is recorded with its status (``partial``: the load factor it reached) and message.
    """
    scene = case_level(case)
    model = METHODS[case["method"]]
    t0 = time.perf_counter()
    caps = [c for c in (case["max_time"], LIMITS["max_time"]) if c is not None]
    with solve_limits(max_time=min(caps) if caps else None, why=CAP_REASON["why"]):
        if case.get("timed", True):
            warm = case_level({**case, "factor": 1}) if int(case["factor"]) != 1 else None
            got = _timed_run(model, scene, warm)
        else:
            got = models.run(scene, model)
    out: dict[str, Any] = {
        "status": got.status,
        "message": got.message[:240],
        "tets": scene.mesh.n_tets,
        "seconds": got.seconds,
        "elapsed": time.perf_counter() - t0,
        "load": got.load_factor,
    }
    if got.solved:
        r = got.solution.result
        out.update(u=list(map(float, r.probes[case["probe"]])), law=r.law,
                   dofs=int(r.counts.get("dofs", 3 * scene.mesh.n_points)))  # fmt: skip
    return out
