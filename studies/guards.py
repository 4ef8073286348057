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

from springfem.scene import UNIT_SYSTEMS, Material

E_RANGE = (10.0, 1.0e9)  # Pa


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
