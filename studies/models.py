"""The models: one name, one label and one solve per model, in one registry.

Every comparison, sweep and study names its models here, so a model has one spelling in
the command line (``compare --models``), in tables, figures, sweep files and headline keys.
Names are looked up case-insensitively (``p1`` is ``P1``); a misspelt name gets a "did you
mean". Failures are caught in one place, :func:`run`.

Models
------
``spring``
    the spring model with the scene's ``[spring]`` options;
``spring-<variant>``
    the spring model with a variant's changes to the scene's ``[spring]`` options
    (:func:`spring_variant`; ``spring-energy``, ``spring-cosine``: that torsion law; on a
    scene that names an element other than ``seed``, or gets one by default, the changes
    are made to the specification's element, so that a variant means the same on every
    scene), or a
    whole element of its own: ``spring-spec`` (the specification's element: barycentric
    volume springs, cosine torsion, the analytic calibration), ``spring-exact`` (axis-volume
    + energy torsion + the exact calibration, with the Poisson-coupling springs for an
    anisotropic law: P1's small-strain element on any tet), ``spring-stiffened`` (the exact
    element for tissue at finite strain: Green axial springs, shear torsion, exponential
    stiffening);
``fem``
    the FEM the scene's ``[fem]`` section and law ask for (``springfem solve --model fem``);
``P1``, ``P2``
    FEM on the scene's mesh with the scene's small-strain law (``linear`` or
    ``transverse-linear``; ``linear`` with ``E, nu`` for a neo-Hookean scene), or for a
    finite-strain tissue law the scene's own law: ``P2`` with the scene's formulation,
    ``P1`` in the displacement formulation with the scene's ``kappa`` or, for an
    incompressible material, the spring model's penalty (:func:`studies.fem_laws.p1_penalty`);
``P1-NH``, ``P2-NH``
    neo-Hookean FEM (the scene's formulation); not for anisotropic laws;
plug-ins
    every model of the plug-in API (:mod:`springfem.model_api`: entry points of group
    ``springfem.models`` and :func:`springfem.model_api.register_model`), such as
    ``corotational``; :func:`plugins` lists those a study weighs by default.

Examples
--------
>>> get("p1-nh").name, get("P1-NH").label
('P1-NH', 'FEM P1 neo-Hookean')
>>> get("spring-exact").changes
{'volume': 'axes', 'torsion': 'energy', 'calibration': 'exact'}
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({"mesh": {"generator": "box", "size": [0.1, 0.01, 0.01],
...     "divisions": [4, 1, 1]}, "material": {"law": "linear", "E": 1e4, "nu": 0.3},
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
...     "load": [{"type": "traction", "region": "x_max", "value": [0, 0, -0.1]}]})
>>> [run(scene, m).status for m in ("spring-exact", "P1")]
['ok', 'ok']
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np

from reference_fem.options import FemOptions
from springfem.errors import InputError, SolverError
from springfem.materials.tissue import TISSUE_LAWS
from springfem.mechanics.limits import SolveStopped
from springfem.plausibility import check_solution
from springfem.scene import Scene
from springfem.scene.reader import suggestion
from springmodel.options import ANISOTROPIC_LAWS, ELEMENT_KEYS, ELEMENTS

from .fem_laws import linear_law, tissue_scene
from .partial import partial_solution
from .solve import Solution

#: The exact spring element: small-strain P1 on any tet (with coupling when anisotropic).
EXACT = dict(ELEMENTS["exact"])
#: The spring element for tissue at finite strain: the exact element with Green axial
#: springs, the shear torsion law, the exponential stiffening of the element energy and the
#: tissue laws' log penalty ``U(J)``.
STIFFENED = dict(ELEMENTS["stiffened"])
#: The tissue element: the stiffened element's Green measures with the Green torsion (all six
#: frame components of E) and each spring group stiffened as the law's own terms, so that
#: it equals its law under any homogeneous deformation (docs/tissue.rst).
TISSUE = dict(ELEMENTS["tissue"])


@dataclass(frozen=True)
class Model:
    """A model of the registry.

    Attributes
    ----------
    name
        Its one spelling.
    label
        A longer human name for tables and figures.
    kind
        ``spring``, ``fem`` or ``plugin`` (a model of :mod:`springfem.model_api`).
    changes
        Spring models: changes to the scene's ``[spring]`` options (values of
        :class:`springmodel.options.SpringOptions`; ``lms`` may be a rule name and
        ``axial`` ``"green"``, as in a scene file). If the scene's element is not the
        seed's, the changes are made to the seed's element.
    coupling
        Spring models: add the Poisson-coupling springs when the law is anisotropic.
    element
        Spring models: the model defines the whole element (:data:`ELEMENT_KEYS` start from
        their defaults, whatever the scene's ``[spring]`` says); otherwise ``changes``
        modify the scene's options.
    order
        FEM models: 1 or 2 (``None``: the scene's ``[fem] order``).
    law
        FEM models: ``small-strain``, ``neo-hookean`` or ``scene`` (the scene's own law and
        formulation).
    fem
        FEM models: ``[fem]`` options (fields of :class:`reference_fem.options.FemOptions`,
        such as ``formulation``) that replace the scene's before the solve.
    plugin
        Plug-in models: the :class:`~springfem.model_api.ModelPlugin`.
    """

    name: str
    label: str
    kind: Literal["spring", "fem", "plugin"]
    changes: Mapping[str, Any] = field(default_factory=dict)
    coupling: bool = False
    element: bool = False
    order: int | None = None
    law: Literal["small-strain", "neo-hookean", "scene"] = "small-strain"
    fem: Mapping[str, Any] = field(default_factory=dict)
    plugin: Any = None

    # -- what the model solves ---------------------------------------------------------------
    def applies(self, scene: Scene) -> str | None:
        """Why this model cannot solve ``scene`` (``None``: it can).

        Parameters
        ----------
        scene
            The scene.

        Returns
        -------
        str or None
        """
        if self.kind == "plugin":
            return self.plugin.applies(scene)
        if self.kind == "fem" and self.law == "neo-hookean":
            law = scene.material.law
            if law == "transverse-linear":
                return (
                    f"model {self.name}: reference_fem has no anisotropic hyperelastic law "
                    "for the transverse-linear material"
                )
            if law in TISSUE_LAWS:
                return (
                    f"model {self.name}: neo-Hookean is not the scene's {law} law; P1 and P2 "
                    "solve that law"
                )
        if self.kind == "spring" and self.changes.get("stiffening") == "law":
            if scene.material.law not in TISSUE_LAWS:
                return f'model {self.name}: stiffening = "law" needs a tissue law'
        return None

    def spring_options(self, scene: Scene):
        """The spring options this model solves ``scene`` with (spring models only).

        Parameters
        ----------
        scene
            The scene.

        Returns
        -------
        springmodel.options.SpringOptions
        """
        from springmodel.options import GREEN_AXIAL_COEFFICIENTS, LMSOptions, SpringOptions

        changes = dict(self.changes)
        if isinstance(changes.get("lms"), str):
            changes["lms"] = LMSOptions(rule=changes["lms"])
        if changes.get("axial") == "green":  # the scene files' spelling of the cubic law
            changes["axial"], changes["axial_coefficients"] = "cubic", GREEN_AXIAL_COEFFICIENTS
        if self.coupling and scene.material.law in ANISOTROPIC_LAWS:
            changes["coupling"] = True
        options = SpringOptions.of(scene)
        if self.element or (changes and options.element != "seed"):
            # a whole element, or a variant of one option: a variant is of the spec's
            # element, whichever element the scene names (docs/studies.rst)
            default = SpringOptions()
            reset = {k: getattr(default, k) for k in ELEMENT_KEYS}
            options = replace(options, **reset, element="seed")
        return replace(options, **changes)

    def fem_settings(self, scene: Scene) -> tuple[Scene, int | None, str | None]:
        """``(scene, order, law)`` of :func:`reference_fem.solve` for this FEM model.

        Parameters
        ----------
        scene
            The scene.

        Returns
        -------
        tuple
        """
        if self.fem:
            scene = scene.with_options(fem=replace(FemOptions.of(scene), **self.fem))
        if self.law == "scene":
            return scene, self.order, None
        if self.law == "neo-hookean":
            return scene, self.order, "neo-hookean"
        if scene.material.law in TISSUE_LAWS:
            return tissue_scene(scene, self.order), self.order, scene.material.law
        return scene, self.order, linear_law(scene)

    def solve(self, scene: Scene, verbose: bool = False) -> Solution:
        """Solve ``scene`` with this model (raises what the model raises).

        Parameters
        ----------
        scene
            The scene.
        verbose
            Solver progress on stderr.

        Returns
        -------
        Solution

        Raises
        ------
        InputError
            The model does not apply to the scene (:meth:`applies`).
        SolverError
            From the solver.
        """
        why = self.applies(scene)
        if why is not None:
            raise InputError(why)
        if self.kind == "plugin":
            got = self.plugin.solve(scene, verbose)
            return Solution(got.result, got.u, dict(got.cell_data))
        if self.kind == "spring":
            from springmodel.model import solve_spring

            sol = solve_spring(scene, self.spring_options(scene), verbose)
            return Solution(sol.result, sol.u, dict(sol.cell_data))
        import reference_fem

        fem_scene, order, law = self.fem_settings(scene)
        sol = reference_fem.solve(fem_scene, order=order, law=law, verbose=verbose)
        return Solution(sol.result, sol.u_vertices, dict(sol.cell_data))

    def system(self, scene: Scene):
        """The model as a :class:`~springfem.mechanics.MechanicalSystem` for time
        integration: the spring model, or the explicit P1 FEM.

        Parameters
        ----------
        scene
            The scene.

        Returns
        -------
        MechanicalSystem

        Raises
        ------
        InputError
            For a P2 model (no explicit P2 FEM), a law the explicit FEM lacks, or a plug-in
            without an explicit form.
        """
        if self.kind == "plugin":
            why = self.applies(scene)
            system = self.plugin.system(scene) if why is None else None
            if system is None:
                raise InputError(why or f"model {self.name}: no explicit form")
            return system
        if self.kind == "spring":
            from springmodel.model import SpringModel

            return SpringModel(scene, self.spring_options(scene))
        if self.order == 2:
            raise InputError(f"model {self.name}: there is no explicit P2 FEM")
        from reference_fem.explicit import ExplicitFem

        _, _, law = self.fem_settings(scene)
        return ExplicitFem(scene, law=law or scene.material.law)


#: Registered models, by name, in registration order.
REGISTRY: dict[str, Model] = {}


def register(model: Model) -> Model:
    """Add ``model`` to :data:`REGISTRY` (a name is registered once).

    Parameters
    ----------
    model
        The model.

    Returns
    -------
    Model
        ``model``.

    Raises
    ------
    ValueError
        If another model has its name (case-insensitively).
    """
    key = model.name.lower()
    old = next((m for m in REGISTRY.values() if m.name.lower() == key), None)
    if old is not None and old != model:
        raise ValueError(f"model {model.name!r} is registered twice")
    REGISTRY[model.name] = model
    return model


def spring_variant(
    name: str, label: str, coupling: bool = False, element: bool = False, **changes: Any
) -> Model:
    """Register a spring model: the scene's ``[spring]`` options with ``changes``.

    Parameters
    ----------
    name
        ``spring-<variant>``.
    label
        Its label.
    coupling
        Add the Poisson-coupling springs for an anisotropic law.
    element
        The model defines the whole element (see :attr:`Model.element`).
    **changes
        Spring options.

    Returns
    -------
    Model
    """
    return register(Model(name, label, "spring", dict(changes), coupling=coupling, element=element))


def get(name: str | Model) -> Model:
    """The registered model ``name`` (case-insensitive).

    Parameters
    ----------
    name
        A model name, or a :class:`Model` (returned as is).

    Returns
    -------
    Model

    Raises
    ------
    InputError
        Unknown name: the message suggests the closest and lists the valid ones.
    """
    if isinstance(name, Model):
        return name
    sync_plugins()
    for m in REGISTRY.values():
        if m.name.lower() == str(name).lower():
            return m
    near = suggestion(str(name), REGISTRY)
    hint = f" (did you mean {near}?)" if near else ""
    raise InputError(f"unknown model {name!r}{hint}; valid models: {', '.join(REGISTRY)}")


@dataclass
class Outcome:
    """What :func:`run` got from one model on one scene.

    Attributes
    ----------
    model
        The model.
    status
        ``ok``, ``implausible`` (solved, but :func:`springfem.plausibility.check_solution`
        found the state implausible: ``message`` says why), ``partial`` (a load-stepped
        solve stopped part way: ``solution`` is the state at ``load_factor``) or
        ``failed``.
    solution
        The solution (``ok``: a :class:`~studies.solve.Solution`, or what a study's own
        solve returned) or the partial state (``partial``); ``None`` when failed.
    message
        Why it failed or stopped (empty when ok).
    seconds
        Wall time of the attempt.
    """

    model: Model
    status: Literal["ok", "implausible", "partial", "failed"]
    solution: Any = None
    message: str = ""
    seconds: float = float("nan")

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    @property
    def solved(self) -> bool:
        """Solved to full load (``ok`` or ``implausible``)."""
        return self.status in ("ok", "implausible")

    @property
    def load_factor(self) -> float:
        """The load reached: 1 when ok, the partial state's, NaN when failed."""
        if self.solved:
            return 1.0
        if self.solution is not None:
            return float(self.solution.result.info.get("load_factor", np.nan))
        return float("nan")

    @property
    def u(self) -> np.ndarray | None:
        return None if self.solution is None else self.solution.u


def run(
    scene: Scene,
    model: str | Model,
    solve: Callable[[Model, Scene], Any] | None = None,
    verbose: bool = False,
    check: bool = False,
) -> Outcome:
    """Solve ``scene`` with ``model``; a solver failure is an outcome, not an exception.

    Parameters
    ----------
    scene
        The scene.
    model
        A model or its name.
    solve
        How to solve (default :meth:`Model.solve`): a study's own solver settings; what it
        returns is the outcome's ``solution``.
    verbose
        Solver progress on stderr (the default solve).
    check
        Check a solved state's plausibility (:func:`springfem.plausibility.check_solution`:
        ``J``, volume change, small strain, displacement): ``implausible`` when it fails.

    Returns
    -------
    Outcome
        ``ok``; ``implausible`` (with ``check``); ``partial`` with the last converged
        state when a load-stepped solve stopped part way (a solver failure, or a cap of
        :func:`springfem.mechanics.limits.solve_limits`); ``failed`` with the message.

    Raises
    ------
    InputError
        Unknown model, or one that does not apply to the scene: bad input, not a failure.
    """
    m = get(model)
    t0 = time.perf_counter()
    try:
        sol = solve(m, scene) if solve is not None else m.solve(scene, verbose)
    except (SolverError, SolveStopped) as exc:  # a stop by a cap is kept like a failure
        seconds = time.perf_counter() - t0
        state = partial_solution(scene, m.kind, exc, seconds)
        status: Literal["partial", "failed"] = "partial" if state is not None else "failed"
        return Outcome(m, status, state, str(exc), seconds)
    seconds = time.perf_counter() - t0
    if check and getattr(sol, "u", None) is not None:
        findings = check_solution(scene, sol.u, sol.result.law)
        if findings:
            return Outcome(m, "implausible", sol, "; ".join(f.line for f in findings), seconds)
    return Outcome(m, "ok", sol, "", seconds)


# -- the registry ----------------------------------------------------------------------------

SPRING = register(Model("spring", "spring model (the scene's [spring] options)", "spring"))
spring_variant("spring-spec", "the specification's spring element", element=True)
spring_variant("spring-exact", "exact spring element", coupling=True, element=True, **EXACT)
spring_variant(
    "spring-stiffened", "stiffened exact spring element", coupling=True, element=True, **STIFFENED
)
spring_variant(
    "spring-tissue",
    "tissue spring element (Green torsion, the law's stiffening)",
    coupling=True,
    element=True,
    **TISSUE,
)
spring_variant("spring-energy", "spring model, energy torsion", torsion="energy")
spring_variant("spring-cosine", "spring model, cosine torsion", torsion="cosine")
FEM = register(Model("fem", "FEM (the scene's [fem] options)", "fem", law="scene"))
P1 = register(Model("P1", "FEM P1", "fem", order=1))
P2 = register(Model("P2", "FEM P2", "fem", order=2))
P1_NH = register(Model("P1-NH", "FEM P1 neo-Hookean", "fem", order=1, law="neo-hookean"))
P2_NH = register(Model("P2-NH", "FEM P2 neo-Hookean", "fem", order=2, law="neo-hookean"))

#: The models a verdict weighs on a user's scene: the scene's own spring model, the three
#: spring elements and the FEM of the scene's law (the torsion variants and the studies'
#: own variants are the studies' business).
PRIMARY = (
    "spring",
    "spring-spec",
    "spring-exact",
    "spring-stiffened",
    "P1",
    "P2",
    "P1-NH",
    "P2-NH",
)


def sync_plugins() -> list[Model]:
    """Register the plug-in models (:func:`springfem.model_api.plugin_models`) not yet in
    :data:`REGISTRY`; the plug-in models, in registration order.

    Returns
    -------
    list of Model
    """
    from springfem.model_api import plugin_models

    for p in plugin_models().values():
        if p.name not in REGISTRY:
            register(Model(p.name, p.label, "plugin", plugin=p))
    return [m for m in REGISTRY.values() if m.kind == "plugin"]


def plugins(scene: Scene | None = None, explicit: bool = False) -> list[str]:
    """The plug-in models a study weighs by default (``default``) on ``scene``.

    Parameters
    ----------
    scene
        Only those that apply to it (``None``: all).
    explicit
        Only those with an explicit form on ``scene`` (a mechanical system).

    Returns
    -------
    list of str
    """
    out = []
    for m in sync_plugins():
        if not m.plugin.default:
            continue
        if scene is not None and m.applies(scene) is not None:
            continue
        if explicit and scene is not None:
            try:
                m.system(scene)
            except Exception:  # noqa: BLE001 - no explicit form on this scene
                continue
        out.append(m.name)
    return out


def candidates() -> tuple[str, ...]:
    """The models a verdict weighs: :data:`PRIMARY` and the default plug-ins."""
    return PRIMARY + tuple(plugins())


def plugin_sources() -> list[Path]:
    """The source folders of the plug-in models' packages (part of the studies' and
    sweeps' code fingerprints, so that editing a plug-in recomputes its cases).

    Returns
    -------
    list of Path
    """
    import importlib

    from springfem.model_api import plugin_module

    folders = set()
    for m in sync_plugins():
        name = plugin_module(m.plugin)
        if name in ("springfem", "studies"):
            continue  # in every fingerprint already
        src = getattr(importlib.import_module(name), "__file__", None)
        if src:
            path = Path(src).parent if Path(src).name == "__init__.py" else Path(src)
            folders.add(path)
    return sorted(folders)
