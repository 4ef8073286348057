"""Spring-model options: what a scene's ``[spring]`` section switches on.

"Model no more than a scene needs": every part of the spring model is named here and is
computed only when it is on. :func:`springfem.scene.load_scene` validates the TOML section
and builds a :class:`SpringOptions`; code that builds models programmatically constructs
one directly.

Examples
--------
>>> o = SpringOptions()
>>> o.axial, o.torsion, o.volume
('linear', 'cosine', True)
>>> LMSOptions().rule  # the sign-consistent LMS variant by default
'abs'

A scene names a whole element with ``[spring] element`` (:mod:`springmodel.presets`); the
section's other keys override its parts.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any, Literal, get_args

from springfem.errors import SceneError
from springfem.scene import Scene, TableReader, register_section
from springfem.volumetric import VOLUMETRIC_ENERGIES, Volumetric

from .locking_free import LOCKING_FREE, locking_free_switch, volume_stabilisation_default
from .presets import (  # noqa: F401  (the named elements, re-exported for the section's users)
    ANISOTROPIC_LAWS,
    DEFAULT_ELEMENT,
    ELEMENT_KEYS,
    ELEMENTS,
    GREEN_AXIAL_COEFFICIENTS,
    element_for_law,
    element_options,
    named_element,
)

AxialLaw = Literal["linear", "quadratic", "cubic", "stress-scaled"]
TorsionLaw = Literal["off", "angle", "cosine", "cubic", "energy", "shear", "green"]
#: Torsion laws that are energies of the axis cosine, ``U = k phi(c)`` (conservative, with an
#: analytic Hessian; the same small-strain tangent).
ENERGY_TORSION = ("energy", "shear")
#: The torsion law on the Green shear ``gamma_lm = zeta_l . zeta_m / (l_l^0 l_m^0)`` (``2 E_lm``
#: in the frame), ``U = k/2 (gamma - gamma0)^2``: conservative, the small-strain tangent of
#: ``energy``; computed by the tissue element's pass (:mod:`springmodel.tissue_element`).
GREEN_TORSION = "green"
LMSRule = Literal["spec", "abs"]
Calibration = Literal["analytic", "analytic-lsq", "nnls", "exact"]
SolverKind = Literal["static", "linear", "explicit", "implicit"]
Integrator = Literal["symplectic-euler", "verlet"]
VolumeForm = Literal["gradient", "spec"]
Precision = Literal["float64", "mixed", "float32"]
#: ``True``: the specification's barycentric volume springs; ``"axes"``: the axis-volume spring.
VolumeKind = bool | Literal["axes"]
#: ``element``: the axis-volume spring per tet; ``nodal``: on nodal volumes (Bonet & Burton).
VolumeAverage = Literal["element", "nodal"]
#: ``element``: each tet's springs measure its own ``F``; ``nodal``: blended with the
#: nodal-averaged ``F`` of its vertices (:mod:`springmodel.nodal_strain`).
StrainAverage = Literal["element", "nodal"]
#: Default share ``alpha`` of the element's own springs with ``strain_average = "nodal"``
#: (chosen by measurement, docs/volumetric.rst#stabilised-nodal-strain).
STRAIN_STABILISATION = 0.3
#: ``volume_stabilisation`` with nodal strain where ``kappa = 1000 mu`` (measured there,
#: docs/volumetric.rst#stabilised-nodal-strain); elsewhere ``alpha mu / kappa``.
VOLUME_STABILISATION = 3e-4
#: ``off``: the spec's quadratic springs; ``exponential``: :mod:`springmodel.stiffening` (with
#: ``torsion = "green"``: :mod:`springmodel.tissue_element`); ``law``: each spring group
#: stiffens as the tissue law's terms do (:mod:`springmodel.tissue_element`).
Stiffening = Literal["off", "exponential", "law"]


@dataclass(frozen=True)
class LMSOptions:
    """Adaptive volume stiffness (LMS, eq. 2.81), clamped to ``[k_min, k_max]``.

    ``k_min`` and ``k_max`` are multiples of each element's calibrated volume stiffness.
    ``rule = "spec"`` is eq. 2.81 as written (``k += mu dV sum|xi|``, which *lowers* the
    stiffness of a compressed element); ``rule = "abs"`` is the sign-consistent variant
    driven by ``|dV|`` (stiffness grows with any volume error). ``mu`` is dimensionless: the
    update is applied to ``k_s / k_s0`` with ``dV / V0`` and ``sum|xi| / sum|xi0|``.

    Attributes
    ----------
    mu
        Dimensionless learning rate.
    k_min, k_max
        Clamp of ``k_s / k_s0``.
    rule
        ``abs`` or ``spec``.
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
    element
        The named element these options started from (a key of :data:`ELEMENTS`): ``seed``
        for options built in code, the scene's ``[spring] element`` or its law's default
        for a scene. Informative only: neither compared nor in the ``repr``.
    axial
        Axial spring law: ``linear`` (eq. 2.35), ``quadratic``/``cubic`` polynomial (2.36),
        ``stress-scaled`` (2.37–2.38). A scene's ``axial = "green"`` is ``cubic`` with
        :data:`GREEN_AXIAL_COEFFICIENTS` (energy quadratic in the spring's Green strain).
    axial_coefficients
        Dimensionless polynomial coefficients ``(b2, b3)``: the axial force is
        ``-k (d + b2 d^2 / l0 + b3 d^3 / l0^2)`` with ``d = |zeta| - |zeta0|``.
    torsion
        Torsion spring law: ``off``, ``angle`` (2.40–2.41), ``cosine`` (2.44–2.45, the
        spec's default), ``cubic`` (2.47–2.50), ``energy`` (exact gradient of
        ``U = k/2 (c - c0)^2``) or ``shear`` (``U = k/2 (s0^3 (cot theta - cot theta0))^2``,
        the same small-strain tangent as ``energy`` and convex past 45 deg of shear, where
        ``energy`` loses its shear stiffness; :mod:`springmodel.springs.shear`) or ``green``
        (``U = k/2 (gamma - gamma0)^2`` on the Green shear
        ``gamma_lm = zeta_l . zeta_m / (l_l^0 l_m^0)``, which is ``2 E_lm`` in the frame under
        any deformation; with Green axial springs the element measures all six components of
        ``E``, docs/tissue.rst#the-tissue-element-on-the-green-strain; needs volume
        ``"axes"`` or off; with ``strain_average = "nodal"`` the nodal measures carry the
        same pass, docs/tissue.rst#the-tissue-element-with-nodal-strain).
    torsion_cubic
        Dimensionless cubic coefficient of the ``cubic`` torsion law.
    volume
        ``True``: the specification's barycentric volume springs (2.76–2.77); ``False``: off;
        ``"axes"``: the axis-volume spring, energy ``V0 U(J)`` with the exact volume ratio
        ``J = det[zeta_1 zeta_2 zeta_3] / det[zeta_1^0 zeta_2^0 zeta_3^0]``
        (docs/theory.rst#the-axis-volume-ratio-is-j).
    volume_average
        Where the axis-volume energy measures ``J`` (only with ``volume = "axes"``):
        ``element`` (default), ``J`` of each tet; ``nodal``, the average nodal pressure
        tetrahedron of Bonet & Burton (1998): ``J_a = V_a / V_a0`` of the nodal volumes
        ``V_a = sum_{e ni a} V_e / 4``, energy ``sum_a V_a0 U(J_a)`` in place of the per-tet
        term (it does not lock like P1 on nearly incompressible scenes;
        :mod:`springmodel.nodal_volume`). The calibration is unchanged (the same ``kappa``).
    nodal_fraction
        With ``volume_average = "nodal"``: the share ``f`` of each element's ``kappa`` put
        on the nodal volumes; ``1 - f`` stays on the tet (``f < 1`` stiffens the element
        volume modes that nodal volumes leave free, at the price of some locking).
    volume_stabilisation
        With ``volume_average = "nodal"``: ``beta``, each tet keeps ``beta kappa V0 U(J_e)`` of
        its own volume besides the nodal term (nodal volumes leave the element volume modes
        free, and a spring element does not see its own inversion; Puso & Solberg 2006).
        Default (``None``): ``alpha mu / kappa`` with ``strain_average = "nodal"``, else 0
        (:meth:`volume_stabilisation_share`).
    strain_average
        ``element`` (default): each tet's springs measure its own deformation gradient;
        ``nodal``: the share ``1 - strain_stabilisation`` of the springs measures the
        nodal-averaged ``F`` of each vertex (linear tets are too stiff in bending, nodal
        measures too soft; :mod:`springmodel.nodal_strain`). Needs the energy forms. With
        ``volume_average = "nodal"`` it is the locking-free tet of
        docs/volumetric.rst#stabilised-nodal-strain.
    strain_stabilisation
        ``alpha`` in ``[0, 1]``: the share of the springs measuring the element's own
        ``F`` (stabilises the modes nodal measures leave free); default
        :data:`STRAIN_STABILISATION`.
    stiffening
        ``off`` (the spec's springs), ``exponential``: the element's axial, torsion and
        coupling energy ``W_q`` becomes ``V C/2 (exp(2 W_q / (C V)) - 1)``, the shape of the
        Guccione law, with the same small-strain tangent (:mod:`springmodel.stiffening`;
        needs the energy forms: axial linear/quadratic/cubic, torsion energy/shear/green/off),
        or ``law``: each spring group stiffens as the scene's tissue law's terms do, so the
        element's energy is the law's ``W(E)`` of the six measured frame strains
        (``guccione`` or ``holzapfel-ogden``; needs ``axial = "green"``,
        ``torsion = "green"``, ``volume = "axes"``; :mod:`springmodel.tissue_element`).
    stiffening_modulus
        ``C`` (Pa) of the stiffening; default: the ``guccione`` law's ``C``, the
        ``holzapfel-ogden`` law's ``a_f / b_f`` (required for other laws).
    volumetric
        ``U(J)`` of the axis-volume spring: ``quadratic``, ``log`` or ``simo-taylor``
        (:mod:`springfem.volumetric`, the FEM's choices).
    coupling
        Poisson-coupling springs: energy ``c_lm s_l s_m`` for each axis pair, with the axial
        strains ``s_l = |zeta_l| / l_l^0 - 1``.
    volume_form
        ``gradient``: the exact gradient of ``k_s/2 dL^2`` (net force zero); ``spec``: the
        force ``-k_s dL xi_hat_j`` as written in eq. 2.77 (with the restoring sign), whose
        net force is not zero on irregular tets.
    volume_damping
        Damping of the volume springs: barycentric, ``c`` (N s/m) acting on ``v_j - v_b``;
        axis-volume, a volume viscosity ``eta`` (Pa s), force ``-eta V0 (dJ/dt) dJ/dx``.
    axial_damping
        Relative damping along the axial springs (N s/m); off by default.
    lms
        Adaptive volume stiffness, or ``None`` for off.
    calibration
        ``analytic`` (match the small-strain element energy,
        docs/calibration.rst#analytic-calibration), ``analytic-lsq``
        (the same with a least-squares volume constant ``k_s = lam V tr(R)^2 / |R|^4``, equal
        when ``R = rho I``), ``nnls`` (per-element non-negative least squares of the
        effective 6x6 matrix, with positive axial and torsion constants so that every element
        is positive definite) or ``exact`` (closed-form constants that reproduce the
        material's P1 element exactly when ``volume = "axes"``, ``torsion = "energy"`` and,
        for anisotropic materials, ``coupling = true``; see
        :mod:`springmodel.calibration`).
    k_axial, k_torsion, k_volume
        Explicit spring constants (N/m, J, and N/m for the barycentric volume spring or Pa
        for the axis-volume spring) overriding the calibration.
    solver, integrator, dt, dt_safety, t_end, steps, mass_damping, tol, max_iter
        Solver settings: ``solver`` is ``static`` (Newton, finite strain), ``linear`` (the
        small-strain spring model: one tangent solve at rest), ``explicit`` or
        ``implicit``. ``dt = None`` means ``dt_safety * 2 / omega_max``.
        ``mass_damping`` (1/s) is a Rayleigh mass-proportional damping used to bring an
        explicit run to equilibrium.
    precision
        Force kernel precision: ``float64``, ``mixed`` (float32 constants, float64
        arithmetic) or ``float32``.
    """

    axial: AxialLaw = "linear"
    axial_coefficients: tuple[float, float] = (0.0, 0.0)
    torsion: TorsionLaw = "cosine"
    torsion_cubic: float = 0.0
    volume: VolumeKind = True
    volume_average: VolumeAverage = "element"
    nodal_fraction: float = 1.0
    volume_stabilisation: float | None = None
    strain_average: StrainAverage = "element"
    strain_stabilisation: float = STRAIN_STABILISATION
    stiffening: Stiffening = "off"
    stiffening_modulus: float | None = None
    volumetric: Volumetric = "quadratic"
    coupling: bool = False
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
    precision: Precision = "float64"
    element: str = field(default="seed", compare=False, repr=False)

    def __post_init__(self):
        if self.volume not in (True, False, "axes"):
            raise ValueError(f"volume {self.volume!r} is not one of True, False, 'axes'")
        if self.volume_average not in get_args(VolumeAverage):
            raise ValueError(f"volume_average {self.volume_average!r} is not element or nodal")
        if self.volume_average == "nodal" and self.volume != "axes":
            raise ValueError('volume_average = "nodal" needs volume = "axes"')
        if not 0.0 <= self.nodal_fraction <= 1.0:
            raise ValueError(f"nodal_fraction {self.nodal_fraction} is not in [0, 1]")
        if self.volume_stabilisation is not None and not 0.0 <= self.volume_stabilisation <= 1.0:
            raise ValueError(f"volume_stabilisation {self.volume_stabilisation} is not in [0, 1]")
        if self.strain_average not in get_args(StrainAverage):
            raise ValueError(f"strain_average {self.strain_average!r} is not element or nodal")
        if not 0.0 <= self.strain_stabilisation <= 1.0:
            raise ValueError(f"strain_stabilisation {self.strain_stabilisation} is not in [0, 1]")
        if self.strain_average == "nodal" and (
            self.axial == "stress-scaled"
            or self.torsion not in ("off", *ENERGY_TORSION, GREEN_TORSION)
            or self.volume is True or self.lms is not None
            or self.volume_damping or self.axial_damping
        ):  # fmt: skip
            raise ValueError(
                'strain_average = "nodal" needs the energy forms (axial linear, quadratic or '
                'cubic, torsion "energy", "shear", "green" or "off", volume "axes" or off, no '
                f"damping or LMS; got axial {self.axial!r}, torsion {self.torsion!r}, volume "
                f"{self.volume!r})"
            )
        if self.stiffening not in get_args(Stiffening):
            raise ValueError(f"stiffening {self.stiffening!r} is not off, exponential or law")
        if self.stiffening != "off" and (
            self.axial == "stress-scaled"
            or self.torsion not in ("off", *ENERGY_TORSION, GREEN_TORSION)
        ):
            raise ValueError(
                'stiffening = "exponential" needs an energy to exponentiate: axial linear, '
                'quadratic or cubic and torsion "energy", "shear", "green" or "off" (got axial '
                f"{self.axial!r}, torsion {self.torsion!r})"
            )
        if self.torsion == GREEN_TORSION and (
            self.axial == "stress-scaled" or self.volume is True
            or self.axial_damping or self.volume_damping
        ):  # fmt: skip
            raise ValueError(
                'torsion = "green" needs axial linear, quadratic or cubic, volume "axes" or '
                f"off and no damping (got axial {self.axial!r}, volume {self.volume!r})"
            )
        if self.stiffening == "law" and (
            self.torsion != GREEN_TORSION or self.volume != "axes"
            or self.axial != "cubic" or tuple(self.axial_coefficients) != GREEN_AXIAL_COEFFICIENTS
        ):  # fmt: skip
            raise ValueError(
                'stiffening = "law" needs the Green measures: axial = "green", torsion = '
                f'"green" and volume = "axes" (got axial {self.axial!r}, torsion '
                f"{self.torsion!r}, volume {self.volume!r})"
            )
        if self.volumetric not in VOLUMETRIC_ENERGIES:
            raise ValueError(
                f"volumetric {self.volumetric!r} is not one of {', '.join(VOLUMETRIC_ENERGIES)}"
            )

    @property
    def barycentric_volume(self) -> bool:
        """The specification's barycentric volume springs are on (``volume = true``)."""
        return self.volume is True

    @property
    def energy_torsion(self) -> bool:
        """The torsion law is an energy of the axis cosine (:data:`ENERGY_TORSION`)."""
        return self.torsion in ENERGY_TORSION

    @property
    def green_torsion(self) -> bool:
        """The torsion law is on the Green shear (:data:`GREEN_TORSION`): the element's
        deviatoric springs are the tissue element's pass (:mod:`springmodel.tissue_element`)."""
        return self.torsion == GREEN_TORSION

    @property
    def axis_volume(self) -> bool:
        """The axis-volume spring is on (``volume = "axes"``)."""
        return self.volume == "axes"

    def volume_stabilisation_share(self, material=None) -> float:
        """``beta`` in use: ``volume_stabilisation``; else, with ``strain_average = "nodal"``,
        :func:`~springmodel.locking_free.volume_stabilisation_default` for ``material``."""
        if self.volume_stabilisation is not None:
            return float(self.volume_stabilisation)
        if self.strain_average != "nodal":
            return 0.0
        return volume_stabilisation_default(self.strain_stabilisation, material)

    @property
    def nodal_volume(self) -> bool:
        """The axis-volume energy is on nodal volumes (``volume_average = "nodal"``)."""
        return self.volume_average == "nodal"

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
            "precision": Precision,
            "volumetric": Volumetric,
            "volume_average": VolumeAverage,
            "stiffening": Stiffening,
            "strain_average": StrainAverage,
        }
        return get_args(hints[name]) if name in hints else ()

    @classmethod
    def of(cls, scene: Scene) -> SpringOptions:
        """The ``[spring]`` options of ``scene`` (defaults when the section is absent)."""
        return scene.section("spring", parse_spring_options)

    @classmethod
    def keys(cls) -> tuple[str, ...]:
        """Names of the scene keys accepted in ``[spring]``."""
        return tuple(f.name for f in fields(cls))


def parse_spring_options(r: TableReader) -> SpringOptions:
    """Validate a scene's ``[spring]`` table into :class:`SpringOptions`.

    Parameters
    ----------
    r
        Reader over the table; every error names the file and key.

    Returns
    -------
    SpringOptions
        The named element (``element``; by default the law's, :data:`DEFAULT_ELEMENT`)
        with the table's other keys on top.
    """
    name, base = named_element(r)
    named = r.t.get("element")  # "auto" by name takes parts on top; none only without them
    auto = named == DEFAULT_ELEMENT or (named is None and not any(k in r.t for k in ELEMENT_KEYS))
    if locking_free_switch(r, name, auto):
        base.update(LOCKING_FREE)
    kw: dict[str, Any] = {}
    S = SpringOptions
    for key in ("torsion", "calibration", "solver", "integrator", "precision"):
        if r.has(key):
            kw[key] = r.get(key, "str", choices=S.choices(key))
    if r.has("axial"):
        kw["axial"] = r.get("axial", "str", choices=(*S.choices("axial"), "green"))
    if r.has("volume_form"):
        kw["volume_form"] = r.get("volume_form", "str", choices=S.choices("volume_form"))
    if r.has("volume"):
        kw["volume"] = _volume_kind(r)
    if r.has("volume_average"):
        kw["volume_average"] = r.get("volume_average", "str", choices=S.choices("volume_average"))
        if kw["volume_average"] == "nodal" and kw.get("volume", base.get("volume")) != "axes":
            raise r.fail("volume_average", '"nodal" needs volume = "axes"')
    if r.has("nodal_fraction"):
        kw["nodal_fraction"] = f = r.get("nodal_fraction", "float", nonneg=True)
        if f > 1.0:
            raise r.fail("nodal_fraction", f"{f} is larger than 1")
    if r.has("volume_stabilisation"):
        kw["volume_stabilisation"] = b = r.get("volume_stabilisation", "float", nonneg=True)
        if b > 1.0:
            raise r.fail("volume_stabilisation", f"{b} is larger than 1")
        if b and kw.get("volume_average", base.get("volume_average")) != "nodal":
            raise r.fail("volume_stabilisation", 'needs volume_average = "nodal"')
    if r.has("strain_average"):
        kw["strain_average"] = r.get("strain_average", "str", choices=S.choices("strain_average"))
    if r.has("strain_stabilisation"):
        kw["strain_stabilisation"] = a = r.get("strain_stabilisation", "float", nonneg=True)
        if a > 1.0:
            raise r.fail("strain_stabilisation", f"{a} is larger than 1")
    if r.has("stiffening"):
        kw["stiffening"] = r.get("stiffening", "str", choices=S.choices("stiffening"))
    if r.has("stiffening_modulus"):
        kw["stiffening_modulus"] = r.get("stiffening_modulus", "float", positive=True)
    if r.has("volumetric"):
        kw["volumetric"] = r.get("volumetric", "str", choices=VOLUMETRIC_ENERGIES)
    if r.has("coupling"):
        kw["coupling"] = r.get("coupling", "bool")
    for key in ("volume_damping", "axial_damping", "mass_damping", "torsion_cubic"):
        if r.has(key):
            kw[key] = r.get(key, "float", nonneg=key != "torsion_cubic")
    for key in ("k_axial", "k_torsion", "k_volume", "dt", "t_end", "tol"):
        if r.has(key):
            kw[key] = r.get(key, "float", positive=True)
    if r.has("dt_safety"):
        kw["dt_safety"] = r.get("dt_safety", "float", positive=True)
    for key in ("steps", "max_iter"):
        if r.has(key):
            kw[key] = r.get(key, "int", positive=True)
    if r.has("axial_coefficients"):
        if kw.get("axial") == "green":
            raise r.fail("axial_coefficients", 'axial = "green" sets them (1.5, 0.5)')
        kw["axial_coefficients"] = tuple(r.get("axial_coefficients", "vec", length=2))
    if kw.get("axial") == "green":
        kw["axial"], kw["axial_coefficients"] = "cubic", GREEN_AXIAL_COEFFICIENTS
    if r.has("lms"):
        r.used.add("lms")
        lr = TableReader(r.t["lms"], "spring.lms", r.file)
        lk: dict[str, Any] = {}
        if lr.has("mu"):
            lk["mu"] = lr.get("mu", "float", nonneg=True)
        for key in ("k_min", "k_max"):
            if lr.has(key):
                lk[key] = lr.get(key, "float", positive=True)
        if lr.has("rule"):
            lk["rule"] = lr.get("rule", "str", choices=("spec", "abs"))
        lr.finish()
        lms = LMSOptions(**lk)
        if lms.k_min > lms.k_max:
            raise lr.fail("k_min", f"{lms.k_min} is larger than k_max = {lms.k_max}")
        kw["lms"] = lms
    r.finish()
    if "axial" in kw and "axial_coefficients" not in kw:  # the table's own axial law
        base.pop("axial_coefficients", None)
    try:
        return SpringOptions(**{**base, **kw, "element": name})
    except ValueError as exc:  # a combination of keys, e.g. stiffening of the cosine torsion
        key = next((k for k in KEY_ORDER if k in str(exc)), None)
        if key is None:
            raise SceneError(f"{r.file}: spring: {exc}") from None
        raise r.fail(key, str(exc)) from None


#: Keys a combination error names, first match first (the scene error points at it).
KEY_ORDER = ("volume_stabilisation", "strain_average", "stiffening", "volume_average", "torsion")


def _volume_kind(r: TableReader) -> VolumeKind:
    """``volume = true | false | "axes"``."""
    value = r.t["volume"]
    if isinstance(value, bool):
        return r.get("volume", "bool")
    if value == "axes":
        r.used.add("volume")
        return "axes"
    raise r.fail("volume", f'{value!r} is not one of true, false, "axes"')


register_section("spring", parse_spring_options)
