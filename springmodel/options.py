"""Spring-model options: what a scene's ``[spring]`` section switches on.

"Model no more than a scene needs": every part of the spring model is named here and is
computed only when it is on. :func:`springmodel.scene.load_scene` validates the TOML section
and builds a :class:`SpringOptions`; code that builds models programmatically constructs
one directly.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Literal, get_args

AxialLaw = Literal["linear", "quadratic", "cubic", "stress-scaled"]
TorsionLaw = Literal["off", "angle", "cosine", "cubic", "energy"]
LMSRule = Literal["spec", "abs"]
Calibration = Literal["analytic", "analytic-lsq", "nnls"]
SolverKind = Literal["static", "explicit", "implicit"]
Integrator = Literal["symplectic-euler", "verlet"]
VolumeForm = Literal["gradient", "spec"]
LinearSolver = Literal["auto", "direct", "amg"]


@dataclass(frozen=True)
class LMSOptions:
    """Adaptive volume stiffness (LMS, eq. 2.81), clamped to ``[k_min, k_max]``.

    ``k_min`` and ``k_max`` are multiples of each element's calibrated volume stiffness.
    ``rule = "spec"`` is eq. 2.81 as written (``k += mu dV sum|xi|``, which *lowers* the
    stiffness of a compressed element); ``rule = "abs"`` is the sign-consistent variant
    driven by ``|dV|`` (stiffness grows with any volume error). ``mu`` is dimensionless: the
    update is applied to ``k_s / k_s0`` with ``dV / V0`` and ``sum|xi| / sum|xi0|``.
    """

    mu: float = 1.0
    k_min: float = 0.1
    k_max: float = 10.0
    rule: LMSRule = "abs"


@dataclass(frozen=True)
class SpringOptions:
    """Which spring-model parts are on, their laws, calibration and solver settings.

    Attributes
    ----------
    axial
        Axial spring law: ``linear`` (eq. 2.35), ``quadratic``/``cubic`` polynomial (2.36),
        ``stress-scaled`` (2.37–2.38).
    axial_coefficients
        Dimensionless polynomial coefficients ``(b2, b3)``: the axial force is
        ``-k (d + b2 d^2 / l0 + b3 d^3 / l0^2)`` with ``d = |zeta| - |zeta0|``.
    torsion
        Torsion spring law: ``off``, ``angle`` (2.40–2.41), ``cosine`` (2.44–2.45, the
        spec's default), ``cubic`` (2.47–2.50) or ``energy`` (exact gradient of
        ``U = k/2 (c - c0)^2``).
    torsion_cubic
        Dimensionless cubic coefficient of the ``cubic`` torsion law.
    volume
        Barycentric volume springs on/off (2.76–2.77).
    volume_form
        ``gradient``: the exact gradient of ``k_s/2 dL^2`` (net force zero); ``spec``: the
        force ``-k_s dL xi_hat_j`` as written in eq. 2.77 (with the restoring sign), whose
        net force is not zero on irregular tets.
    volume_damping
        Damping coefficient ``c`` of the volume springs (N s/m), acting on ``v_j - v_b``.
    axial_damping
        Relative damping along the axial springs (N s/m); off by default.
    lms
        Adaptive volume stiffness, or ``None`` for off.
    calibration
        ``analytic`` (match the small-strain element energy, DESIGN §4), ``analytic-lsq``
        (the same with a least-squares volume constant ``k_s = lam V tr(R)^2 / |R|^4``, equal
        when ``R = rho I``) or ``nnls`` (per-element non-negative least squares of the
        effective 6x6 matrix).
    k_axial, k_torsion, k_volume
        Explicit spring constants (N/m, N m, N/m) overriding the calibration.
    solver, integrator, dt, dt_safety, t_end, steps, mass_damping, tol, max_iter
        Solver settings. ``dt = None`` means ``dt_safety * 2 / omega_max``.
        ``mass_damping`` (1/s) is a Rayleigh mass-proportional damping used to bring an
        explicit run to equilibrium.
    """

    axial: AxialLaw = "linear"
    axial_coefficients: tuple[float, float] = (0.0, 0.0)
    torsion: TorsionLaw = "cosine"
    torsion_cubic: float = 0.0
    volume: bool = True
    volume_form: VolumeForm = "gradient"
    volume_damping: float = 0.0
    axial_damping: float = 0.0
    lms: LMSOptions | None = None
    calibration: Calibration = "analytic"
    k_axial: float | None = None
    k_torsion: float | None = None
    k_volume: float | None = None
    solver: SolverKind = "static"
    integrator: Integrator = "symplectic-euler"
    dt: float | None = None
    dt_safety: float = 0.5
    t_end: float | None = None
    steps: int | None = None
    mass_damping: float = 0.0
    tol: float = 1e-8
    max_iter: int = 200

    @classmethod
    def choices(cls, name: str) -> tuple[str, ...]:
        """Valid string values of the option ``name`` (empty for non-string options)."""
        hints = {
            "axial": AxialLaw,
            "torsion": TorsionLaw,
            "calibration": Calibration,
            "solver": SolverKind,
            "integrator": Integrator,
            "volume_form": VolumeForm,
        }
        return get_args(hints[name]) if name in hints else ()

    @classmethod
    def keys(cls) -> tuple[str, ...]:
        """Names of the scene keys accepted in ``[spring]``."""
        return tuple(f.name for f in fields(cls))


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
    """

    order: int = 1
    linear_solver: LinearSolver = "auto"
    tol: float = 1e-10
    max_iter: int = 25
    load_steps: int = 1

    @classmethod
    def choices(cls, name: str) -> tuple[str, ...]:
        return get_args(LinearSolver) if name == "linear_solver" else ()
