"""The dynamic reference: implicit time integration of P2 and P2/P1 mixed hyperelasticity.

Every law and formulation of the static reference (:func:`reference_fem.solver.make_problem`)
moves in time with a consistent mass matrix (:func:`mass_matrix`) and Rayleigh damping
``C = a_M M + a_K K_0`` from the scene's ``[dynamics]`` section
(:class:`springfem.scene.DynamicsOptions`; ``K_0`` is the tangent at rest). A step solves

    M a_{n+1-am} + C v_{n+1-af} + (1-af) (f_int - f_ext)_{n+1} + af (f_int - f_ext)_n = 0

for ``u_{n+1}`` by Newton, with the Newmark updates
``u_{n+1} = u_n + h v_n + h^2 ((1/2 - beta) a_n + beta a_{n+1})`` and
``v_{n+1} = v_n + h ((1 - gamma) a_n + gamma a_{n+1})``: the trapezoidal rule
(``am = af = 0``, ``beta = 1/4``, ``gamma = 1/2``; second order, no numerical damping)
or Chung–Hulbert's generalised-α (:meth:`Integrator.generalized_alpha`, with the spectral
radius ``rho_inf`` at infinite frequency; ``rho_inf = 1`` gives the trapezoidal rule's
motion). Internal forces and tangents are the static reference's own
(:meth:`~reference_fem.problem.FemProblem.internal_force`); the mixed formulation's
pressure rows are its incompressibility constraint at ``t_{n+1}`` (the pressure has no
inertia). Loads follow their time functions (:mod:`springfem.scene.load_time`); a jump
in a load is put on the time grid and the acceleration is taken afresh after it, so the
rule stays second order across a release.

A run records the probe trajectories, the kinetic and strain energies, the work of the
loads, the energy dissipated by damping and the balance of the four (zero up to the
time-integration error: to round-off for the trapezoidal rule on a linear law), and the
full field at chosen frames. The manual: docs/fem.rst#the-dynamic-reference.

Examples
--------
A cantilever released from its static deflection under a small tip load swings about
its rest state:

>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({
...     "mesh": {"generator": "box", "size": [0.1, 0.01, 0.01], "divisions": [6, 1, 1]},
...     "material": {"law": "linear", "E": 1.0e4, "nu": 0.3, "density": 1000.0},
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
...     "load": [{"type": "traction", "region": "x_max", "value": [0, 0, -0.01],
...               "time": {"release": 0.0}}],
...     "probe": [{"name": "tip", "point": [0.1, 0.005, 0.005]}],
...     "dynamics": {"initial": "static"}})
>>> r = run(scene, t_end=1.0, dt=0.01)
>>> z = r.probes["tip"][:, 2]
>>> bool(z[0] < 0 < z.max()), len(r.times), r.steps
(True, 101, 100)
>>> bool(abs(r.energies["balance"]).max() < 1e-10 * r.energies["strain"][0])
True
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import cg

from springfem.errors import InputError, SolverError
from springfem.regions import locate_points
from springfem.scene import DynamicsOptions, Scene
from springfem.scene.dynamics import STEPS

from .dynamics_terms import Integrator, Recorder, TimeLoads, mass_matrix
from .newton import InvertedElements
from .options import FemOptions
from .problem import FemProblem
from .solver import check_memory, make_problem, solve

#: How many times a Newton increment that inverts an element is halved before giving up.
MAX_HALVINGS = 10
#: A step whose Newton fails is split in two at most this many times over (a step of
#: ``dt / 2**MAX_SPLITS`` at the shortest) before the run gives up.
MAX_SPLITS = 3
#: ``linear_solver = "auto"`` factorises up to this many DOFs in a dynamic run (PARDISO): a
#: factorisation serves several steps' solves, where AMG rebuilds a preconditioner and
#: iterates for each (pull-release at 24,375 P2 DOFs: 1.8 s a step direct, 15 s with AMG).
DIRECT_MAX_DOFS = 60_000
#: A nonlinear step reuses the last step's factorised matrix when that step converged in at
#: most this many iterations, else it starts with a fresh tangent.
REUSE_ITERATIONS = 4


@dataclass
class DynamicResult:
    """A dynamic run of the reference.

    Attributes
    ----------
    times
        ``(n + 1,)`` the time grid (s), ``times[0] = 0``.
    probes
        Probe name -> ``(n + 1, 3)`` displacement trajectory.
    energies
        ``kinetic``, ``strain``, ``external_work`` (of the loads since ``t = 0``),
        ``dissipated`` (by damping since ``t = 0``) and ``balance`` (kinetic + strain -
        external work + dissipated, minus its value at ``t = 0``), each ``(n + 1,)``.
    frame_times, frames
        The kept full fields: times, and ``(n_vertices, 3)`` vertex displacements.
    newton_iterations
        ``(n,)`` Newton iterations of each step.
    info
        Settings and counts: element, law, integrator, damping, DOFs, wall time,
        seconds per step, factorisations.
    probe_velocities
        Probe name -> ``(n + 1, 3)`` velocity (for :meth:`probes_at`).
    """

    times: np.ndarray
    probes: dict[str, np.ndarray]
    energies: dict[str, np.ndarray]
    frame_times: list[float] = field(default_factory=list)
    frames: list[np.ndarray] = field(default_factory=list)
    newton_iterations: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    info: dict = field(default_factory=dict)
    probe_velocities: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def steps(self) -> int:
        """The number of time steps taken."""
        return len(self.times) - 1

    def probes_at(self, times) -> dict[str, np.ndarray]:
        """The probe trajectories at other ``times`` (a fast model's frames): cubic Hermite
        interpolation in each step from the displacements and velocities at its ends, so
        the interpolation adds ``O(h^4)`` to the rule's ``O(h^2)``.

        Parameters
        ----------
        times
            Times inside ``[0, t_end]`` (s).

        Returns
        -------
        dict
            Probe name -> ``(len(times), 3)``.
        """
        t = np.clip(np.asarray(times, dtype=float), self.times[0], self.times[-1])
        k = np.clip(np.searchsorted(self.times, t, side="right") - 1, 0, len(self.times) - 2)
        h = self.times[k + 1] - self.times[k]
        s = ((t - self.times[k]) / h)[:, None]
        h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
        h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
        out = {}
        for name, q in self.probes.items():
            v = self.probe_velocities[name]
            hv = h[:, None]
            out[name] = h00 * q[k] + h10 * hv * v[k] + h01 * q[k + 1] + h11 * hv * v[k + 1]
        return out

    def to_dict(self) -> dict:
        """Plain lists, for JSON."""
        return {
            "times": self.times.tolist(),
            "probes": {k: v.tolist() for k, v in self.probes.items()},
            "energies": {k: v.tolist() for k, v in self.energies.items()},
            "frame_times": list(self.frame_times),
            "newton_iterations": self.newton_iterations.tolist(),
            "info": self.info,
        }


def time_grid(t_end: float, dt: float, breakpoints: list[float]) -> np.ndarray:
    """Steps of ``dt`` from 0 to ``t_end`` (the last one shorter if need be), with the
    loads' breakpoints (jumps and kinks) inside the run added as grid points: a step then
    never straddles one, and the rule keeps its order.

    Examples
    --------
    >>> time_grid(0.3, 0.1, [0.15, 0.2]).round(12).tolist()
    [0.0, 0.1, 0.15, 0.2, 0.3]
    """
    n = max(1, math.ceil(t_end / dt - 1e-9))
    grid = np.minimum(np.arange(n + 1) * dt, t_end)
    inner = [t for t in breakpoints if 0.0 < t < t_end]
    grid = np.unique(np.concatenate([grid, inner]))
    close = np.diff(grid) < 1e-9 * dt  # a jump on a grid point
    return np.delete(grid, np.flatnonzero(close) + 1) if close.any() else grid


def run(
    scene: Scene,
    t_end: float | None = None,
    dt: float | None = None,
    order: int = 2,
    formulation: str | None = None,
    probes: Mapping[str, object] | None = None,
    law: str | None = None,
    integrator: str | None = None,
    rho_inf: float | None = None,
    initial: str | np.ndarray | None = None,
    frames: int | Sequence[float] | None = None,
    tol: float = 1e-8,
    max_iter: int = 25,
) -> DynamicResult:
    """Integrate a scene in time with the implicit reference (module docstring).

    Parameters
    ----------
    scene
        The scene; its ``[dynamics]`` section gives the defaults of ``t_end``, ``dt``,
        ``integrator``, ``rho_inf``, ``initial``, ``frames`` and the damping.
    t_end, dt
        Simulated time and time step (s).
    order
        Displacement order: 2 (the reference) or 1.
    formulation
        ``displacement`` or ``mixed`` (P2/P1, for incompressible or nearly incompressible
        material); default: the scene's ``[fem] formulation``.
    probes
        Extra points to follow, name -> ``[x, y, z]`` (inside the mesh), besides the
        scene's probes.
    law
        As for :func:`reference_fem.solve` (default: the scene's).
    integrator, rho_inf
        ``trapezoidal`` or ``generalized-alpha`` with its ``rho_inf``.
    initial
        ``rest``, ``static`` (equilibrium under the loads just before ``t = 0``) or a DOF
        vector of the displacement space (then at rest). Prescribed displacements hold
        from ``t = 0`` on (from rest, a nonzero one is a jump at the start).
    frames
        How many full fields to keep, evenly spaced in time (first and last included), or
        the times to keep them at (each the first step at or after it).
    tol
        Newton tolerance on the residual relative to the forces of the step (1e-8 moves
        the organ scene's probes by 1e-8 of their motion against 1e-10, a quarter faster).
    max_iter
        Newton iterations per step at most.

    Returns
    -------
    DynamicResult

    Raises
    ------
    InputError
        Bad settings or a probe outside the mesh.
    SolverError
        A step's Newton does not converge (the message gives the time).
    MemoryLimitExceeded
        The solves would not fit the memory limit
        (:func:`reference_fem.solver.check_memory`).

    Examples
    --------
    A block under gravity switched on at ``t = 0``, watched at a point off the step grid:

    >>> from springfem.scene import scene_from_dict
    >>> block = scene_from_dict({
    ...     "mesh": {"generator": "box", "size": [1, 1, 1], "divisions": [1, 1, 1]},
    ...     "material": {"law": "neo-hookean", "E": 1e4, "nu": 0.3, "density": 1e3},
    ...     "boundary": [{"region": "z_min", "fix": ["x", "y", "z"]}],
    ...     "load": [{"type": "gravity", "value": [0, 0, -9.81]}],
    ...     "probe": [{"name": "top", "point": [0.5, 0.5, 1.0]}]})
    >>> r = run(block, t_end=0.05, dt=0.01, probes={"middle": [0.5, 0.5, 0.5]})
    >>> r.steps, sorted(r.probes), bool(r.probes_at([0.025])["top"][0, 2] < 0)
    (5, ['middle', 'top'], True)
    """
    opts = DynamicsOptions.of(scene)
    t_end = opts.t_end if t_end is None else float(t_end)
    if dt is None:
        given = "dt" in (scene.raw.get("dynamics") or {})
        dt = float(opts.dt) if given and opts.dt is not None else t_end / STEPS
    if not (t_end > 0 and 0 < dt <= t_end):
        raise InputError(f"need 0 < dt <= t_end, got dt = {dt!r}, t_end = {t_end!r}")
    scheme = Integrator.of(
        integrator or opts.integrator, opts.rho_inf if rho_inf is None else rho_inf
    )
    fem = FemOptions.of(scene)
    if formulation is not None and formulation not in FemOptions.choices("formulation"):
        raise InputError(
            f"formulation must be one of {', '.join(FemOptions.choices('formulation'))}, "
            f"got {formulation!r}"
        )
    fem = replace(fem, order=order, formulation=formulation or fem.formulation)  # type: ignore[arg-type]
    scene = scene.with_options(fem=fem)
    problem = make_problem(scene, order, law)
    check_memory(problem)  # refused before it starts when its solves cannot fit
    return _Run(problem, scheme, opts, probes).integrate(
        t_end, dt, opts.initial if initial is None else initial,
        opts.frames if frames is None else frames, tol, max_iter,
    )  # fmt: skip


class _Run:
    """The state and operators of one run (see :func:`run`)."""

    def __init__(self, problem: FemProblem, scheme: Integrator, opts, probes):
        self.problem, self.scheme, self.opts = problem, scheme, opts
        ls = problem.linear_solver
        if ls.method == "auto" and ls.direct.backend == "pardiso":  # factors serve many solves
            ls.direct_max_dofs = max(ls.direct_max_dofs or 0, DIRECT_MAX_DOFS)
        self.nu = problem.space.n_dofs
        self.n = problem.n_dofs
        self.M = mass_matrix(problem).tocsr()
        self.loads = TimeLoads(problem)
        self.free = np.asarray(problem.free)
        self.free_u = self.free[: self.nu]
        d = opts.damping
        self.C = None
        K0 = sp.csr_matrix(problem.internal_force(np.zeros(self.n), tangent=True)[1])
        if not d.none:  # K_0: the displacement block of the tangent at rest
            self.C = (d.mass * self.M + d.stiffness * K0[: self.nu, : self.nu]).tocsr()
        self.probe_names, self.P = self._probes(probes)
        # the residual that round-off leaves: a few machine epsilons per DOF (root of their
        # count) of the largest stiffness and mass entries times the displacements
        self.k_max = float(abs(K0.diagonal()).max())
        self.m_max = float(self.M.diagonal().max())
        self.round_off = 100.0 * np.finfo(float).eps * math.sqrt(self.n)
        # a nonlinear law's stress near rest is a difference of O(modulus) terms
        # (neo-Hookean: mu (F - F^-T)): its nodal forces carry noise ~ eps k_max length
        mesh = problem.scene.mesh
        edge = float(np.linalg.norm(np.ptp(mesh.points, axis=0))) / max(mesh.n_tets, 1) ** (1 / 3)
        self.stress_noise = self.k_max * edge if problem.nonlinear else 0.0
        self.symmetric = not problem.mixed and not any(e.has_follower for e, _ in self.loads.parts)
        self.factorizations = 0
        self.splits = 0

    def _probes(self, extra):
        scene, space = self.problem.scene, self.problem.space
        names = [p.name for p in scene.probes]
        tets = [p.tet for p in scene.probes]
        pts = [p.point for p in scene.probes]
        for name, point in (extra or {}).items():
            pt = np.asarray(point, dtype=float).reshape(3)
            tet, _ = locate_points(scene.mesh.points, scene.mesh.tets, pt[None])
            if tet[0] < 0:
                raise InputError(f"probe {name!r} at {pt.tolist()} is outside the mesh")
            names.append(str(name))
            tets.append(int(tet[0]))
            pts.append(pt)
        if not names:
            return [], sp.csr_matrix((0, space.n_nodes))
        return names, space.interpolation_matrix(np.array(tets), np.array(pts))

    # -- pieces of a step -------------------------------------------------------------------
    def _damping_force(self, v: np.ndarray) -> np.ndarray:
        return np.zeros(self.nu) if self.C is None else self.C @ v

    def _acceleration(self, x: np.ndarray, v: np.ndarray, t: float) -> np.ndarray:
        """``M a = f_ext(t+) - f_int(x) - C v`` on the free displacement DOFs."""
        fi = self.problem.internal_force(x)[0][: self.nu]
        r = self.loads.vector(self._U(x), t) - fi - self._damping_force(v)
        f = self.free_u
        Mff = self.M[f][:, f]
        a = np.zeros(self.nu)
        if not f.any():
            return a
        diag = Mff.diagonal()
        sol, info = cg(Mff, r[f], rtol=1e-14, atol=0.0, maxiter=2000,
                       M=sp.diags(1.0 / diag))  # fmt: skip
        if info != 0:
            raise SolverError(f"t = {t:.6g}: the mass solve for the acceleration failed")
        a[f] = sol
        return a

    def _U(self, x: np.ndarray) -> np.ndarray:
        return np.asarray(x[: self.nu]).reshape(-1, 3)

    def _initial(self, initial) -> np.ndarray:
        x = np.zeros(self.n)
        x[self.problem.fixed_dofs] = self.problem.fixed_values
        if isinstance(initial, str):
            if initial == "rest":
                return x
            if initial != "static":
                raise InputError(f"initial must be rest, static or a DOF vector, got {initial!r}")
            scene = self.problem.scene
            held = [
                replace(ld, value=ld.value * g, time=None)
                for ld, g in zip(scene.loads, self.loads.factors(0.0, left=True), strict=True)
            ]
            sol = solve(replace(scene, loads=held, options=dict(scene.options)),
                        self.problem.order)  # fmt: skip
            return np.asarray(sol.u, dtype=float).copy()
        u0 = np.asarray(initial, dtype=float).ravel()
        if u0.size not in (self.nu, self.n):
            raise InputError(f"initial DOF vector has {u0.size} entries, expected {self.nu}")
        x[: u0.size] = u0
        x[self.problem.fixed_dofs] = self.problem.fixed_values
        return x

    def integrate(self, t_end, dt, initial, n_frames, tol, max_iter) -> DynamicResult:
        t_wall = time.perf_counter()
        p, s = self.problem, self.scheme
        grid = time_grid(t_end, dt, self.loads.breakpoints())
        jumps = set(self.loads.jumps())
        x = self._initial(initial)
        v = np.zeros(self.nu)
        a = self._acceleration(x, v, 0.0)
        if np.ndim(n_frames) == 0:
            wanted = np.linspace(0.0, t_end, max(int(n_frames), 1))
        else:
            wanted = np.asarray(n_frames, dtype=float)
        frame_at = set(np.searchsorted(grid, wanted - 1e-9 * dt).tolist())
        rec = Recorder(self, len(grid))
        rec.record(0, x, v, grid[0])
        fe = self.loads.vector(self._U(x), 0.0)
        g_n = p.internal_force(x)[0][: self.nu] - fe
        iters = np.zeros(len(grid) - 1, dtype=int)
        frame_times, frames = [], []
        if 0 in frame_at:
            frame_times.append(0.0)
            frames.append(p.state(x))
        step_time = 0.0
        for k in range(1, len(grid)):
            t0, t1 = grid[k - 1], grid[k]
            tick = time.perf_counter()
            x_new, v_new, a_new, fi_u, fe_left, iters[k - 1], work, lost = self._advance(
                x, v, a, g_n, fe, t0, t1, tol, max_iter, rec
            )
            step_time += time.perf_counter() - tick
            rec.work(k, work, lost)
            x, v, a = x_new, v_new, a_new
            fe = fe_left
            if any(abs(t1 - j) <= 1e-9 * dt for j in jumps):  # the load jumped: a afresh
                fe = self.loads.vector(self._U(x), t1)
                a = self._acceleration(x, v, t1)
            g_n = fi_u - fe
            rec.record(k, x, v, t1)
            if k in frame_at:
                frame_times.append(float(t1))
                frames.append(p.state(x))
        info = {
            "element": f"P{p.order}",
            "law": p.law_name,
            "formulation": "mixed" if p.mixed else "displacement",
            "integrator": s.name,
            "damping": {"mass": self.opts.damping.mass, "stiffness": self.opts.damping.stiffness},
            "dofs": int(self.n),
            "tets": int(p.scene.mesh.n_tets),
            "steps": len(grid) - 1,
            "dt": float(dt),
            "t_end": float(t_end),
            "factorizations": self.factorizations,
            "split_steps": self.splits,
            "seconds_per_step": step_time / max(1, len(grid) - 1),
            "wall_time": time.perf_counter() - t_wall,
        }
        return DynamicResult(grid, rec.probe_dict(), rec.energy_dict(), frame_times, frames,
                             iters, info, rec.probe_dict(velocity=True))  # fmt: skip

    def _advance(self, x, v, a, g_n, fe, t0, t1, tol, max_iter, rec, depth=0):
        """A step from ``t0`` to ``t1``; when its Newton fails, two half steps (at most
        :data:`MAX_SPLITS` times over): after a release the mesh modes the step does not
        resolve can stall Newton where a shorter step converges. Returns :meth:`_step`'s
        state, its iterations, and the step's external work and dissipation."""
        try:
            x1, v1, a1, fi_u, fe1, it = self._step(x, v, a, g_n, t1, t1 - t0, tol, max_iter)
        except (SolverError, InvertedElements):
            if depth >= MAX_SPLITS:
                raise
        else:
            work, lost = rec.increments(fe, fe1, x, x1, v, v1, t1 - t0)
            return x1, v1, a1, fi_u, fe1, it, work, lost
        tm = 0.5 * (t0 + t1)
        first = self._advance(x, v, a, g_n, fe, t0, tm, tol, max_iter, rec, depth + 1)
        xm, vm, am, fim, fem, im, wm, lm = first
        x1, v1, a1, fi_u, fe1, it, w1, l1 = self._advance(
            xm, vm, am, fim - fem, fem, tm, t1, tol, max_iter, rec, depth + 1
        )
        self.splits += 1
        return x1, v1, a1, fi_u, fe1, im + it, wm + w1, lm + l1

    def _step(self, x, v, a, g_n, t1, h, tol, max_iter):
        """One step to ``t1``: Newton on ``u_{n+1}`` (module docstring).

        The factorised step matrix is kept while it serves: for a linear law it is exact
        (one per step size); for a nonlinear one it is refreshed when an iteration cuts the
        residual less than fourfold (modified Newton, as the static mixed solve does). An
        increment that raises the residual or inverts an element is halved.
        """
        s = self.scheme
        am, af, beta, gamma = s.alpha_m, s.alpha_f, s.beta, s.gamma
        c = 1.0 - af
        ca = (1.0 - am) / (c * beta * h * h)  # d(inertia)/du over (1 - af)
        cv = gamma / (beta * h)  # dv/du
        u_n = x[: self.nu]

        def evaluate(x1, tangent):
            a1 = (x1[: self.nu] - u_n - h * v) / (beta * h * h) - (0.5 - beta) / beta * a
            v1 = v + h * ((1.0 - gamma) * a + gamma * a1)
            inertia = self.M @ ((1.0 - am) * a1 + am * a)
            damp = self._damping_force((1.0 - af) * v1 + af * v)
            fi, K = self.problem.internal_force(x1, tangent=tangent)
            if tangent:
                fe, Kf = self.loads.vector_and_stiffness(self._U(x1), t1, left=True)
            else:
                fe, Kf = self.loads.vector(self._U(x1), t1, left=True), None
            R = fi.copy()
            R[: self.nu] += (inertia + damp) / c - fe + (af / c) * g_n
            R[~self.free] = 0.0
            scale = max(float(np.linalg.norm(fi[: self.nu])), float(np.linalg.norm(fe)),
                        float(np.linalg.norm(inertia)), 1e-300)  # fmt: skip
            return R, scale, (a1, v1, fi[: self.nu], fe), (K, Kf)

        # predictor: constant velocity (an extrapolation by a as well overshoots the stiff
        # modes when omega h >> 1, where an implicit step is meant to be used)
        x1 = x.copy()
        x1[: self.nu] += h * v * self.free_u
        x = x.copy()  # identity marks the fallback start below
        same_h = self._fac_h is not None and abs(self._fac_h - h) <= 1e-9 * h
        # a nonlinear step starts from the last matrix only while it served (few iterations)
        served = not self.problem.nonlinear or self._last_iterations <= REUSE_ITERATIONS
        fac = self._fac if same_h and served else None
        fresh = False  # fac is the tangent at an iterate of this step
        dx, prev, halvings, norm, scale = None, math.inf, 0, math.nan, math.nan
        for it in range(max_iter + 1):
            need_K = fac is None
            try:
                R, scale, out, (K, Kf) = evaluate(x1, need_K)
                norm = float(np.linalg.norm(R))
            except InvertedElements:
                if dx is not None:
                    norm = math.inf
                elif x1 is not x:
                    x1 = x  # the predictor inverts an element: start from the last state
                    continue
                else:
                    raise
            umax = float(np.abs(x1[: self.nu]).max()) + float(np.abs(u_n).max())
            floor = self.round_off * (self.stress_noise + umax * (self.k_max + ca * self.m_max)
                                      + h * float(np.abs(v).max()) * ca * self.m_max)  # fmt: skip
            if norm <= max(tol * scale, floor):
                self._last_iterations = it
                return x1, out[1], out[0], out[2], out[3], it
            while dx is not None and not norm < prev and halvings < MAX_HALVINGS:
                dx *= 0.5  # the increment made things worse: go half as far
                x1 = x1 + dx
                halvings += 1
                try:
                    R, scale, out, (K, Kf) = evaluate(x1, not fresh)
                    norm = float(np.linalg.norm(R))
                except InvertedElements:
                    norm = math.inf
                if not fresh:  # a stale matrix misled the step: a fresh one here
                    fac, need_K = None, True
            if not math.isfinite(norm):
                break
            if not need_K and dx is not None and norm > 0.25 * prev:
                R, scale, out, (K, Kf) = evaluate(x1, True)  # slow: a fresh tangent
                fac, need_K = None, True
            if need_K:
                fac = self._factorize(K, Kf, ca, cv, t1)
                self._fac, self._fac_h, fresh = fac, h, True
            prev, halvings = norm, 0
            dx = fac.solve(R)
            x1 = x1 - dx
        raise SolverError(
            f"t = {t1:.6g}: Newton did not converge in {max_iter} iterations "
            f"(residual {norm:.3g} of force {scale:.3g})"
        )

    _fac = None
    _fac_h: float | None = None
    _last_iterations = 0

    def _factorize(self, K, Kf, ca, cv, t1):
        """The step's tangent ``K + ca M + cv C`` (minus the follower stiffness), factorised."""
        D = ca * self.M
        if self.C is not None:
            D = D + cv * self.C
        if Kf is not None:
            D = D - Kf
        if self.problem.mixed:
            D = sp.block_diag([D, sp.csr_matrix((self.n - self.nu, self.n - self.nu))])
        A = (sp.csr_matrix(K) + D).tocsr()
        if not self.problem.mixed:
            A = A.tobsr(blocksize=(3, 3))
        self.factorizations += 1
        return self.problem.linear_solver.factorize(A, self.free, self.symmetric, f"t = {t1:.6g}: ")
