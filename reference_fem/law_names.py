"""FEM law names: which law a scene (or a ``--law`` option) asks the reference for.

The name is ``linear``, ``transverse-linear``, a tissue law (``guccione``,
``holzapfel-ogden``), or ``neo-hookean`` with an optional formulation and volumetric
function, ``neo-hookean/coupled`` or ``neo-hookean/uncoupled/<log|quadratic|simo-taylor>``
(:data:`LAW_NAMES`).

Examples
--------
>>> from springfem.mesh import box_mesh
>>> from springfem.scene import Material, scene_from_dict
>>> scene = scene_from_dict({"mesh": box_mesh((1.0, 1.0, 1.0), (1, 1, 1)),
...                          "material": Material("neo-hookean", 100.0, 0.3)})
>>> parse_law(scene, "linear")
('linear', None)
>>> kind, law = parse_law(scene, "neo-hookean/coupled")
>>> kind, type(law).__name__
('neo-hookean', 'NeoHookean')
>>> parse_law(scene, "neo-hookean/elastic")
Traceback (most recent call last):
...
springfem.errors.InputError: formulation 'elastic' is not one of ...
"""

from __future__ import annotations

from springfem.errors import InputError
from springfem.materials.laws import TISSUE_LAWS, LawNames, TissueLaw, tissue_law
from springfem.materials.laws.neo_hookean import NeoHookean
from springfem.scene import FORMULATIONS, VOLUMETRIC, Scene

#: Every law name the FEM reference accepts (every registered tissue law last).
LAW_NAMES = LawNames(
    ("linear", "transverse-linear", "neo-hookean", "neo-hookean/coupled")
    + tuple(f"neo-hookean/uncoupled/{v}" for v in VOLUMETRIC)
)


def parse_law(scene: Scene, law: str | None) -> tuple[str, NeoHookean | TissueLaw | None]:
    """Resolve a law name (default: the scene's) to a kind and, if nonlinear, a law object.

    ``neo-hookean`` takes the formulation and volumetric function of the scene's material;
    ``neo-hookean/coupled`` or ``neo-hookean/uncoupled[/log|quadratic|simo-taylor]``
    override them. A tissue material takes only its own law.

    Parameters
    ----------
    scene
        The scene; its material gives the default law and the constants.
    law
        A name of :data:`LAW_NAMES`, or None for ``scene.material.law``.

    Returns
    -------
    kind, law
        ``kind`` is ``linear``, ``transverse-linear``, ``neo-hookean`` or the tissue law's
        name; ``law`` is None for the linear kinds, else the
        :class:`~springfem.materials.laws.neo_hookean.NeoHookean` or
        :class:`~springfem.materials.laws.TissueLaw` object.

    Raises
    ------
    InputError
        An unknown name, or a law the scene's material cannot provide (e.g.
        ``transverse-linear`` without the transverse constants, an isotropic law for a
        transverse material, another law for a tissue material).
    """
    mat = scene.material
    name = law or mat.law
    kind, _, rest = name.partition("/")
    if kind in TISSUE_LAWS or mat.law in TISSUE_LAWS:  # the tissue laws
        if rest or kind != mat.law:
            raise InputError(f"law {name!r} does not apply to {mat.law}; use law {mat.law}")
        return kind, tissue_law(mat)
    if kind not in ("linear", "transverse-linear", "neo-hookean"):
        raise InputError(f"law {name!r} is not one of {', '.join(LAW_NAMES)}")
    if kind == "transverse-linear":
        if rest or mat.E_fiber is None:
            raise InputError(
                f"law {name!r} needs a transverse-linear material (E_fiber, E_cross, "
                "nu_fiber_cross, nu_cross, G_fiber)"
            )
        return kind, None
    if mat.law == "transverse-linear":
        raise InputError(
            f"law {name!r} is isotropic but the scene's material is transverse-linear; "
            "use law transverse-linear"
        )
    if kind == "linear":
        if rest:
            raise InputError(f"law {name!r} is not one of {', '.join(LAW_NAMES)}")
        return kind, None
    form, _, vol = rest.partition("/")
    if form and form not in FORMULATIONS:
        raise InputError(f"formulation {form!r} is not one of {', '.join(FORMULATIONS)}")
    if vol and (form != "uncoupled" or vol not in VOLUMETRIC):
        raise InputError(f"law {name!r} is not one of {', '.join(LAW_NAMES)}")
    return kind, NeoHookean.from_material(mat, form or None, vol or None)
