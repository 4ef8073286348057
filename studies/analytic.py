"""Closed-form references: the one optional hook through which a scene brings its own.

A bundled :class:`~studies.scenes.StudyScene` may name a closed-form reference
(``analytic = "timoshenko"``); a study asks :func:`reference` for it and gets the probe,
the displacement component, its value and where the value comes from, or ``None`` (a
user's scene has none: the studies then measure against their FEM reference).

- ``timoshenko``: the tip deflection of a cantilever with a rectangular section clamped at
  ``x = 0`` under an end traction along ``z`` (Euler–Bernoulli bending plus Timoshenko
  shear, :func:`studies.metrics.timoshenko_tip_deflection`), at the probe ``tip``;
- ``uniaxial-fiber``, ``uniaxial-cross``: the stretch ``σ L / E`` of a block in uniaxial
  stress along ``x``, with ``E`` the fibre or cross modulus of a transversely isotropic
  material, at the probe ``corner``;
- ``off-axis``: the same stretch of a transversely isotropic block whose uniform fibre lies
  in the x-y plane at an angle θ from x, with the off-axis modulus ``E(θ)``
  (:func:`off_axis_modulus`; Lekhnitskii 1963, *Theory of elasticity of an anisotropic
  elastic body*);
- ``uniaxial-z``: the stretch ``σ L / E`` along ``z`` of an isotropic block at the probe
  ``corner``.

A reference state may also know the body's relative volume change
(:func:`volume_change`): ``uniaxial-z`` gives the small-strain ``(1 − 2ν) σ / E``.

Examples
--------
>>> from studies.scenes import StudyScene
>>> s = StudyScene.bundled("cantilever", analytic="timoshenko")
>>> probe, component, value, source = reference(s, s.build())
>>> probe, component, round(value, 7), source
('tip', 2, -0.0004031, 'Timoshenko')
>>> reference(StudyScene.bundled("sag"), None) is None
True
>>> cube = StudyScene.bundled("drift-cube", {"mesh.divisions": [1, 1, 1]}, analytic="uniaxial-z")
>>> value, source = volume_change(cube, cube.build())
>>> round(value, 6), source
(-0.002, '(1 − 2ν) σ / E')
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from springfem.errors import InputError
from springfem.scene import Scene

from .metrics import timoshenko_tip_deflection
from .scenes import StudyScene

Reference = tuple[str, int, float, str]


def extent(scene: Scene) -> list[float]:
    """The extents of the scene's bounding box along x, y and z (its length unit)."""
    lo, hi = scene.mesh.bounding_box()
    return [float(x) for x in np.asarray(hi) - np.asarray(lo)]


def _first_load(scene: Scene) -> np.ndarray:
    return np.asarray(scene.raw["load"][0]["value"], float)


def timoshenko(scene: Scene) -> Reference:
    """The cantilever's tip deflection along ``z`` (sign of the traction)."""
    size = extent(scene)
    load = _first_load(scene)
    mat = scene.material
    force = abs(load[2]) * size[1] * size[2]
    w = timoshenko_tip_deflection(force, *size, mat.E, mat.nu)
    return "tip", 2, float(np.sign(load[2]) * w), "Timoshenko"


def uniaxial(modulus: str, label: str) -> Callable[[Scene], Reference]:
    """The uniaxial-stress stretch ``σ L / E`` along ``x`` with ``E`` = ``material.modulus``."""

    def stretch(scene: Scene) -> Reference:
        E = getattr(scene.material, modulus)
        return "corner", 0, float(_first_load(scene)[0] / E * extent(scene)[0]), label

    return stretch


#: The transverse (Poisson) displacement component of the uniaxial references.
LATERAL = {"uniaxial-fiber": 1, "uniaxial-cross": 2}


def off_axis_modulus(material, angle: float) -> float:
    """Young's modulus along x of a transversely isotropic material whose fibre lies in the
    x-y plane at ``angle`` degrees from x (the off-axis formula).

    ``1/E(θ) = cos⁴θ/E_f + sin⁴θ/E_c + (1/G_f − 2ν_fc/E_f) sin²θ cos²θ``.

    Parameters
    ----------
    material
        A ``transverse-linear`` :class:`~springfem.scene.Material`.
    angle
        The fibre angle θ from x, in degrees.

    Returns
    -------
    float

    Examples
    --------
    >>> from springfem.scene import Material
    >>> m = Material("transverse-linear", 1e4, 0.4, E_fiber=3e4, E_cross=1e4, nu_fiber_cross=0.3,
    ...              nu_cross=0.4, G_fiber=5e3)
    >>> round(off_axis_modulus(m, 0.0)), round(off_axis_modulus(m, 90.0))
    (30000, 10000)
    """
    th = np.radians(angle)
    c2, s2 = np.cos(th) ** 2, np.sin(th) ** 2
    inv = (
        c2**2 / material.E_fiber
        + s2**2 / material.E_cross
        + (1.0 / material.G_fiber - 2.0 * material.nu_fiber_cross / material.E_fiber) * s2 * c2
    )
    return float(1.0 / inv)


_VOIGT = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))


def off_axis_strain(material, angle: float, stress: float) -> np.ndarray:
    """Strain tensor of uniaxial stress ``stress`` along x with the fibre at ``angle`` degrees
    in the x-y plane, from the rotated fourth-order compliance (a route independent of
    :func:`off_axis_modulus`).

    Parameters
    ----------
    material
        A ``transverse-linear`` material.
    angle
        The fibre angle from x, in degrees.
    stress
        The uniaxial stress.

    Returns
    -------
    numpy.ndarray
        ``(3, 3)``; ``2 ε_xy / ε_xx`` is the shear coupling of the off-axis stretch.

    Examples
    --------
    >>> from springfem.scene import Material
    >>> m = Material("transverse-linear", 1e4, 0.4, E_fiber=3e4, E_cross=1e4, nu_fiber_cross=0.3,
    ...              nu_cross=0.4, G_fiber=5e3)
    >>> bool(np.isclose(1 / off_axis_strain(m, 30.0, 1.0)[0, 0], off_axis_modulus(m, 30.0)))
    True
    """
    from springfem.materials import transverse_compliance

    S = transverse_compliance(
        material.E_fiber,
        material.E_cross,
        material.nu_fiber_cross,
        material.nu_cross,
        material.G_fiber,
    )
    S4 = np.zeros((3, 3, 3, 3))
    for a, (i, j) in enumerate(_VOIGT):
        for b, (k, l) in enumerate(_VOIGT):
            w = (0.5 if i != j else 1.0) * (0.5 if k != l else 1.0)  # engineering shear
            for p, q in {(i, j), (j, i)}:
                for r, t in {(k, l), (l, k)}:
                    S4[p, q, r, t] = S[a, b] * w
    th = np.radians(angle)
    R = np.array([[np.cos(th), -np.sin(th), 0.0], [np.sin(th), np.cos(th), 0.0], [0, 0, 1.0]])
    Sg = np.einsum("ia,jb,kc,ld,abcd->ijkl", R, R, R, R, S4)  # material axes = columns of R
    sigma = np.zeros((3, 3))
    sigma[0, 0] = stress
    return np.einsum("ijkl,kl->ij", Sg, sigma)


def fibre_angle(scene: Scene) -> float:
    """The angle (degrees, from x) of the scene's uniform fibre in the x-y plane.

    Parameters
    ----------
    scene
        The scene.

    Returns
    -------
    float

    Raises
    ------
    InputError
        If the fibre is not uniform or not in the x-y plane.
    """
    f = scene.frames[:, 0, :]
    if not np.allclose(f, f[0], atol=1e-12) or abs(f[0, 2]) > 1e-12:
        raise InputError(
            f"scene {scene.name}: the off-axis reference needs one fibre direction in the x-y plane"
        )
    return float(np.degrees(np.arctan2(f[0, 1], f[0, 0])))


def off_axis(scene: Scene) -> Reference:
    """The stretch ``σ L / E(θ)`` along x at the probe ``corner`` (:func:`off_axis_modulus`)."""
    E = off_axis_modulus(scene.material, fibre_angle(scene))
    return "corner", 0, float(_first_load(scene)[0] / E * extent(scene)[0]), "off-axis formula"


def uniaxial_z(scene: Scene) -> Reference:
    """The stretch ``σ L / E`` along ``z`` of an isotropic block at the probe ``corner``."""
    E = scene.material.E
    return "corner", 2, float(_first_load(scene)[2] / E * extent(scene)[2]), "σ/E · L"


#: Closed-form references by name.
REFERENCES: dict[str, Callable[[Scene], Reference]] = {
    "timoshenko": timoshenko,
    "uniaxial-fiber": uniaxial("E_fiber", "σ/E_fiber · L"),
    "uniaxial-cross": uniaxial("E_cross", "σ/E_cross · L"),
    "off-axis": off_axis,
    "uniaxial-z": uniaxial_z,
}


def _uniaxial_z_volume(scene: Scene) -> tuple[float, str]:
    mat = scene.material
    return (1.0 - 2.0 * mat.nu) * float(_first_load(scene)[2]) / mat.E, "(1 − 2ν) σ / E"


#: Closed-form relative volume changes of the reference states that have one.
VOLUME_CHANGES: dict[str, Callable[[Scene], tuple[float, str]]] = {
    "uniaxial-z": _uniaxial_z_volume,
}


def reference_for(name: str, scene: Scene) -> Reference:
    """The closed-form reference ``name`` of ``scene``.

    Parameters
    ----------
    name
        A key of :data:`REFERENCES`.
    scene
        The scene.

    Returns
    -------
    tuple
        ``(probe, component, value, source)``.
    """
    if name not in REFERENCES:
        raise InputError(f"no closed-form reference {name!r}; known: {', '.join(REFERENCES)}")
    return REFERENCES[name](scene)


def reference(study_scene: StudyScene, scene: Scene | None) -> Reference | None:
    """The scene's closed-form reference, if it has one.

    Parameters
    ----------
    study_scene
        The study's scene (its ``analytic`` names the reference).
    scene
        Its built scene (``None`` is fine when there is no reference).

    Returns
    -------
    tuple or None
        ``(probe, component, value, source)``.
    """
    if study_scene.analytic is None:
        return None
    return reference_for(study_scene.analytic, scene if scene is not None else study_scene.build())


def volume_change(study_scene: StudyScene, scene: Scene | None) -> tuple[float, str] | None:
    """The small-strain relative volume change of the scene's reference state, if known.

    Parameters
    ----------
    study_scene
        The study's scene (its ``analytic`` names the reference state).
    scene
        Its built scene (``None``: built here when needed).

    Returns
    -------
    tuple or None
        ``(ΔV / V0, source)``.
    """
    if study_scene.analytic not in VOLUME_CHANGES:
        return None
    return VOLUME_CHANGES[study_scene.analytic](scene if scene is not None else study_scene.build())
