"""The terms of the dynamic reference's step: the integrator's parameters, the consistent
mass matrix, the loads in time and the stored energy (:mod:`reference_fem.dynamics_implicit`
puts them together).

Examples
--------
>>> Integrator.trapezoidal().beta, Integrator.generalized_alpha(0.0).alpha_f
(0.25, 0.0)
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp
import skfem

from springfem.errors import InputError
from springfem.materials.laws.kinematics import det as _det

from .assembly import displacement_gradient
from .loads import ExternalLoads
from .problem import FemProblem


@dataclass(frozen=True)
class Integrator:
    """The parameters of a Newmark / generalised-α step.

    Attributes
    ----------
    alpha_m, alpha_f
        Where inertia and forces are balanced within the step (0: at its end).
    beta, gamma
        Newmark's parameters.
    name
        ``trapezoidal`` or ``generalized-alpha(rho_inf=...)``.
    """

    alpha_m: float
    alpha_f: float
    beta: float
    gamma: float
    name: str

    @classmethod
    def trapezoidal(cls) -> Integrator:
        """Newmark's average acceleration rule (``beta = 1/4``, ``gamma = 1/2``)."""
        return cls(0.0, 0.0, 0.25, 0.5, "trapezoidal")

    @classmethod
    def generalized_alpha(cls, rho_inf: float) -> Integrator:
        """Chung & Hulbert (1993): second order, dissipation set by ``rho_inf``.

        Parameters
        ----------
        rho_inf
            Spectral radius at infinite frequency, in ``[0, 1]``.

        Returns
        -------
        Integrator

        Examples
        --------
        >>> g = Integrator.generalized_alpha(1.0)
        >>> g.alpha_m, g.alpha_f, g.beta, g.gamma
        (0.5, 0.5, 0.25, 0.5)
        """
        if not 0.0 <= rho_inf <= 1.0:
            raise InputError(f"rho_inf must lie in [0, 1], got {rho_inf!r}")
        am = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0)
        af = rho_inf / (rho_inf + 1.0)
        gamma = 0.5 - am + af
        beta = 0.25 * (1.0 - am + af) ** 2
        return cls(am, af, beta, gamma, f"generalized-alpha(rho_inf={rho_inf:g})")

    @classmethod
    def of(cls, name: str, rho_inf: float = 0.8) -> Integrator:
        """``trapezoidal`` or ``generalized-alpha`` (with ``rho_inf``)."""
        if name == "trapezoidal":
            return cls.trapezoidal()
        if name == "generalized-alpha":
            return cls.generalized_alpha(rho_inf)
        raise InputError(f"integrator must be trapezoidal or generalized-alpha, got {name!r}")


def mass_matrix(problem: FemProblem) -> sp.bsr_matrix:
    """The consistent mass matrix ``M = int rho N_a N_b dV I_3`` of the displacement space.

    Integrated exactly (degree ``2 order``), whatever quadrature the forces use.

    Parameters
    ----------
    problem
        The discrete problem (its space, pattern and the scene's density).

    Returns
    -------
    scipy.sparse.bsr_matrix
        ``(3 n_nodes, 3 n_nodes)``, the displacement DOFs' ordering.

    Examples
    --------
    >>> from springfem.scene import scene_from_dict
    >>> s = scene_from_dict({"mesh": {"generator": "box", "size": [1, 2, 1],
    ...                               "divisions": [1, 1, 1]},
    ...                      "material": {"law": "linear", "E": 1.0, "nu": 0.3,
    ...                                   "density": 3.0}})
    >>> M = mass_matrix(FemProblem(s, order=2))
    >>> round(float(M.tocsr().sum()), 12)  # rho V for each of the three components
    18.0
    """
    space = problem.space
    basis = skfem.Basis(space.skmesh, space.element, space.mapping, intorder=2 * space.order)
    N = np.stack([np.asarray(b[0])[0] for b in basis.basis], axis=1)  # (nq, nloc)
    Me = problem.scene.material.density * np.einsum("eq,qa,qb->eab", basis.dx, N, N)
    blocks = Me[:, :, :, None, None] * np.eye(3)
    return problem.pattern.matrix(blocks)


class TimeLoads:
    """The scene's loads on a space, each scaled by its time function.

    Parameters
    ----------
    problem
        The discrete problem (its space; follower pressures when its law is nonlinear).
    """

    def __init__(self, problem: FemProblem):
        scene = problem.scene
        self.parts = [
            (ExternalLoads.from_scene(replace(scene, loads=[load]), problem.space,
                                      follower=problem.nonlinear), load)
            for load in scene.loads
        ]  # fmt: skip
        self.n = problem.space.n_dofs

    def factors(self, t: float, left: bool = False) -> list[float]:
        """Each load's factor at ``t`` (just before ``t`` when ``left``)."""
        out = []
        for _, load in self.parts:
            g = load.time
            out.append(1.0 if g is None else (g.left(t) if left else g(t)))
        return out

    def jumps(self) -> list[float]:
        """The times where a load jumps."""
        return sorted({t for _, load in self.parts if load.time for t in load.time.jumps()})

    def breakpoints(self) -> list[float]:
        """The times where a load jumps or changes slope."""
        return sorted({t for _, ld in self.parts if ld.time for t in ld.time.breakpoints()})

    def vector(self, U: np.ndarray, t: float, left: bool = False) -> np.ndarray:
        """The external force at time ``t`` and displacement ``U`` (``(n_nodes, 3)``)."""
        f = np.zeros(self.n)
        for (ext, _), g in zip(self.parts, self.factors(t, left), strict=True):
            if g != 0.0:
                f += ext.vector(U, g)
        return f

    def vector_and_stiffness(self, U: np.ndarray, t: float, left: bool = False):
        """The external force and its derivative ``d f / d u`` (``None`` if constant)."""
        f, K = np.zeros(self.n), None
        for (ext, _), g in zip(self.parts, self.factors(t, left), strict=True):
            if g == 0.0:
                continue
            fg, Kg = ext.vector_and_stiffness(U, g)
            f += fg
            if Kg is not None:
                K = Kg if K is None else K + Kg
        return f, K


def strain_energy(problem: FemProblem, x: np.ndarray) -> float:
    """The stored energy of state ``x``: ``int psi(F) dV`` (displacement formulations),
    ``u.K.u / 2`` (linear law), a formulation's own potential (nodal volume and strain:
    :meth:`~reference_fem.problem.FemProblem.energy` without the loads), or the mixed
    potential ``int W(F) - p (J - 1) - p^2 / (2 kappa) dV`` (:mod:`reference_fem.mixed`),
    whose rate is ``f_int . v`` when the constraint holds.

    Parameters
    ----------
    problem
        The discrete problem.
    x
        Its DOF vector.

    Returns
    -------
    float
    """
    if not problem.nonlinear:
        return 0.5 * float(x @ (problem.stiffness @ x))
    nu = problem.space.n_dofs
    if not problem.mixed and type(problem).energy is not FemProblem.energy:
        # a formulation with its own energy (nodal volumes, nodal strain): its potential
        # without the dead loads' work (None with follower loads: then the element part)
        total = problem.energy(x, 1.0)
        if total is not None:
            return float(total) + float(problem.loads.dead @ x[:nu])
    U = np.asarray(x[:nu]).reshape(-1, 3)
    F = np.eye(3) + displacement_gradient(problem.space, U)
    psi = problem.law_at(1.0).energy(F, frames=problem.qframes)
    if problem.mixed:
        _, p = problem.split(x)  # type: ignore[attr-defined]
        pq = np.einsum("qa,ea->eq", problem.p_values, p[problem.p_nodes])  # type: ignore[attr-defined]
        bulk = problem.bulk  # type: ignore[attr-defined]
        psi = psi - pq * (_det(F) - 1.0) - (pq**2 / (2.0 * bulk) if np.isfinite(bulk) else 0.0)
    return float((problem.space.dx * psi).sum())


class Recorder:
    """Probe trajectories and energies along a run of :mod:`reference_fem.dynamics_implicit`
    (``run``: its ``_Run``, which holds the problem, the probes and the matrices)."""

    def __init__(self, run, n: int):
        self.run = run
        self.q = np.zeros((n, run.P.shape[0], 3))
        self.qv = np.zeros((n, run.P.shape[0], 3))
        self.kinetic = np.zeros(n)
        self.strain = np.zeros(n)
        self.external = np.zeros(n)
        self.dissipated = np.zeros(n)

    def record(self, k: int, x: np.ndarray, v: np.ndarray, t: float) -> None:
        r = self.run
        self.q[k] = r.P @ r._U(x)
        self.qv[k] = r.P @ v.reshape(-1, 3)
        self.kinetic[k] = 0.5 * float(v @ (r.M @ v))
        self.strain[k] = strain_energy(r.problem, x)

    def increments(self, fe0, fe1, x0, x1, v0, v1, h) -> tuple[float, float]:
        """External work (trapezoid in ``u``) and damping dissipation of one step."""
        r = self.run
        du = x1[: r.nu] - x0[: r.nu]
        vm = 0.5 * (v0 + v1)
        return 0.5 * float((fe0 + fe1) @ du), h * float(vm @ r._damping_force(vm))

    def work(self, k, external: float, dissipated: float) -> None:
        """Add step ``k``'s external work and dissipation to the running sums."""
        self.external[k] = self.external[k - 1] + external
        self.dissipated[k] = self.dissipated[k - 1] + dissipated

    def probe_dict(self, velocity: bool = False) -> dict[str, np.ndarray]:
        q = self.qv if velocity else self.q
        return {name: q[:, i] for i, name in enumerate(self.run.probe_names)}

    def energy_dict(self) -> dict[str, np.ndarray]:
        total = self.kinetic + self.strain - self.external + self.dissipated
        return {
            "kinetic": self.kinetic,
            "strain": self.strain,
            "external_work": self.external,
            "dissipated": self.dissipated,
            "balance": total - total[0],
        }
