"""The critical (stable) time step of explicit integration, ``dt_crit = 2 / omega_max``.

Examples
--------
A unit mass on a spring of stiffness 4 (``omega = 2``):

>>> import numpy as np
>>> from springfem.mechanics.toy import Oscillator
>>> dt_crit, omega = stable_time_step(Oscillator())
>>> round(dt_crit, 12), round(omega, 12)
(1.0, 2.0)
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from springfem.errors import SolverError

from .context import JacobianKind, Scale, SolveContext
from .linsolve import is_symmetric
from .system import MechanicalSystem, constrained_positions

#: Up to this many free DOFs, the critical time step uses a dense eigensolver.
DENSE_EIG_THRESHOLD = 600


def stable_time_step(
    system: MechanicalSystem,
    x: np.ndarray | None = None,
    scale: float = 1.0,
    jacobian: JacobianKind = "auto",
) -> tuple[float, float]:
    """Critical time step ``2 / omega_max`` of explicit integration at a state.

    ``omega_max^2`` is the largest eigenvalue of ``M^-1 K`` on the free DOFs, computed as
    the largest eigenvalue of the symmetric ``M^-1/2 K M^-1/2`` (dense below
    :data:`DENSE_EIG_THRESHOLD` free DOFs, Lanczos ``eigsh`` above). For a non-symmetric
    tangent (non-gradient forces) ``omega_max^2`` is the largest ``|lambda|`` of ``M^-1 K``.
    Symplectic Euler and velocity Verlet are stable for linear systems iff
    ``omega_max dt < 2``.

    Parameters
    ----------
    system
        The system.
    x
        State ``(n, 3)``; default the rest positions (fixed DOFs are set to
        ``prescribed(scale)`` in either case).
    scale
        Load factor.
    jacobian
        ``auto`` (analytic if available, else coloured finite differences), ``analytic``
        or ``fd``.

    Returns
    -------
    dt_crit, omega_max
        ``(inf, 0)`` when the tangent has no positive eigenvalue.
    """
    ctx = SolveContext(system)
    x = constrained_positions(system, scale, x)
    Kff = ctx.ff(ctx.stiffness(x, scale, jacobian))
    d = sp.diags(1.0 / np.sqrt(ctx.m_dof[ctx.free]))
    A = (d @ Kff @ d).tocsr()
    n = A.shape[0]
    if n == 0:
        return float("inf"), 0.0
    sym = is_symmetric(A)
    if sym:
        A = ((A + A.T) * 0.5).tocsr()
    if n <= DENSE_EIG_THRESHOLD:
        if sym:
            lam = float(scipy.linalg.eigvalsh(A.toarray())[-1])
        else:
            lam = float(np.abs(np.linalg.eigvals(A.toarray())).max())
    else:
        lam = _largest_eigenvalue(A, sym)
    if not lam > 0:
        return float("inf"), 0.0
    omega = float(np.sqrt(lam))
    return 2.0 / omega, omega


def _largest_eigenvalue(A: sp.csr_matrix, sym: bool) -> float:
    rng = np.random.default_rng(1)
    v0 = rng.standard_normal(A.shape[0])
    ncv = min(A.shape[0], 40)
    try:
        if sym:
            return float(spla.eigsh(A, k=1, which="LA", tol=1e-8, ncv=ncv, v0=v0)[0][0])
        return float(np.abs(spla.eigs(A, k=1, which="LM", tol=1e-8, ncv=ncv, v0=v0)[0][0]))
    except spla.ArpackNoConvergence:
        # Gershgorin: an upper bound on the spectral radius (a safe, smaller dt).
        return float(np.abs(A).sum(axis=1).max())


def choose_time_step(
    system: MechanicalSystem, dt: float | None, dt_safety: float, scale: Scale
) -> tuple[float, float | None]:
    """The time step to use: ``dt`` if given, else ``dt_safety * dt_crit`` at rest.

    Parameters
    ----------
    system
        The system.
    dt
        A given time step, or ``None``.
    dt_safety
        Fraction of the critical time step.
    scale
        Load factor (or a function of time: its value at ``t = 0`` is used).

    Returns
    -------
    dt, dt_crit
        ``dt_crit`` is ``None`` when ``dt`` was given.

    Raises
    ------
    SolverError
        When the tangent has no positive eigenvalue and no ``dt`` is given.
    """
    if dt is not None:
        if not dt > 0:
            raise ValueError(f"dt must be positive, got {dt}")
        return float(dt), None
    s0 = scale(0.0) if callable(scale) else float(scale)
    dt_crit, _ = stable_time_step(system, scale=s0)
    if not np.isfinite(dt_crit):
        raise SolverError(
            "cannot choose a time step: the stiffness has no positive eigenvalue; give dt"
        )
    return dt_safety * dt_crit, dt_crit
