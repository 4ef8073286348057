"""The named spring elements of ``[spring] element`` and the default a scene gets.

A scene names a whole element with ``[spring] element``; a scene that sets no part of the
element gets the best measured one for its law (docs/studies.rst#the-default-spring-element).
The section's other keys override the named element's parts
(:func:`springmodel.options.parse_spring_options`).

Examples
--------
>>> element_for_law("neo-hookean"), element_for_law("guccione")
('exact', 'tissue')
>>> element_options("exact", "transverse-linear")
{'volume': 'axes', 'torsion': 'energy', 'calibration': 'exact', 'coupling': True}
"""

from __future__ import annotations

from typing import Any

from springfem.materials.laws import TISSUE_LAWS, LawNames
from springfem.scene import TableReader

#: ``axial = "green"`` in a scene: the cubic law with these ``(b2, b3)``, whose energy is
#: ``k l0^2 E^2 / 2`` in the spring's Green strain ``E = (lambda^2 - 1) / 2`` (eq. 2.36).
GREEN_AXIAL_COEFFICIENTS = (1.5, 0.5)
#: The named spring elements of ``[spring] element``: the options each sets (the section's
#: other keys override them). ``seed``: the specification's element (barycentric volume
#: springs, cosine torsion, the analytic calibration); ``exact``: the axis-volume spring,
#: the energy torsion and the exact calibration, which is the law's small-strain P1 element
#: on any tet (docs/calibration.rst); ``stiffened``: the exact element for tissue at finite
#: strain (Green axial springs, shear torsion, exponential stiffening, the tissue laws' log
#: penalty); ``tissue``: the Green measures of all six frame strains, each spring group
#: stiffened as the tissue law's terms, equal to the law under any homogeneous deformation
#: (docs/tissue.rst).
ELEMENTS: dict[str, dict[str, Any]] = {
    "seed": {},
    "exact": {"volume": "axes", "torsion": "energy", "calibration": "exact"},
    "stiffened": {
        "volume": "axes",
        "torsion": "shear",
        "calibration": "exact",
        "axial": "cubic",
        "axial_coefficients": GREEN_AXIAL_COEFFICIENTS,
        "stiffening": "exponential",
        "volumetric": "log",
    },
    "tissue": {
        "volume": "axes",
        "torsion": "green",
        "calibration": "exact",
        "axial": "cubic",
        "axial_coefficients": GREEN_AXIAL_COEFFICIENTS,
        "stiffening": "law",
        "volumetric": "log",
    },
}
#: ``[spring] element`` when a scene names none: :func:`element_for_law` if the section sets
#: no part of the element (:data:`ELEMENT_KEYS`), else the seed's element with those parts.
DEFAULT_ELEMENT = "auto"
#: The ``[spring]`` options that make up the element (the rest choose the solver).
ELEMENT_KEYS = (
    *("axial", "axial_coefficients", "torsion", "torsion_cubic", "volume", "volume_average"),
    *("nodal_fraction", "stiffening", "stiffening_modulus", "volumetric", "coupling"),
    *("volume_form", "lms", "calibration", "k_axial", "k_torsion", "k_volume"),
    *("volume_stabilisation", "strain_average", "strain_stabilisation"),
)
#: Laws with an anisotropic small-strain tangent: every named element but the seed's adds
#: the Poisson-coupling springs on them (the exact calibration needs them there).
ANISOTROPIC_LAWS = LawNames(("transverse-linear",))
#: The tissue laws whose terms the ``tissue`` element carries in its compiled pass
#: (:mod:`springmodel.tissue_kernel`, ``stiffening = "law"``); another tissue law's element
#: takes the law's own energy in numpy (:func:`springmodel.tissue_element.law_derivatives`).
LAW_TERMS = ("guccione", "holzapfel-ogden")


def element_for_law(law: str) -> str:
    """The element a scene of ``law`` gets by default: the best measured one.

    Parameters
    ----------
    law
        The ``[material]`` law.

    Returns
    -------
    str
        ``tissue`` for a tissue law, else ``exact``.

    Examples
    --------
    >>> element_for_law("linear")
    'exact'
    """
    return "tissue" if law in TISSUE_LAWS else "exact"


def element_options(name: str, law: str) -> dict[str, Any]:
    """The :class:`SpringOptions` fields of the named element for ``law``.

    Parameters
    ----------
    name
        A key of :data:`ELEMENTS`.
    law
        The ``[material]`` law: an anisotropic one adds ``coupling`` to every element but
        the seed's.

    Returns
    -------
    dict
        Field name -> value.

    Examples
    --------
    >>> element_options("seed", "guccione")
    {}
    """
    options = dict(ELEMENTS[name])
    if name != "seed" and law in ANISOTROPIC_LAWS:
        options["coupling"] = True
    return options


def named_element(r: TableReader) -> tuple[str, dict[str, Any]]:
    """The ``[spring] element`` a table builds on and its options (:func:`element_options`)."""
    law = _scene_law(r)
    name = DEFAULT_ELEMENT
    if r.has("element"):
        name = r.get("element", "str", choices=(DEFAULT_ELEMENT, *ELEMENTS))
    elif any(key in r.t for key in ELEMENT_KEYS):
        name = "seed"  # parts picked one by one build on the specification's element
    if name == DEFAULT_ELEMENT:
        name = element_for_law(law)
    if name == "tissue" and law not in TISSUE_LAWS:
        raise r.fail(
            "element", f'"tissue" needs a tissue law ({", ".join(TISSUE_LAWS)}), not {law!r}'
        )
    if name == "stiffened" and law not in TISSUE_LAWS and "stiffening_modulus" not in r.t:
        raise r.fail(
            "element", f'"stiffened" needs stiffening_modulus for law {law!r} (no C of its own)'
        )
    return name, element_options(name, law)


def _scene_law(r: TableReader) -> str:
    """The ``[material]`` law of the scene the table belongs to (``linear`` if unknown)."""
    material = (r.root or {}).get("material", {})
    law = getattr(material, "law", None)
    if law is None and isinstance(material, dict):
        law = material.get("law")
    return law if isinstance(law, str) else "linear"
