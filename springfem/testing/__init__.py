"""The conformance check every model passes: :func:`check_model`.

A model of the plug-in API (:mod:`springfem.model_api`) is checked on a scene through what
the protocol gives, its :class:`~springfem.mechanics.MechanicalSystem` (``model.system``)
and its static solve (``model.solve``), against references that owe nothing to the model:

rigid motion
    A rigid translation gives no internal force; so does a rotation: an infinitesimal one
    for every model, a finite one (with ``f(Q y) = Q f(y)`` on a deformed state) for a
    model whose forces are nonlinear in the positions or that claims finite rotations.
finite differences
    On a random deformed and rotated state, the forces are minus the central difference
    of the energy (where the system has one) and the tangent is minus the central
    difference of the forces (where it has one).
small-strain limit
    Where the model claims it: its tangent at rest is the linear P1 stiffness of the
    scene's small-strain law (``exact``), or its displacement under a tiny load is linear
    P1's within a tolerance (``limit``); the reference is :class:`LinearP1`, the core's
    own P1 element, unless another is given.
explicit energy
    Velocity Verlet (:func:`springfem.mechanics.explicit`), undamped, released from a
    smooth deformed state for a few hundred steps at a quarter of the stable step,
    conserves the total energy: its excursion is Verlet's, small and falling as ``dt^2``
    (a damped system's may only fall).

The tolerances are constants of :mod:`springfem.testing.checks`, each with its reason; a
check states what it measured against them. ``tests/studies/test_every_model.py`` calls
:func:`check_model` for every registered model; an out-of-tree model calls it in its own
tests (docs/plugins.rst#plugin-check).

Examples
--------
The core's linear P1 passes, with the finite rotation skipped because its forces are
linear and it claims none; the same forces with the tangent's sign flipped fail:

>>> import numpy as np
>>> from springfem.model_api import SystemModel
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({"mesh": {"generator": "box", "size": [0.04, 0.02, 0.02],
...     "divisions": [4, 2, 2], "split": "delaunay"}, "material": {"law": "linear",
...     "E": 1e4, "nu": 0.3, "density": 1000.0},
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
...     "load": [{"type": "traction", "region": "x_max", "value": [0, 0, -10.0]}]})
>>> report = check_model(SystemModel("p1", "linear P1", LinearP1), scene,
...                      small_strain="exact")
>>> report.passed, [c.status for c in report.checks]
(True, ['passed', 'passed', 'skipped', 'passed', 'passed', 'passed', 'passed'])
>>> class Flipped(LinearP1):
...     def stiffness(self, x, scale=1.0):
...         return -self.K
>>> report = check_model(SystemModel("flipped", "P1, tangent sign flipped", Flipped),
...                      scene, strict=False)
>>> [c.name for c in report.failures]  # the stable step comes from the tangent
['tangent', 'explicit energy']
>>> print(report.checks[4].line())
tangent: failed: |K d + df/dx d| (central differences, h = 1e-04 l) / |df/dx d| = 2 > 1e-06
>>> check_model(SystemModel("flipped", "P1", Flipped), scene)  # doctest: +ELLIPSIS
Traceback (most recent call last):
AssertionError: model flipped fails 2 checks on scene ...: tangent: ...
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..errors import InputError
from ..scene import Scene
from . import checks as _c
from .checks import STEPS, Rotation, SmallStrain, Tangent
from .reference import LinearP1, rotation, scaled_scene
from .report import Check, ModelReport, Status


def _guarded(name: str, run: Callable[[], Check]) -> Check:
    try:
        return run()
    except Exception as exc:  # noqa: BLE001 - a crash is a failed check, named
        return Check(name, "failed", f"raised {type(exc).__name__}: {exc}")


NAMES = ("translation", "infinitesimal rotation", "finite rotation", "energy gradient",
         "tangent", "small strain", "explicit energy")  # fmt: skip


def check_model(
    model: Any,
    scene: Scene,
    *,
    rotation: Rotation | None = None,
    small_strain: SmallStrain | None = None,
    small_strain_tol: float | None = None,
    tangent: Tangent | None = None,
    linear: Any = None,
    steps: int = STEPS,
    seed: int = 0,
    strict: bool = True,
) -> ModelReport:
    """Check a model on a scene: rigid motion, finite differences, the small-strain limit
    and the energy of an explicit run (the module text says how, and each tolerance why).

    Parameters
    ----------
    model
        A :class:`~springfem.model_api.ModelPlugin` (``name``, ``applies``, ``system``,
        ``solve``). Its optional ``claims`` mapping gives the defaults of ``rotation``,
        ``small_strain``, ``small_strain_tol`` and ``tangent``.
    scene
        The scene (small: a few hundred tets, not a cube).
    rotation
        ``finite``: the model claims invariance under finite rotations; ``infinitesimal``:
        only under infinitesimal ones (a small-strain model). ``None``: finite when its
        forces are nonlinear in the positions (a nonlinear model that is not objective is
        a defect), else infinitesimal.
    small_strain
        ``exact``: its tangent at rest is linear P1's; ``limit``: its displacement under a
        tiny load is linear P1's within ``small_strain_tol``; ``None``: no claim, skipped.
    small_strain_tol
        The bound of the small-strain check (default :data:`LIMIT_TOL` for ``limit``,
        :data:`EXACT_TOL` for ``exact``).
    tangent
        ``approximate``: the model's stiffness is deliberately not the forces' derivative
        (a warped or secant stiffness for Newton): measured and reported, not failed.
        ``None`` or ``exact``: it must be the derivative.
    linear
        The small-strain reference: a mechanical system, a model (its ``system``) or a
        function of the scene returning a system (default :class:`LinearP1`).
    steps
        Explicit steps of the energy check.
    seed
        Of the random states and directions.
    strict
        Raise ``AssertionError`` listing the failures.

    Returns
    -------
    ModelReport
        Each check passed, skipped (with the reason) or failed (with the numbers).

    Raises
    ------
    AssertionError
        With ``strict``, when a check failed.
    """
    claims = dict(getattr(model, "claims", None) or {})
    rotation = rotation or claims.get("rotation")
    small_strain = small_strain or claims.get("small_strain")
    small_strain_tol = small_strain_tol or claims.get("small_strain_tol")
    tangent = tangent or claims.get("tangent")
    report = ModelReport(str(model.name), str(scene.name))
    why = model.applies(scene)
    if why is not None:
        report.checks = [Check(n, "skipped", f"does not apply: {why}") for n in NAMES]
        return report
    system = None
    try:
        system = model.system(scene)
    except InputError as exc:
        why = f"no mechanical system: {exc}"
    if system is None:
        why = why or "no mechanical system (model.system returned None)"
        report.checks = [Check(n, "skipped", why) for n in NAMES[:5]]
        body = None
    else:
        body = _c.Body(system, seed)
        runs: list[Callable[[], Check]] = [
            lambda: _c.translation(body), lambda: _c.infinitesimal_rotation(body),
            lambda: _c.finite_rotation(body, rotation), lambda: _c.energy_gradient(body),
            lambda: _c.tangent(body, tangent),
        ]  # fmt: skip
        report.checks = [_guarded(n, r) for n, r in zip(NAMES[:5], runs, strict=True)]
    report.checks.append(_guarded("small strain", lambda: _c.small_strain(
        model, scene, body, small_strain, small_strain_tol, linear)))  # fmt: skip
    if body is None:
        report.checks.append(Check("explicit energy", "skipped", str(why)))
    else:
        report.checks.append(_guarded("explicit energy", lambda: _c.explicit_energy(body, steps)))
    if strict:
        report.raise_on_failure()
    return report


__all__ = ["Check", "LinearP1", "ModelReport", "Status", "check_model", "rotation", "scaled_scene"]
