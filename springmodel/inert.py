"""``[spring]`` keys that cannot change a scene's result, stated once instead of ignored.

A key can be valid and still do nothing: a cubic torsion coefficient without the cubic
torsion law, time-step settings of a static solve, or a calibration that gives the element
the same constants as its element's own (``calibration = "exact"`` equals ``"analytic"``
for the specification's parts on an isotropic law, and every analytic calibration is the
exact one on the axis-volume and coupling parts, :func:`springmodel.calibration.calibrate`).
:func:`inert_keys` names each such key of the scene's table in one line, so that a user
does not spend a sweep on duplicates without a word (the sweeps also solve cases that
resolve to the same computation once, :mod:`studies.sweep_resolve`).

Examples
--------
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({
...     "mesh": {"generator": "box", "size": [0.1, 0.01, 0.01], "divisions": [4, 1, 1]},
...     "material": {"law": "linear", "E": 1.0e4, "nu": 0.3},
...     "spring": {"torsion_cubic": 2.0, "dt_safety": 0.3}})
>>> for line in inert_keys(scene):
...     print(line)
spring.torsion_cubic: no effect with torsion = "cosine" (only the "cubic" torsion law reads it)
spring.dt_safety: no effect on a static solve (it sets the time step of a timed run)
"""

from __future__ import annotations

from typing import Any

import numpy as np

from springfem.scene import TableReader

from .options import SpringOptions, parse_spring_options

#: Keys that only a timed run (``solver = "explicit"`` or ``"implicit"``) reads.
TIMED_KEYS = ("integrator", "dt", "dt_safety", "t_end", "steps", "mass_damping")
#: Keys that only dynamics read: the damping of the springs.
DAMPING_KEYS = ("volume_damping", "axial_damping")
#: The calibrated constants that define a spring element.
CONSTANTS = ("k_axial", "k_torsion", "k_volume", "k_axis_volume", "k_coupling")


def _rules(o: SpringOptions) -> dict[str, str | None]:
    """Key -> why it is inert with the options ``o`` (``None``: it is not)."""
    static = o.solver in ("static", "linear")
    out: dict[str, str | None] = {
        "torsion_cubic": (
            f'no effect with torsion = "{o.torsion}" (only the "cubic" torsion law reads it)'
            if o.torsion != "cubic"
            else None
        ),
        "axial_coefficients": (
            'no effect with axial = "linear" (only the polynomial axial laws read them)'
            if o.axial == "linear"
            else None
        ),
        "stiffening_modulus": (
            'no effect with stiffening = "off"' if o.stiffening == "off" else None
        ),
        "nodal_fraction": (
            'no effect with volume_average = "element" (it splits the nodal volume energy)'
            if not o.nodal_volume
            else None
        ),
        "strain_stabilisation": (
            'no effect with strain_average = "element"' if o.strain_average == "element" else None
        ),
        "volumetric": (
            f"no effect with volume = {str(o.volume).lower()} (only the axis-volume spring "
            "has a U(J))"
            if not o.axis_volume
            else None
        ),
        "volume_form": (
            "no effect without the barycentric volume springs (volume = true)"
            if not o.barycentric_volume
            else None
        ),
    }
    for key in TIMED_KEYS:
        out[key] = (
            f"no effect on a {o.solver} solve (it sets the time step of a timed run)"
            if static and key in ("dt", "dt_safety")
            else f"no effect on a {o.solver} solve (only a timed run reads it)"
            if static
            else None
        )
    for key in DAMPING_KEYS:
        out[key] = f"no effect on a {o.solver} solve (damping acts in dynamics)" if static else None
    return out


def inert_keys(scene: Any, options: SpringOptions | None = None) -> list[str]:
    """One line for each key of the scene's ``[spring]`` table that changes nothing.

    Parameters
    ----------
    scene
        The scene (its ``[spring]`` table as written, ``scene.raw["spring"]``).
    options
        The options the scene is solved with; lines are given only when they are the
        scene's own (:meth:`SpringOptions.of`), since a study's variant is not the user's.

    Returns
    -------
    list of str
        ``"spring.<key>: no effect ... (why)"``, in the table's key order.
    """
    table = scene.raw.get("spring", {}) if isinstance(scene.raw, dict) else {}
    if not isinstance(table, dict) or not table:
        return []
    file = str(scene.path) if scene.path is not None else "<scene>"
    written = parse_spring_options(TableReader(table, "spring", file, root=scene.raw))
    o = SpringOptions.of(scene) if options is None else options
    if o != written:  # not the options the scene's table says (a study's variant)
        return []
    why = _rules(o)
    lines = [f"spring.{k}: {why[k]}" for k in table if why.get(k)]
    if "calibration" in table:
        line = _same_calibration(scene, o)
        if line:
            lines.append(line)
    return lines


def _same_calibration(scene: Any, o: SpringOptions) -> str | None:
    """The line for a ``calibration`` that gives the same constants as its element's own
    calibration (the named element's; ``analytic`` for the specification's)."""
    from dataclasses import replace

    from .elements import build_spring_elements
    from .options import ELEMENTS

    base = ELEMENTS.get(o.element, {}).get("calibration", "analytic")
    if o.calibration == base or o.calibration == "nnls" or base == "nnls":
        return None
    mesh = scene.mesh

    def constants(calibration: str) -> list[np.ndarray | None]:
        el = build_spring_elements(
            mesh.points, mesh.tets, scene.frames, replace(o, calibration=calibration),
            scene.material,
        )  # fmt: skip
        return [getattr(el, c, None) for c in CONSTANTS]

    a, b = constants(o.calibration), constants(base)
    same = all(
        (x is None and y is None)
        or (x is not None and y is not None and np.array_equal(np.asarray(x), np.asarray(y)))
        for x, y in zip(a, b, strict=True)
    )
    if not same:
        return None
    return (
        f'spring.calibration: "{o.calibration}" gives the same constants as "{base}" for '
        f"this element and the {scene.material.law} law: no effect"
    )
