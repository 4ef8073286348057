"""Guard rails: warnings for implausible input and for solutions outside a law's range.

Each check returns one line (or ``None``); ``springfem solve`` prints them to stderr as
``warning: …`` and goes on. The thresholds, documented in the README:

- :data:`E_RANGE`: Young's moduli of soft tissue lie far inside 10 Pa – 1 GPa (brain
  ~1 kPa, liver ~5 kPa, tendon ~1 GPa); a modulus outside is almost surely a unit slip.
- :data:`SMALL_STRAIN`: a linear (small-strain) law is trusted up to 5 % max principal
  Green–Lagrange strain (the limit ``compare`` uses to move to a neo-Hookean reference).
- a displacement larger than the body's size (its bounding-box diagonal) is no small
  deformation, whatever the law.

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

import numpy as np

from springfem.scene import UNIT_SYSTEMS, Material, Scene

E_RANGE = (10.0, 1.0e9)  # Pa
SMALL_STRAIN = 0.05  # max |principal Green-Lagrange strain| of a linear-law solution
LINEAR_LAWS = ("linear", "transverse-linear")


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


def body_size(scene: Scene) -> float:
    """The diagonal of the mesh's bounding box (m)."""
    pts = scene.mesh.points
    return float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0)))


def solution_warnings(scene: Scene, law: str, u: np.ndarray) -> list[str]:
    """Lines for a solution outside its law's range.

    Parameters
    ----------
    scene
        The scene solved.
    law
        The law solved with (a result's ``law``); strains are checked for
        :data:`LINEAR_LAWS` only.
    u
        Nodal displacement ``(n, 3)``.

    Returns
    -------
    list of str
        The large-displacement line (any law) and the small-strain line (linear laws).
    """
    from .compare import max_principal_strain

    out = []
    u = np.asarray(u, float).reshape(-1, 3)
    size = body_size(scene)
    umax = float(np.linalg.norm(u, axis=1).max()) if u.size else 0.0
    if not np.isfinite(umax) or umax > size:
        out.append(
            f"the largest displacement {umax:.3g} m exceeds the body's size {size:.3g} m: "
            "check the load and the modulus"
        )
    if law in LINEAR_LAWS:
        strain = max_principal_strain(scene, u)
        if not strain <= SMALL_STRAIN:
            out.append(
                f"the {law} (small-strain) solution reaches {100 * strain:.3g}% strain "
                f"(> {SMALL_STRAIN:.0%}): use a neo-hookean law (compare does)"
            )
    return out
