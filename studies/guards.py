"""Guard rails: a warning for implausible input (the solutions' checks are
:mod:`springfem.plausibility`).

The check returns one line (or ``None``); ``springfem solve`` prints it to stderr as
``warning: …`` and goes on. :data:`E_RANGE`: Young's moduli of soft tissue lie far inside
10 Pa – 1 GPa (brain ~1 kPa, liver ~5 kPa, tendon ~1 GPa); a modulus outside is almost
surely a unit slip.

Examples
--------
>>> from springfem.scene import Material
>>> modulus_warning(Material("linear", 0.01, 0.3))
'E = 0.01 Pa is outside 10 Pa – 1e+09 Pa, the range of soft tissue: check the units'
>>> modulus_warning(Material("linear", 5e3, 0.3)) is None
True
>>> modulus_warning(Material("linear", 5.0, 0.3), units="mm-kPa") is None  # 5 kPa
True
"""

from __future__ import annotations

from springfem.scene import LENGTH_UNITS, UNIT_SYSTEMS, Material, Scene

E_RANGE = (10.0, 1.0e9)  # Pa
#: Bodies of soft tissue (a cell sheet to a torso) are 0.1 mm to 10 m across: a size
#: outside is almost surely a length unit slip (a mesh in mm read as metres).
SIZE_RANGE = (1.0e-4, 10.0)  # m


def modulus_warning(material: Material, units: str = "SI") -> str | None:
    """A line when a Young's modulus of ``material`` is outside :data:`E_RANGE`.

    Parameters
    ----------
    material
        The scene's material.
    units
        The scene's unit system (:data:`springfem.scene.UNIT_SYSTEMS`): its stress unit
        scales the moduli to Pa.

    Returns
    -------
    str or None
    """
    lo, hi = E_RANGE
    scale = UNIT_SYSTEMS[units]
    unit = "Pa" if units == "SI" else units.split("-")[1]
    for name in ("E", "E_fiber", "E_cross"):
        E = getattr(material, name, None)
        if E is not None and not lo <= E * scale <= hi:
            shown = f"{E:g} Pa" if scale == 1.0 else f"{E:g} {unit} ({E * scale:g} Pa)"
            return (
                f"{name} = {shown} is outside {lo:g} Pa – {hi:g} Pa, the range of soft "
                "tissue: check the units" + ("" if scale == 1.0 else f" (the scene's: {units})")
            )
    return None


def size_warning(scene: Scene) -> str | None:
    """A line when the body's size (its bounding-box diagonal, in m through the scene's
    ``units``) is outside :data:`SIZE_RANGE`.

    Parameters
    ----------
    scene
        The scene.

    Returns
    -------
    str or None

    Examples
    --------
    >>> from springfem.scene import scene_from_dict
    >>> mesh = {"generator": "box", "size": [40.0, 20.0, 20.0], "divisions": [1, 1, 1]}
    >>> s = scene_from_dict({"mesh": mesh, "material": {"law": "linear", "E": 5e3, "nu": 0.3}})
    >>> size_warning(s)[:50]
    'the body is 49 m across (units = "SI"), outside 0.'
    >>> size_warning(scene_from_dict({**s.raw, "units": "mm-kPa"})) is None  # 49 mm
    True
    """
    lo, hi = scene.mesh.bounding_box()
    size = float(((hi - lo) ** 2).sum() ** 0.5) * LENGTH_UNITS[scene.units]
    low, high = SIZE_RANGE
    if low <= size <= high:
        return None
    return (
        f'the body is {size:.3g} m across (units = "{scene.units}"), outside {low * 1e3:g} mm '
        f"– {high:g} m, the size of soft tissue: check the scene's units or mesh.scale"
    )


def locking_warnings(scene: Scene, models: tuple[str, ...] = ("spring", "fem")) -> list[str]:
    """Lines for the formulations that lock on a nearly incompressible scene.

    A material with Poisson's ratio of at least 0.45, an incompressible flag or a bulk
    modulus above ten shear moduli (:func:`springfem.plausibility.nearly_incompressible`)
    locks linear tets with one volume constraint per element: the FEM's displacement
    formulation and the spring element's per-element volume (docs/volumetric.rst). Each
    line names the option that fixes it.

    Parameters
    ----------
    scene
        The scene.
    models
        Which models' options to check: ``spring`` and/or ``fem``.

    Returns
    -------
    list of str

    Examples
    --------
    >>> from springfem.scene import load_scene
    >>> locking_warnings(load_scene("cantilever"))  # nu = 0.3
    []
    """
    from reference_fem.options import FemOptions
    from springfem.plausibility import nearly_incompressible
    from springmodel.options import SpringOptions

    if not nearly_incompressible(scene):
        return []
    what = _incompressibility(scene)
    out = []
    if "fem" in models and FemOptions.of(scene).formulation == "displacement":
        out.append(
            f"{what}: the FEM's displacement formulation locks on tets; set [fem] "
            'formulation = "nodal-strain" (P1, also free of bending stiffness) or "mixed" '
            "(order 2)"
        )
    if "spring" in models and not SpringOptions.of(scene).nodal_volume:
        out.append(
            f"{what}: the spring element's per-element volume locks like P1; set [spring] "
            'volume = "axes" with volume_average = "nodal" (and strain_average = "nodal", '
            "docs/volumetric.rst#stabilised-nodal-strain)"
        )
    return out


def _incompressibility(scene: Scene) -> str:
    """What makes the scene nearly incompressible, in the scene's own keys: ``nu`` only when
    the scene sets it (a tissue law's or a ``mu``/``kappa`` material's ``nu`` is derived).

    Examples
    --------
    >>> from springfem.scene import scene_from_dict
    >>> box = {"generator": "box", "size": [1.0, 1.0, 1.0], "divisions": [1, 1, 1]}
    >>> nh = {"law": "neo-hookean", "mu": 1.0, "kappa": 50.0}
    >>> _incompressibility(scene_from_dict({"mesh": box, "material": nh}))
    'kappa = 50 (50 mu)'
    >>> lin = {"law": "linear", "E": 1.0, "nu": 0.49}
    >>> _incompressibility(scene_from_dict({"mesh": box, "material": lin}))
    'nu = 0.49'
    """
    given = scene.raw.get("material", {}) if isinstance(scene.raw, dict) else {}
    mat = scene.material
    if "nu" in given:
        return f"nu = {float(given['nu']):g}"
    if getattr(mat, "incompressible", False):
        return "incompressible = true"
    if "kappa" in given:
        kappa = float(given["kappa"])
        mu = float(getattr(mat, "mu", 0.0) or 0.0)
        return f"kappa = {kappa:g}" + (f" ({kappa / mu:.3g} mu)" if mu > 0 else "")
    return "a nearly incompressible law"
