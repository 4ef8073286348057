"""The model plug-in API: what a model must provide to join the comparisons and studies.

A *model* is a name, a label and a static solve of a scene, optionally with an explicit
form (a :class:`~springfem.mechanics.MechanicalSystem`) that timed runs, the critical step
and the step cost use. Anything with these members is a :class:`ModelPlugin` (structural
typing, no base class to inherit); :class:`SystemModel` builds one from a function that
makes the mechanical system, with a static Newton solve and a timed explicit run on the
core's solvers and the result contract (docs/contract.rst#result-fields) filled in.

A package makes its models known in one of two ways, one code path (:func:`register_model`):

- an entry point of group ``springfem.models`` in its distribution's metadata
  (``pyproject.toml``: ``[project.entry-points."springfem.models"]``,
  ``name = "module:attribute"``), naming a plug-in object, a sequence of them, or a
  function returning either; found by :func:`plugin_models` without the core naming it;
- :func:`register_model` in Python (a script, a notebook, a test).

The comparisons look models up by name, case-insensitively; a registered model appears in
``compare --models``, ``verdict``, sweeps and the studies that weigh models
(docs/plugins.rst).

Examples
--------
A plug-in is checked by its members; :func:`model_result` fills the result contract from
a displacement (here: a 10 % stretch along x of a unit cube):

>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({"mesh": {"generator": "box", "size": [1, 1, 1],
...     "divisions": [1, 1, 1]}, "material": {"law": "linear", "E": 1e4, "nu": 0.3},
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}]})
>>> model = SystemModel("mine", "my model", lambda scene: None)
>>> isinstance(model, ModelPlugin), model.default
(True, True)
>>> u = 0.1 * scene.mesh.points * [1.0, 0.0, 0.0]
>>> r = model_result(scene, u, model="mine", element="P1", law="linear", wall_time=0.0,
...                  converged=True, iterations=1)
>>> r.model, round(r.volume["relative_change"], 12), r.counts["fixed_dofs"]
('mine', 0.1, 12)
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

from .errors import InputError, SolverError
from .loads import reactions
from .mechanics.limits import SolveStopped
from .mechanics.system import MechanicalSystem
from .plugins import entry_points, load
from .result import Result, volume_summary
from .scene import Scene

#: The entry-point group of model plug-ins.
GROUP = "springfem.models"


@dataclass
class ModelSolution:
    """What every model's solve returns: the result record, the nodal displacement
    ``(n, 3)`` at the mesh vertices, per-element data for the VTU file, the plausibility
    warnings of the state (:func:`springfem.api.solve` fills them:
    :func:`springfem.plausibility.check_solution`, the lines the CLI prints) and the
    solver's own record, when a model keeps it (iterations, residual history ...)."""

    result: Result
    u: np.ndarray
    cell_data: dict[str, np.ndarray] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    info: Any = None


@runtime_checkable
class ModelPlugin(Protocol):
    """A model the comparisons and studies can weigh.

    Attributes
    ----------
    name
        Its one spelling (``compare --models NAME``, table rows, sweep files); unique
        case-insensitively among the registered models.
    label
        A longer human name for tables and figures.
    default
        Whether the studies and the verdict weigh it without being asked (where
        :meth:`applies`); ``False``: only when named (``--models``, a sweep file).
    settings
        The model's own settings (substeps, iterations, tangent ...): plain values that
        go into the studies' cache keys, so that changing one recomputes.

    Notes
    -----
    Optional, not checked by ``isinstance``: a plug-in may offer ``sweep``, a sequence of
    mappings of its own settings (most telling first), with ``with_settings(**changes)``
    returning the model with those settings changed. The speed-accuracy study then charts
    one point per sweep entry (its quick preset the first few) where a model without
    ``sweep`` has one static point (docs/peers.rst#in-the-studies).

    A model without an explicit form (``system`` ``None``) whose dynamics are its own may
    offer them to the studies, each member optional (``peers.plugin.XPBDModel`` has all):

    - ``largest_step(scene, steps, bisections) -> dict``: the largest step its undamped run
      survives with the loads off (``dt_pred``, ``dt_measured``, ``ratio``, ``setting_h``,
      ``failure``): the stability study's critical-step series;
    - ``variants``: a mapping of variant names to changes of its settings, weighed beside
      it in the stability study (each through ``with_settings``);
    - ``release_run(scene, t_end=, safety=, samples=, probe=) -> dict``: released from its
      static state with the loads off (``status``, ``dt``, ``u_steps`` the probe
      displacement after every step, ``energy_t``, ``energy`` ...), and
      ``step_timer(scene, safety) -> go(steps, tick)``: the dynamics study's run and cost;
      ``setting_step``: the step (s) of its own settings.

    Any model may offer ``kernel_pass(scene) -> (go, bytes_per_tet)``: a function running
    one pass of its kernel over every element (a force pass; one iteration of a
    position-based peer) and the bytes that pass moves per element, for
    ``springfem bench forces --models`` (without it the bench times ``system(scene)``'s
    internal forces).

    What a model applies to, which the verdict and the studies ask (:func:`declared`;
    the default when a model does not say):

    - ``order`` (``None``): the polynomial order of its tets (1: linear tets, the spring
      elements included; 2: quadratic);
    - ``reference`` (``False``): an FEM of the scene's law that may be a comparison's
      reference;
    - ``locking_free`` (``False``): accurate near incompressibility, so weighed too on a
      nearly incompressible scene;
    - ``claims`` (``{}``): what :func:`springfem.testing.check_model` holds it to
      (``small_strain``: ``exact``, its tangent at rest is linear P1's, or ``limit``, its
      solve under a tiny load is; ``rotation``; ``tangent``);
    - ``law`` (``None``): the law it solves in its own words (``None``: the scene's);
    - ``locks(scene)`` (``None``): why it locks on the scene (ruled out as a reference);
    - ``solve_key(scene)`` (its name): models with equal keys are the same solve;
    - ``law_versus(scene, reference_law)``: what it solves against the reference's law;
    - ``fem_options(scene)``: the ``[fem]`` options an FEM model solves the scene with.
    """

    name: str
    label: str
    default: bool
    settings: Mapping[str, Any]

    def applies(self, scene: Scene) -> str | None:
        """Why the model cannot solve ``scene`` in one line (``None``: it can)."""
        ...

    def solve(self, scene: Scene, verbose: bool = False) -> ModelSolution:
        """The static equilibrium of ``scene`` under its loads (raise
        :class:`~springfem.errors.SolverError` with ``state`` and ``load_factor`` when a
        load-stepped solve stops part way)."""
        ...

    def system(self, scene: Scene) -> MechanicalSystem | None:
        """The model's explicit form (forces, masses, constraints), or ``None`` when it
        has none (or raise :class:`~springfem.errors.InputError` saying why it has none on
        this scene): what timed runs, the stable step and the step cost use."""
        ...


def declared(model: Any, name: str, *args: Any, default: Any = None) -> Any:
    """What ``model`` declares as ``name`` (an attribute, or a method called with ``args``:
    :class:`ModelPlugin`, Notes), or ``default`` when it does not say.

    Examples
    --------
    >>> m = SystemModel("mine", "my model", lambda scene: None)
    >>> declared(m, "locking_free", default=False), declared(m, "locks", None)
    (False, None)
    """
    got = getattr(model, name, None)
    if got is None:
        return default
    return got(*args) if callable(got) else got


def model_result(
    scene: Scene,
    u: np.ndarray,
    *,
    model: str,
    element: str,
    law: str,
    wall_time: float,
    converged: bool,
    iterations: int,
    residual: np.ndarray | None = None,
    info: dict[str, Any] | None = None,
    status: str = "converged",
) -> Result:
    """A :class:`~springfem.result.Result` of displacement ``u`` with the contract's fields.

    Parameters
    ----------
    scene
        The scene solved.
    u
        Nodal displacement ``(n, 3)``.
    model, element, law
        The result's labels (a plug-in's name, its element, its law).
    wall_time
        Seconds of the solve.
    converged, iterations
        Solver outcome.
    residual
        Internal plus external nodal force ``(n, 3)`` at the solution, for the support
        reactions (``None``: no reactions).
    info
        Model-specific extras.
    status
        ``converged`` or the timed run's ``end of run at t = ...``.

    Returns
    -------
    Result
    """
    u = np.asarray(u, dtype=float).reshape(-1, 3)
    mesh = scene.mesh
    return Result(
        scene=scene.name,
        model=model,
        element=element,
        law=law,
        counts={
            "nodes": mesh.n_points,
            "tets": mesh.n_tets,
            "dofs": 3 * mesh.n_points,
            "fixed_dofs": int(scene.dirichlet()[0].size),
        },
        probes=scene.probe_displacements(u),
        volume=volume_summary(mesh, u),
        reactions={} if residual is None else reactions(scene, residual),
        wall_time=float(wall_time),
        converged=bool(converged),
        iterations=int(iterations),
        info=dict(info or {}),
        status=status,
    )


class SystemModel:
    """A model plug-in made from a mechanical system: static Newton and a timed run.

    Parameters
    ----------
    name, label
        See :class:`ModelPlugin`.
    build
        ``build(scene, **settings) -> MechanicalSystem``: the model's system on a scene
        (raise :class:`~springfem.errors.InputError` when the scene does not fit it).
    element, law
        The result's ``element`` label and ``law`` (default: the scene's law); both are
        attributes too (``law`` ``None``: the scene's).
    default
        See :class:`ModelPlugin`.
    applies
        ``applies(scene) -> str | None`` (default: every scene).
    static
        Keyword arguments of :func:`springfem.mechanics.static` (``tol``, ``load_steps``,
        ``jacobian`` ...).
    **settings
        The model's own settings, passed to ``build``.
    """

    def __init__(
        self,
        name: str,
        label: str,
        build: Callable[..., MechanicalSystem],
        *,
        element: str = "P1",
        law: str | None = None,
        default: bool = True,
        applies: Callable[[Scene], str | None] | None = None,
        static: Mapping[str, Any] | None = None,
        **settings: Any,
    ):
        self.name = name
        self.label = label
        self.default = default
        self.settings: Mapping[str, Any] = dict(settings)
        self.element = element
        self.law = law
        self._build = build
        self._applies = applies
        self._static = dict(static or {})

    def __repr__(self) -> str:
        return f"SystemModel({self.name!r}, settings={dict(self.settings)!r})"

    def applies(self, scene: Scene) -> str | None:
        return None if self._applies is None else self._applies(scene)

    def system(self, scene: Scene) -> MechanicalSystem:
        why = self.applies(scene)
        if why is not None:
            raise InputError(why)
        return self._build(scene, **self.settings)

    def solve(self, scene: Scene, verbose: bool = False) -> ModelSolution:
        """Static equilibrium by :func:`springfem.mechanics.static` on :meth:`system`."""
        from .mechanics import static

        t0 = time.perf_counter()
        system = self.system(scene)
        try:
            info = static(system, **self._static)
        except (SolverError, SolveStopped) as exc:
            state = getattr(exc, "state", None)
            if state is not None:
                state = np.asarray(state).reshape(-1, 3) - system.x0
            load_factor = getattr(exc, "load_factor", None)
            raise type(exc)(f"{self.name}: {exc}", state=state, load_factor=load_factor) from None
        u = info.x - system.x0
        if verbose:
            print(f"{self.name}: {info.iterations} Newton iterations", file=sys.stderr)
        return ModelSolution(
            model_result(
                scene, u, model=self.name, element=self.element,
                law=self.law or scene.material.law, wall_time=time.perf_counter() - t0,
                converged=info.converged, iterations=info.iterations,
                residual=system.forces(info.x, None),
                info={"method": info.method, "jacobian": info.jacobian,
                      "load_steps": len(info.load_steps), "settings": dict(self.settings),
                      "residual": info.residual_history[-1] if info.residual_history else None},
            ),
            u,
        )  # fmt: skip

    def run(
        self, scene: Scene, steps: int, dt: float | None = None, verbose: bool = False
    ) -> ModelSolution:
        """A timed explicit run from rest under the scene's loads (velocity Verlet).

        Parameters
        ----------
        scene
            The scene.
        steps
            Time steps.
        dt
            Time step (default: 0.9 of the stable step).
        verbose
            A progress bar.

        Returns
        -------
        ModelSolution
            The state at the end, ``status`` "end of run at t = ...".
        """
        from .mechanics import explicit, stable_time_step

        t0 = time.perf_counter()
        system = self.system(scene)
        if dt is None:
            dt = 0.9 * stable_time_step(system)[0]
        traj = explicit(system, dt=dt, steps=steps, integrator="verlet", progress=verbose)
        u = traj.x - system.x0
        t = steps * dt
        return ModelSolution(
            model_result(
                scene, u, model=self.name, element=self.element,
                law=self.law or scene.material.law, wall_time=time.perf_counter() - t0,
                converged=False, iterations=steps, residual=system.forces(traj.x, None),
                info={"dt": dt, "steps": steps, "settings": dict(self.settings)},
                status=f"end of run at t = {t:.4g} s after {steps} steps",
            ),
            u,
        )  # fmt: skip


_REGISTERED: dict[str, ModelPlugin] = {}
_MODULES: dict[str, str] = {}
_LOADED: list[bool] = []


def plugin_module(plugin: ModelPlugin) -> str:
    """The top-level package a plug-in's code lives in (its entry point's module, else the
    module of a :class:`SystemModel`'s ``build``, else of its class).

    Parameters
    ----------
    plugin
        A registered plug-in.

    Returns
    -------
    str
    """
    name = _MODULES.get(plugin.name)
    if name is None:
        build = getattr(plugin, "_build", None)
        name = getattr(build, "__module__", None) or type(plugin).__module__
    return name.split(".")[0]


def register_model(plugin: Any, module: str | None = None) -> list[ModelPlugin]:
    """Register a model plug-in, a sequence of them, or a function returning either.

    Parameters
    ----------
    plugin
        A :class:`ModelPlugin`, a list or tuple of them, or a callable without arguments
        returning one of these (what an entry point names).
    module
        The module the plug-in comes from (default: found by :func:`plugin_module`).

    Returns
    -------
    list of ModelPlugin
        The plug-ins registered.

    Raises
    ------
    InputError
        Something that is not a model (one line naming what is missing), or a second model
        with a registered model's name.
    """
    if callable(plugin) and not isinstance(plugin, ModelPlugin):
        plugin = plugin()
    items = list(plugin) if isinstance(plugin, list | tuple) else [plugin]
    for p in items:
        if not isinstance(p, ModelPlugin):
            need = ("name", "label", "default", "settings", "applies", "solve", "system")
            missing = [a for a in need if not hasattr(p, a)]
            raise InputError(f"model plug-in {p!r} lacks {', '.join(missing)}")
        old = next((q for k, q in _REGISTERED.items() if k.lower() == p.name.lower()), None)
        if old is not None and old is not p:
            raise InputError(f"model {p.name!r} is registered twice")
        _REGISTERED[p.name] = p
        if module is not None:
            _MODULES[p.name] = module
    return items


def plugin_models() -> dict[str, ModelPlugin]:
    """The registered plug-ins, by name: the entry points' (loaded once) and
    :func:`register_model`'s.

    A plug-in whose entry point fails to load is left out with one ``warning:`` line on
    stderr naming it, so that a broken package does not stop the others.

    Returns
    -------
    dict
    """
    if not _LOADED:
        _LOADED.append(True)
        for name, value in sorted(entry_points(GROUP).items()):
            try:
                register_model(load(value), module=value.partition(":")[0])
            except Exception as exc:  # noqa: BLE001 - any failure of a third-party package
                print(
                    f"springfem: warning: model plug-in {name} ({value}) not loaded: {exc}",
                    file=sys.stderr,
                )
    return dict(_REGISTERED)
