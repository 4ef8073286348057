"""Cases of the volume-drift study: the settings, the spring variants, the bundled scenes,
their time scales and the cases of each series (:mod:`.work` runs them).

Every case is a :meth:`~studies.scenes.StudyScene.case` of the scene it runs on with the
series' own keys: ``kind`` (``static``, ``step`` or ``ramp``), ``model`` (a model of
:mod:`studies.models`), ``load`` (static load factor) or ``period``, ``periods``, ``ramp``,
``damping``, ``records`` (explicit runs).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from springfem.scene import Scene
from springmodel.options import LMSOptions

from .. import models
from ..analytic import extent
from ..scenes import StudyScene

STUDY, VERSION = "volume_drift", 2

#: The spring variants: volume springs off and on, LMS as written (eq. 2.81) and the
#: sign-consistent rule, volume springs on the least-squares calibration, the exact element.
VOLUME_OFF = models.spring_variant("spring-volume-off", "volume springs off", volume=False)
VOLUME_ON = models.spring_variant("spring-volume-on", "barycentric volume springs", volume=True)
LMS_SPEC = models.spring_variant(
    "spring-lms-spec", "volume springs + LMS as written (eq. 2.81)", volume=True, lms="spec"
)
LMS_ABS = models.spring_variant(
    "spring-lms-abs", "volume springs + LMS driven by |dV|", volume=True, lms="abs"
)
VOLUME_NNLS = models.spring_variant(
    "spring-volume-nnls", "volume springs, nnls calibration", volume=True, calibration="nnls"
)
#: Every spring variant runs the explicit series; the specification's element variants (all
#: but the exact element) are counted in the headline's diverged runs.
DYNAMIC = tuple(m.name for m in (VOLUME_OFF, VOLUME_ON, LMS_SPEC, LMS_ABS, VOLUME_NNLS))
DYNAMIC += ("spring-exact",)
SPEC_VARIANTS = DYNAMIC[:-1]
#: The static spring variants (no LMS: it acts per time step).
STATIC_SPRINGS = ("spring-volume-off", "spring-volume-on", "spring-volume-nnls", "spring-exact")
#: Clamp of the LMS stiffness ratio (the :class:`LMSOptions` defaults the variants use).
K_MIN, K_MAX = LMSOptions().k_min, LMSOptions().k_max
#: Mass damping of the slow ramps (fraction of ``2 pi / period``).
RAMP_DAMPING = 0.5
COLORS = dict(
    zip(DYNAMIC, ("tab:gray", "tab:blue", "tab:red", "tab:green", "tab:purple", "tab:orange"))
)


@dataclass(frozen=True)
class Settings:
    """Meshes, run lengths and loads of the volume-drift study.

    Parameters
    ----------
    n
        Divisions per side of the bundled cube.
    sag
        Divisions of the bundled sag scene (``None``: no sag).
    periods
        Length of the sudden-load runs in periods of the scene's time scale.
    ramp_periods
        Ramp length of the slow-ramp runs, in periods (then one more at full load).
    records
        Samples recorded per run.
    loads
        Load factors of the static FEM series (the springs solve at full load).
    """

    n: int = 4
    sag: tuple[int, int, int] | None = (12, 6, 3)
    periods: float = 5.0
    ramp_periods: float = 6.0
    records: int = 120
    loads: tuple[float, ...] = (0.25, 0.5, 0.75, 1.0)

    @classmethod
    def full(cls) -> Settings:
        """4³ cube and the sag scene."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """2³ cube, no sag, shorter runs."""
        return cls(n=2, sag=None, periods=4.0, ramp_periods=5.0, records=60, loads=(0.5, 1.0))


@dataclass(frozen=True)
class TimeScale:
    """The time scale of a scene's explicit runs.

    Attributes
    ----------
    period
        Seconds, or a rule: ``p-wave`` (:func:`quarter_wave_period` with the stiffest
        longitudinal modulus) or ``rod`` (with Young's modulus).
    periods
        Length of the sudden-load runs in periods (``None``: :attr:`Settings.periods`).
    damping
        Mass damping of the sudden-load runs, a fraction of ``2 pi / period``.
    """

    period: float | str = "p-wave"
    periods: float | None = None
    damping: float = 0.3


#: Scene-level time scales of the bundled scenes (a user's scene takes the ``p-wave``
#: rule): the cube's quarter-wave rod period of its height, the sag's fixed 0.5 s (the block
#: swings down and back in about that time).
BUNDLED_TIME = {
    "drift-cube": TimeScale("rod"),
    "sag": TimeScale(0.5, periods=2.0, damping=0.4),
}


def bundled_scenes(s: Settings) -> list[StudyScene]:
    """The drift cube compressed and pulled (every series), and the sag (static, step).

    Examples
    --------
    >>> [x.label for x in bundled_scenes(Settings.full())]
    ['cube compressed', 'cube pulled', 'sag']
    """
    cube = StudyScene.bundled(
        "drift-cube",
        {"mesh.divisions": [s.n] * 3},
        label="cube compressed",
        roles=("static", "load", "step", "ramp"),
        analytic="uniaxial-z",
    )
    scenes = [cube, cube.scaled(-1.0).with_sets({}, label="cube pulled")]
    if s.sag:
        sag = {"mesh.divisions": list(s.sag)}
        scenes.append(StudyScene.bundled("sag", sag, label="sag", roles=("static", "step")))
    return scenes


def time_scale(s: StudyScene) -> TimeScale:
    """The scene's time scale: a bundled scene's own, else the ``p-wave`` rule."""
    return TimeScale() if s.user else BUNDLED_TIME.get(str(s.table.get("name")), TimeScale())


def quarter_wave_period(scene: Scene, rule: str = "p-wave") -> float:
    """``4 l / c`` (seconds) of a rod as long as the body's largest extent ``l``; ``rule``
    ``p-wave``: ``c`` from the stiffest longitudinal modulus (diagonal) of the material's
    small-strain matrix, ``rod``: the bar velocity ``sqrt(E / rho)``.
    """
    mat = scene.material
    if rule == "rod":
        return 4.0 * max(extent(scene)) / np.sqrt(mat.E / mat.density)
    from springfem.materials import material_matrix

    c_max = float(np.max(np.diag(material_matrix(mat))[:3]))
    return 4.0 * max(extent(scene)) / np.sqrt(c_max / mat.density)


def fem_models(scene: Scene) -> tuple[str, ...]:
    """The same-mesh P1 FEM: the scene's small-strain (or tissue) law, and neo-Hookean
    where it applies (isotropic materials)."""
    return ("P1",) if models.P1_NH.applies(scene) else ("P1", "P1-NH")


def grids(scenes: list[StudyScene], s: Settings) -> dict[str, list[dict]]:
    """The cases of the three series on the scenes that serve them.

    ``static``: the static spring variants, same-mesh P1 FEM and the scene's own FEM at
    full load (role ``static``), and the P1 FEM at the other load factors (role ``load``).
    ``step``: every spring variant after a suddenly applied load. ``ramp``: every spring
    variant along a slow load ramp.
    """
    out: dict[str, list[dict]] = {"static": [], "step": [], "ramp": []}
    for sc in scenes:
        scene = sc.build()
        fem = fem_models(scene)
        if sc.serves("static"):
            out["static"] += [
                sc.case(STUDY, VERSION, kind="static", model=m, load=1.0)
                for m in (*STATIC_SPRINGS, *fem, "fem")
            ]
        if sc.serves("load"):
            fs = [f for f in s.loads if f != 1.0 or not sc.serves("static")]
            out["static"] += [
                sc.case(STUDY, VERSION, kind="static", model=m, load=f) for f in fs for m in fem
            ]
        ts = time_scale(sc)
        T = quarter_wave_period(scene, ts.period) if isinstance(ts.period, str) else ts.period
        runs = {
            "step": (0.0, ts.periods or s.periods, ts.damping),
            "ramp": (s.ramp_periods, s.ramp_periods + 1.0, RAMP_DAMPING),
        }
        for kind, (ramp, periods, damping) in runs.items():
            run = {"period": T, "ramp": ramp, "periods": periods, "damping": damping}
            if sc.serves(kind):
                out[kind] += [
                    sc.case(STUDY, VERSION, kind=kind, model=m, records=s.records, **run)
                    for m in DYNAMIC
                ]
    return out
