"""The locking-free switch of the default spring element: nodal strain and nodal volume on
nearly incompressible scenes.

The plain spring elements lock as P1 does when the bulk modulus dwarfs the shear modulus
(docs/volumetric.rst#why-p1-locks). A scene that keeps the default element (``[spring]
element = "auto"``, or no element and none of its parts) and whose material is nearly
incompressible (:func:`nearly_incompressible`) gets :data:`LOCKING_FREE` on top of it:
the stabilised nodal-strain, nodal-volume tet (docs/volumetric.rst#stabilised-nodal-strain).
``[spring] locking_free`` sets the switch for any element but the seed's; the section's
other keys override its parts (docs/studies.rst#the-default-spring-element).

Examples
--------
>>> from springfem.scene import Material
>>> nearly_incompressible(Material("neo-hookean", E=1.0, nu=0.49))
True
>>> sorted(LOCKING_FREE)
['strain_average', 'volume_average']
"""

from __future__ import annotations

from typing import Any

from springfem.errors import SceneError
from springfem.materials.tissue import TISSUE_LAWS
from springfem.scene import TableReader

#: The switch's options (``[spring] locking_free``): nodal strain and nodal volume, at
#: their default stabilisations (``strain_stabilisation``; ``volume_stabilisation``
#: ``alpha mu / kappa``), docs/studies.rst#the-default-spring-element.
LOCKING_FREE: dict[str, Any] = {"volume_average": "nodal", "strain_average": "nodal"}
#: An isotropic material is nearly incompressible (the switch is on by default) from this
#: Poisson ratio ...
NEARLY_INCOMPRESSIBLE_NU = 0.45
#: ... a tissue material from this ratio of its penalty ``kappa`` to the mean shear modulus
#: of its small-strain tangent, or with ``incompressible = true``.
NEARLY_INCOMPRESSIBLE_RATIO = 30.0


def nearly_incompressible(material) -> bool:
    """Whether a scene's material is nearly incompressible: the locking-free switch's rule.

    Parameters
    ----------
    material
        A :class:`~springfem.scene.Material` (a tissue law's ``E``, ``nu`` are its isotropic
        equivalent: the mean shear modulus of its tangent and its penalty ``kappa``).

    Returns
    -------
    bool
        An isotropic law (``linear``, ``neo-hookean``): ``nu >=``
        :data:`NEARLY_INCOMPRESSIBLE_NU` (``kappa / mu >= 9.7``). A tissue law, whose ``nu``
        is only an equivalent: ``incompressible = true`` or its penalty ``kappa >=``
        :data:`NEARLY_INCOMPRESSIBLE_RATIO` times the mean shear modulus of its tangent.
        Never ``transverse-linear`` (no single Poisson ratio; its ``nu`` is ``nu_cross``).

    Examples
    --------
    >>> from springfem.scene import Material
    >>> [nearly_incompressible(Material("neo-hookean", E=1.0, nu=nu)) for nu in (0.3, 0.45)]
    [False, True]
    """
    if material.law == "transverse-linear":
        return False
    if material.law in TISSUE_LAWS:
        ratio = material.kappa / material.mu
        return bool(material.incompressible or ratio >= NEARLY_INCOMPRESSIBLE_RATIO)
    return bool(material.nu >= NEARLY_INCOMPRESSIBLE_NU)


def volume_stabilisation_default(alpha: float, material=None) -> float:
    """The default ``volume_stabilisation`` ``beta`` with nodal strain: ``alpha mu / kappa``.

    Each tet then keeps a volumetric stiffness ``beta kappa = alpha mu``, as it keeps
    ``alpha`` of its deviatoric springs, whatever the bulk modulus: the FEM's nodal-strain
    share (docs/fem.rst#nodal-strain-tetrahedra). A fixed share of ``kappa`` grows with it
    and locks as ``nu -> 1/2`` (docs/volumetric.rst#stabilised-spring-against-nu).

    Parameters
    ----------
    alpha
        ``strain_stabilisation``.
    material
        The scene's :class:`~springfem.scene.Material` (a tissue law's ``mu``, ``kappa``:
        its isotropic equivalent, whose ``kappa`` is the penalty). ``None``: the tissue
        scenes' ``kappa = 1000 mu``, ``VOLUME_STABILISATION`` of :mod:`springmodel.options`.

    Returns
    -------
    float
        ``min(1, alpha mu / kappa)``.

    Examples
    --------
    >>> from springfem.scene import Material
    >>> round(volume_stabilisation_default(0.3, Material("neo-hookean", E=3.0, nu=0.4999)), 8)
    6e-05
    """
    mu = 0.0 if material is None else float(material.mu)
    kappa = 0.0 if material is None else float(material.kappa)
    if not (kappa > 0 and mu > 0):
        return alpha / 1000.0  # kappa = 1000 mu
    return min(1.0, alpha * mu / kappa)


def locking_free_switch(r: TableReader, name: str, auto: bool) -> bool:
    """Whether the element named ``name`` gets the locking-free switch (:data:`LOCKING_FREE`).

    ``[spring] locking_free = true | false`` decides; without it, the default element of a
    nearly incompressible scene (:func:`nearly_incompressible`) gets it: ``element =
    "auto"``, or no ``element`` and none of its parts (parts alone build on the seed's
    element). The section's other keys override the switch's parts. The seed's barycentric
    volume springs have no nodal form.
    """
    if r.has("locking_free"):
        on = r.get("locking_free", "bool")
        if on and name == "seed":
            raise r.fail(
                "locking_free", 'needs an element with the axis-volume spring (element = '
                '"exact" or "tissue"), not the seed\'s barycentric volume springs'
            )  # fmt: skip
        return bool(on)
    material = scene_material(r)
    return auto and material is not None and nearly_incompressible(material)


def scene_material(r: TableReader):
    """The scene's :class:`~springfem.scene.Material`, or ``None`` if its table is not valid
    (the material section reports that itself)."""
    from springfem.scene.sections import parse_material
    from springfem.scene.types import Material

    material = (r.root or {}).get("material")
    if isinstance(material, Material) or material is None:
        return material
    if not isinstance(material, dict):
        return None
    try:
        return parse_material(TableReader(material, "material", r.file))
    except SceneError:
        return None
