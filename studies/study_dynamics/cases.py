"""Cases of the dynamics study: the settings, the models, the bundled beam and the cases of
each scene (:mod:`.work` runs them).

Every case is a :meth:`~studies.scenes.StudyScene.case` of its scene with the study's own
keys: ``kind`` (``period``: the reference's static solve and Rayleigh period; ``release``:
one model released from its static state; ``cost``: every model's step cost, interleaved in
one process), ``model`` / ``models``, ``t_end``, ``samples``, ``safety``, ``rounds``,
``steps``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from springfem.errors import InputError
from springfem.scene import Scene

from .. import models
from ..scenes import StudyScene

STUDY, VERSION = "dynamics", 2

#: The spring elements compared with explicit P1 of the same law: the tissue element (the
#: law's own energy per element), the stiffened exact element (one exponent per element)
#: and the exact small-strain element (linear springs, P1's small-strain tangent).
SPRINGS = ("spring-tissue", "spring-stiffened", "spring-exact")
#: Line colours of the models (the reference is black).
COLORS = {"spring-tissue": "tab:orange", "spring-stiffened": "tab:blue",
          "spring-exact": "tab:green", "spring-spec": "tab:purple",
          "corotational": "goldenrod", "xpbd": "tab:red", "mass-spring": "tab:brown"}  # fmt: skip
#: The isotropic beam: neo-Hookean, ``E`` = Guccione's small-strain fibre modulus ``C b_f``.
NH_NU = 0.45
#: Land's beam, made compressible: ``kappa`` = this × ``C`` (as the explicit kernels' test).
KAPPA_PER_C = 50.0
#: Density of the bundled beam: 1000 kg/m³ in the scene's mm-kPa units (kg/mm³; forces in
#: mN = kg mm/s², so time is in seconds).
BEAM_DENSITY = 1.0e-6
#: Land's load (0.004 kPa on the bottom face), here a dead traction.
BEAM_TRACTION = 0.004


@dataclass(frozen=True)
class Settings:
    """Mesh, load, run length and timing of the dynamics study.

    Parameters
    ----------
    beam
        Divisions of the bundled beam.
    load
        Factor on Land's 0.004 kPa.
    periods
        Run length after the release, in Rayleigh periods of the reference's static
        deflection (:func:`studies.study_dynamics.work.rayleigh_period`).
    samples
        Points of the common time grid the probe is compared on.
    safety
        Time step of every model: this × its own critical step (the smaller at rest and at
        the loaded state).
    models
        The spring models compared with explicit P1.
    rounds, steps
        Cost per step: ``rounds`` interleaved rounds of ``steps`` steps per model.
    """

    beam: tuple[int, int, int] = (30, 3, 3)
    load: float = 1.0
    periods: float = 1.5
    samples: int = 400
    safety: float = 0.5
    models: tuple[str, ...] = SPRINGS
    rounds: int = 5
    steps: int = 200

    @classmethod
    def full(cls) -> Settings:
        """Land's 30×3×3 beam (1,620 tets), 1.5 periods."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """A 10×2×2 beam, one period, fewer timed steps."""
        return cls(beam=(10, 2, 2), periods=1.0, samples=200, rounds=3, steps=100)


def beam_table(divisions: tuple[int, int, int], load: float = 1.0) -> StudyScene:
    """Land's beam made compressible for explicit dynamics: ``kappa = 50 C``, density
    1000 kg/m³, P1 in the displacement formulation, the 0.004 kPa pressure as a dead
    traction (× ``load``) on the bottom face.

    Examples
    --------
    >>> sc = beam_table((10, 1, 1))
    >>> m = sc.build().material
    >>> m.incompressible, m.parameters["kappa"], m.density
    (False, 100.0, 1e-06)
    >>> sc.table["load"][0]["value"]
    [0.0, 0.0, 0.004]
    """
    C = float(StudyScene.bundled("land-beam").table["material"]["C"])
    sets = {
        "material.incompressible": False,
        "material.kappa": KAPPA_PER_C * C,
        "material.density": BEAM_DENSITY,
        "mesh.divisions": list(divisions),
        "fem.order": 1,
        "fem.formulation": "displacement",
    }
    sc = StudyScene.bundled("land-beam", sets, label="land-beam")
    table = dict(sc.table)
    value = [0.0, 0.0, BEAM_TRACTION * load]
    table["load"] = [{"type": "traction", "region": "z_min", "value": value}]
    return StudyScene(sc.label, table, roles=("release",))


def isotropic_beam(divisions: tuple[int, int, int], load: float = 1.0) -> StudyScene:
    """Land's beam of :func:`beam_table`, isotropic: compressible neo-Hookean with ``E`` the
    Guccione law's small-strain fibre modulus ``C b_f`` and ``nu`` = :data:`NH_NU`, so that
    the models of isotropic laws (co-rotational P1, XPBD, the mass-spring network) apply.

    Examples
    --------
    >>> m = isotropic_beam((4, 1, 1)).build().material
    >>> m.law, round(m.E, 6), m.nu
    ('neo-hookean', 16.0, 0.45)
    """
    sc = beam_table(divisions, load)
    g = sc.table["material"]
    table = dict(sc.table)
    table["material"] = {"law": "neo-hookean", "E": float(g["C"]) * float(g["b_f"]),
                         "nu": NH_NU, "density": g["density"]}  # fmt: skip
    table.pop("axes", None)
    return StudyScene("land-beam-nh", table, roles=("release",))


def bundled_scenes(s: Settings) -> list[StudyScene]:
    """The compressible Guccione beam (Land's problem 1 made compressible) and its isotropic
    neo-Hookean twin (:func:`isotropic_beam`).

    Examples
    --------
    >>> [x.label for x in bundled_scenes(Settings.quick())]
    ['land-beam', 'land-beam-nh']
    """
    return [beam_table(s.beam, s.load), isotropic_beam(s.beam, s.load)]


def reference_model(scene: Scene) -> str:
    """The explicit P1 of the scene's law: ``P1`` (its own law, or small-strain linear),
    ``P1-NH`` for a neo-Hookean material.

    Examples
    --------
    >>> reference_model(beam_table((4, 1, 1)).build())
    'P1'
    """
    return "P1-NH" if scene.material.law == "neo-hookean" else "P1"


def check_scene(sc: StudyScene) -> Scene:
    """The built scene, or a one-line refusal: an incompressible material (explicit P1 has
    no pressure unknown), no load to release from."""
    scene = sc.build()
    if scene.material.incompressible:
        raise InputError(
            f"study dynamics: scene {sc.label} is incompressible; explicit P1 needs a "
            "volumetric penalty: give [material] kappa instead of incompressible = true"
        )
    if not scene.loads:
        raise InputError(f"study dynamics: scene {sc.label} has no [[load]] to release from")
    return scene


def spring_models(scene: Scene, s: Settings) -> list[str]:
    """The settings' spring models that apply to the scene (the tissue element needs a tissue
    law, the stiffened one a modulus to stiffen by), then the plug-in models with an
    explicit form on it (:func:`studies.models.plugins`:
    ``corotational`` on a linear or neo-Hookean scene)."""
    own = [m for m in s.models if models.get(m).applies(scene) is None and _builds(m, scene)]
    return own + [m for m in models.plugins(scene, explicit=True) if m not in own]


def _builds(model: str, scene: Scene) -> bool:
    """Whether the model's mechanical system builds on the scene (the stiffened element
    needs a stiffening modulus a neo-Hookean law does not give)."""
    try:
        models.get(model).system(scene)
    except InputError:
        return False
    return True


def own_integrator(name: str) -> Any:
    """The plug-in of model ``name`` when it brings its own time integration (a
    ``release_run``, :class:`~springfem.model_api.ModelPlugin`), else ``None``."""
    model = models.get(name)
    plugin = getattr(model, "plugin", None) or model
    return plugin if hasattr(plugin, "release_run") else None


def own_dynamics(scene: Scene) -> list[str]:
    """The plug-in models weighed by default that apply to the scene and bring their own
    time integration (:func:`own_integrator`)."""
    return [m for m in models.plugins(scene) if own_integrator(m) is not None]


def not_applicable(scene: Scene) -> list[str]:
    """The plug-in models weighed by default that do not apply to the scene (a row each in
    the table, with the model's reason)."""
    return [m for m in models.plugins() if models.get(m).applies(scene) is not None]


def period_case(sc: StudyScene) -> dict[str, Any]:
    """The reference's static solve (for the run length)."""
    scene = check_scene(sc)
    return sc.case(STUDY, VERSION, kind="period", model=reference_model(scene))


def release_cases(sc: StudyScene, s: Settings, t_end: float) -> list[dict[str, Any]]:
    """The reference, every spring model and XPBD, released from its static state for
    ``t_end`` seconds, and a case for each plug-in model that does not apply (its row says
    why)."""
    scene = sc.build()
    names = [reference_model(scene), *spring_models(scene, s), *own_dynamics(scene),
             *not_applicable(scene)]  # fmt: skip
    run = {"t_end": t_end, "samples": s.samples, "safety": s.safety}
    return [sc.case(STUDY, VERSION, kind="release", model=m, **run) for m in names]


def cost_case(sc: StudyScene, s: Settings) -> dict[str, Any]:
    """Every model's cost per step (XPBD: per substep), interleaved in one process."""
    scene = sc.build()
    names = [reference_model(scene), *spring_models(scene, s), *own_dynamics(scene)]
    return sc.case(STUDY, VERSION, kind="cost", models=names, rounds=s.rounds, steps=s.steps,
                   safety=s.safety)  # fmt: skip


def resampled(U: np.ndarray, step: float, t_end: float, samples: int) -> tuple[list, list]:
    """A probe trajectory on ``samples + 1`` even times up to ``t_end``: its rows ``U[k]``
    are at ``k * step`` (NaN after a blow-up: NaN there too).

    Parameters
    ----------
    U
        ``(steps + 1, 3)`` probe displacements.
    step
        Time between rows.
    t_end, samples
        The sampled span and its intervals.

    Returns
    -------
    t, u
        Lists of the sample times and ``[x, y, z]`` per time.

    Examples
    --------
    >>> U = np.array([[0.0, 0, 0], [1, 2, 3], [np.nan, np.nan, np.nan]])
    >>> t, u = resampled(U, 1.0, 2.0, 2)
    >>> t, u[1], bool(np.isnan(u[2][0]))
    ([0.0, 1.0, 2.0], [1.0, 2.0, 3.0], True)
    """
    t = np.linspace(0.0, t_end, int(samples) + 1)
    tk = step * np.arange(U.shape[0])
    ok = np.isfinite(U[:, 0])
    u = np.column_stack([np.interp(t, tk[ok], U[ok, i], right=np.nan) for i in range(3)])
    return t.tolist(), u.tolist()
