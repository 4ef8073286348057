"""Time integration of the P1 FEM: the core integrators drive :class:`ExplicitFem`.

``[fem] solver = "explicit"`` runs :func:`springfem.mechanics.explicit` (symplectic Euler,
lumped masses), ``"implicit"`` runs :func:`springfem.mechanics.implicit` (backward Euler
with the analytic tangent of :meth:`ExplicitFem.stiffness`; a follower load has none, and
the tangent is then taken by coloured finite differences). Only P1: the explicit kernel
is the linear tet's. Every law but the uncoupled neo-Hookean forms has a kernel; a tissue
material needs its penalty ``kappa`` (not ``incompressible = true``).

Examples
--------
>>> from reference_fem.options import FemOptions
>>> FemOptions(solver="explicit", t_end=0.1).solver in FemOptions.choices("solver")
True
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from springfem.errors import InputError
from springfem.mechanics import Trajectory, explicit, implicit
from springfem.scene import Scene

from .explicit import ExplicitFem
from .options import FemOptions


def dynamic_system(scene: Scene, order: int | None = None, law: str | None = None) -> ExplicitFem:
    """The P1 FEM of ``scene`` as a mechanical system for a time integration.

    Parameters
    ----------
    scene
        The scene.
    order
        Must be 1 (or ``None``): the dynamic FEM is P1.
    law
        ``linear``, ``neo-hookean`` or the scene's anisotropic law (``transverse-linear``,
        ``guccione``, ``holzapfel-ogden``, :mod:`reference_fem.explicit_anisotropic`);
        default: the scene's law.

    Returns
    -------
    ExplicitFem
    """
    if (order or FemOptions.of(scene).order) != 1:
        raise InputError("dynamic FEM (fem.solver explicit/implicit) is P1 only; use --order 1")
    law = law or scene.material.law
    return ExplicitFem(scene, "linear" if law == "linear" else law)


def solve_dynamic(
    system: ExplicitFem,
    options: FemOptions,
    callback: Callable[[int, float, np.ndarray, np.ndarray], bool | None] | None = None,
    progress: bool = False,
) -> Trajectory:
    """Integrate ``system`` in time as ``options`` (``[fem]``) ask.

    Parameters
    ----------
    system
        From :func:`dynamic_system`.
    options
        ``solver`` (``explicit`` or ``implicit``), ``t_end`` or ``steps``, ``dt``,
        ``mass_damping``, ``tol``/``max_iter`` (Newton of each implicit step).
    callback
        ``callback(step, t, x, v)`` after every step (e.g. a series writer).
    progress
        Show a progress bar.

    Returns
    -------
    Trajectory
    """
    o = options
    if o.solver == "explicit":
        return explicit(
            system, dt=o.dt, steps=o.steps, t_end=o.t_end, mass_damping=o.mass_damping,
            callback=callback, progress=progress,
        )  # fmt: skip
    if o.solver == "implicit":
        return implicit(
            system, dt=o.dt, steps=o.steps, t_end=o.t_end, mass_damping=o.mass_damping,
            tol=min(o.tol, 1e-8), max_iter=o.max_iter, callback=callback, progress=progress,
        )  # fmt: skip
    raise ValueError(f"solver {o.solver!r} is not a time integration")
