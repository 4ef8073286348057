"""The ``[dynamics]`` scene section: how a dynamic run goes, the same for every model.

A dynamic scene says how long it runs, from which state, and how the tissue is damped;
every model (the implicit reference, :mod:`reference_fem.dynamics_implicit`, and the fast
models) reads the same section, so they solve the same problem. Keys:

- ``t_end`` (s): the simulated time (default 1).
- ``dt`` (s): the reference's time step (default ``t_end / 200``); a fast model picks its
  own (its stable step, its frame budget).
- ``initial``: ``"rest"`` (zero displacement and velocity, the default) or ``"static"``
  (the equilibrium under the loads just before ``t = 0``, at rest).
- ``integrator``: ``"trapezoidal"`` (Newmark, ``beta = 1/4, gamma = 1/2``: no numerical
  dissipation) or ``"generalized-alpha"`` (Chung–Hulbert, with ``rho_inf``).
- ``rho_inf``: generalised-α's spectral radius at infinite frequency, in ``[0, 1]``
  (default 0.8; 1 is the trapezoidal rule, 0 damps the highest frequencies in one step).
- ``frames``: how many full-field frames a run keeps, evenly spaced (default 10).
- ``damping``: Rayleigh damping ``C = a_M M + a_K K_0`` (``K_0`` the stiffness at rest),
  given either as ``{ mass = a_M, stiffness = a_K }`` (1/s and s) or as a damping ratio
  at one or two frequencies, ``{ ratio = zeta, frequencies = [f1, f2] }`` (Hz): the
  ratio is ``zeta`` at both (at ``f1`` with one, split evenly between the two terms).
  Default: undamped.

Examples
--------
>>> o = DynamicsOptions.of_table({"t_end": 0.4, "damping": {"ratio": 0.05,
...                                                        "frequencies": [1.0, 10.0]}})
>>> o.dt, round(o.damping.ratio_at(1.0), 12), round(o.damping.ratio_at(10.0), 12)
(0.002, 0.05, 0.05)
>>> DynamicsOptions.of_table({"damping": {"mass": 1.0, "ratio": 0.1}})
Traceback (most recent call last):
...
springfem.errors.SceneError: <scene>: dynamics.damping.ratio: give mass and stiffness, \
or ratio and frequencies, not both
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from .reader import TableReader, _show

INTEGRATORS = ("trapezoidal", "generalized-alpha")
INITIAL_STATES = ("rest", "static")
#: Frames a run keeps by default.
FRAMES = 10
#: Time steps of a run by default (``dt = t_end / STEPS``).
STEPS = 200


@dataclass(frozen=True)
class RayleighDamping:
    """Rayleigh damping ``C = mass M + stiffness K_0``.

    Attributes
    ----------
    mass
        ``a_M`` (1/s): damps slow motion (the ratio ``a_M / (2 omega)``).
    stiffness
        ``a_K`` (s): damps fast motion (the ratio ``a_K omega / 2``).
    """

    mass: float = 0.0
    stiffness: float = 0.0

    @property
    def none(self) -> bool:
        """Whether there is no damping."""
        return self.mass == 0.0 and self.stiffness == 0.0

    def ratio_at(self, frequency: float) -> float:
        """The damping ratio of a mode of ``frequency`` (Hz).

        Parameters
        ----------
        frequency
            Hz, positive.

        Returns
        -------
        float
            ``a_M / (2 omega) + a_K omega / 2``.
        """
        w = 2.0 * math.pi * frequency
        return self.mass / (2.0 * w) + self.stiffness * w / 2.0

    @classmethod
    def from_ratio(cls, ratio: float, f1: float, f2: float) -> RayleighDamping:
        """The Rayleigh coefficients with damping ratio ``ratio`` at ``f1`` and ``f2`` (Hz).

        Parameters
        ----------
        ratio
            The damping ratio at both frequencies.
        f1, f2
            Hz, positive (equal: the ratio at one frequency, half from each term).

        Returns
        -------
        RayleighDamping
        """
        w1, w2 = 2.0 * math.pi * f1, 2.0 * math.pi * f2
        return cls(2.0 * ratio * w1 * w2 / (w1 + w2), 2.0 * ratio / (w1 + w2))


@dataclass(frozen=True)
class DynamicsOptions:
    """Settings of a scene's ``[dynamics]`` section (module docstring)."""

    t_end: float = 1.0
    dt: float | None = None
    initial: str = "rest"
    integrator: str = "trapezoidal"
    rho_inf: float = 0.8
    frames: int = FRAMES
    damping: RayleighDamping = field(default_factory=RayleighDamping)

    def __post_init__(self):
        if self.dt is None:
            object.__setattr__(self, "dt", self.t_end / STEPS)

    @classmethod
    def of(cls, scene) -> DynamicsOptions:
        """The ``[dynamics]`` options of ``scene`` (defaults when the section is absent)."""
        return scene.section("dynamics", parse_dynamics)

    @classmethod
    def of_table(cls, table: dict, file: str = "<scene>") -> DynamicsOptions:
        """Parse a plain ``[dynamics]`` table (see :func:`parse_dynamics`)."""
        return parse_dynamics(TableReader(table, "dynamics", file))


def parse_dynamics(r: TableReader) -> DynamicsOptions:
    """Validate a scene's ``[dynamics]`` table.

    Parameters
    ----------
    r
        Reader over the table; every error is one line naming the file and the key.

    Returns
    -------
    DynamicsOptions
    """
    t_end = r.get("t_end", "float", default=1.0, positive=True)
    dt = r.get("dt", "float", default=None, positive=True)
    if dt is not None and dt > t_end:
        raise r.fail("dt", f"must not exceed t_end ({t_end:g}), got {dt:g}")
    initial = r.get("initial", "str", default="rest", choices=INITIAL_STATES)
    integrator = r.get("integrator", "str", default="trapezoidal", choices=INTEGRATORS)
    rho_inf = r.get("rho_inf", "float", default=0.8, nonneg=True)
    if rho_inf > 1.0:
        raise r.fail("rho_inf", f"must lie in [0, 1], got {rho_inf:g}")
    frames = r.get("frames", "int", default=FRAMES, positive=True)
    damping = RayleighDamping()
    if r.has("damping"):
        r.used.add("damping")
        damping = parse_damping(TableReader(r.t["damping"], r._key("damping"), r.file))
    r.finish()
    return DynamicsOptions(t_end, dt, initial, integrator, rho_inf, frames, damping)


def parse_damping(r: TableReader) -> RayleighDamping:
    """``damping = { mass, stiffness }`` or ``{ ratio, frequencies }`` (module docstring).

    Parameters
    ----------
    r
        Reader over the ``damping`` table.

    Returns
    -------
    RayleighDamping
    """
    given = {k for k in ("mass", "stiffness", "ratio", "frequencies") if r.has(k)}
    if given & {"mass", "stiffness"} and given & {"ratio", "frequencies"}:
        key = sorted(given & {"ratio", "frequencies"})[-1]
        raise r.fail(key, "give mass and stiffness, or ratio and frequencies, not both")
    if given & {"ratio", "frequencies"}:
        ratio = r.get("ratio", "float", nonneg=True)
        f = r.get("frequencies", "vec", positive=True)
        if len(f) not in (1, 2):
            raise r.fail("frequencies", f"must be [f] or [f1, f2] (Hz), got {_show(f.tolist())}")
        r.finish()
        return RayleighDamping.from_ratio(ratio, float(f[0]), float(f[-1]))
    mass = r.get("mass", "float", default=0.0, nonneg=True)
    stiffness = r.get("stiffness", "float", default=0.0, nonneg=True)
    r.finish()
    return RayleighDamping(mass, stiffness)
