"""A liver-shaped organ of a chosen size in tets, and a scene that hangs it under gravity.

The organ is two merged ellipsoids (a large right lobe and a flatter left lobe, 150 mm
long, in millimetres) cut flat on top of the right lobe, where it is held. gmsh meshes it
with one element size chosen for the number of tets asked for, and names its parts as
physical groups, which springfem reads as the scene's regions: the volume ``organ``, the
flat cut ``hilum`` and the rest of the surface ``capsule``. The benchmarks and the
organ-scale tests build their meshes here, so that every size of the family is the same
shape.

Examples
--------
>>> import tempfile
>>> from springfem.scene import load_scene
>>> folder = tempfile.mkdtemp()
>>> path = organ_scene(folder, tets=800)
>>> scene = load_scene(path)
>>> 500 < scene.mesh.n_tets < 1300, scene.material.law, scene.material.nu
(True, 'neo-hookean', 0.49)
"""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import MeshError

#: The right lobe: centre and semi-axes (mm).
RIGHT_LOBE = ((-25.0, 0.0, 0.0), (50.0, 45.0, 35.0))
#: The left lobe: centre and semi-axes (mm).
LEFT_LOBE = ((35.0, 8.0, 6.0), (40.0, 28.0, 18.0))
#: Height of the flat cut on top of the right lobe (mm): a patch about 30 mm across.
CUT_Z = 31.0
#: Volume per tet of gmsh's tets of element size h, as a fraction of h³ (measured on this
#: shape; the first mesh corrects it).
TET_VOLUME = 0.12

SCENE = """\
name = "{name}"
units = "mm-kPa"

[mesh]
file = "{mesh}"

[material]
law = "{law}"
E = {E}
nu = {nu}

[[boundary]]
region = "hilum"
fix = ["x", "y", "z"]

[[load]]
type = "gravity"
value = [0.0, 0.0, -9810.0]

[[probe]]
name = "left-tip"
point = [75.0, 8.0, 6.0]

[[probe]]
name = "bottom"
point = [-25.0, 0.0, -35.0]
"""


def organ_volume_mm3() -> float:
    """The organ's volume in mm³ (from gmsh's exact geometry)."""
    import gmsh

    _start()
    try:
        tag = _build()
        return float(gmsh.model.occ.getMass(3, tag))
    finally:
        gmsh.finalize()


def organ_mesh(path: str | os.PathLike, tets: int = 5000, seed: int = 0) -> int:
    """Write a gmsh 4.1 mesh of the organ with about ``tets`` tets.

    Parameters
    ----------
    path
        The ``.msh`` file to write.
    tets
        The number of tets wanted; the mesh has it to within about 15 %.
    seed
        gmsh's random seed (the same seed, the same mesh).

    Returns
    -------
    int
        The number of tets written.
    """
    import gmsh

    if tets < 100:
        raise MeshError(f"organ mesh: {tets} tets is too few for the organ's shape (≥ 100)")
    _start()
    try:
        tag = _build()
        volume = gmsh.model.occ.getMass(3, tag)
        size = (volume / (TET_VOLUME * tets)) ** (1 / 3)
        n = _mesh(size, seed)
        if abs(n / tets - 1) > 0.1:  # correct the size once by the count it gave
            size *= (n / tets) ** (1 / 3)
            gmsh.model.mesh.clear()
            n = _mesh(size, seed)
        path = Path(path)
        tmp = path.with_name(path.name + ".tmp.msh")
        gmsh.write(str(tmp))
        os.replace(tmp, path)
        return n
    finally:
        gmsh.finalize()


def organ_scene(
    folder: str | os.PathLike,
    tets: int = 5000,
    law: str = "neo-hookean",
    E: float = 5.0,
    nu: float = 0.49,
    name: str | None = None,
) -> Path:
    """Write an organ mesh of about ``tets`` tets and its scene file into ``folder``.

    The scene (units mm-kPa): the organ's ``law`` with Young's modulus ``E`` (kPa) and
    Poisson's ratio ``nu``, the flat cut ``hilum`` fixed, gravity along −z, probes at the
    left lobe's tip and the right lobe's bottom.

    Parameters
    ----------
    folder
        Where to write ``<name>.msh`` and ``<name>.toml``.
    tets
        The number of tets wanted (:func:`organ_mesh`).
    law, E, nu
        The material.
    name
        The scene's name (default ``organ-<tets>``).

    Returns
    -------
    Path
        The scene file.
    """
    from ..files import atomic_write_text

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    name = name or f"organ-{tets}"
    organ_mesh(folder / f"{name}.msh", tets)
    text = SCENE.format(name=name, mesh=f"{name}.msh", law=law, E=E, nu=nu)
    atomic_write_text(folder / f"{name}.toml", text)
    return folder / f"{name}.toml"


def _start() -> None:
    import gmsh

    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("organ")


def _build() -> int:
    """The organ's volume in the current gmsh model, with its physical groups; its tag."""
    import gmsh

    occ = gmsh.model.occ
    lobes = []
    for centre, axes in (RIGHT_LOBE, LEFT_LOBE):
        ball = occ.addSphere(0.0, 0.0, 0.0, 1.0)
        occ.dilate([(3, ball)], 0.0, 0.0, 0.0, *axes)
        occ.translate([(3, ball)], *centre)
        lobes.append((3, ball))
    merged, _ = occ.fuse([lobes[0]], [lobes[1]])
    keep = occ.addBox(-200.0, -200.0, -200.0, 400.0, 400.0, 200.0 + CUT_Z)
    body, _ = occ.intersect(merged, [(3, keep)])
    occ.synchronize()
    tag = body[0][1]
    surfaces = [t for _, t in gmsh.model.getBoundary(body, oriented=False)]
    flat = [s for s in surfaces if gmsh.model.getBoundingBox(2, s)[2] > CUT_Z - 1e-3]
    gmsh.model.addPhysicalGroup(3, [tag], name="organ")
    gmsh.model.addPhysicalGroup(2, flat, name="hilum")
    gmsh.model.addPhysicalGroup(2, [s for s in surfaces if s not in flat], name="capsule")
    return tag


def _mesh(size: float, seed: int) -> int:
    """Mesh the current model at element size ``size``; the number of tets."""
    import gmsh

    gmsh.option.setNumber("Mesh.MeshSizeMin", size)
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    gmsh.option.setNumber("Mesh.RandomSeed", seed)
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.model.mesh.generate(3)
    types, tags, _ = gmsh.model.mesh.getElements(3)
    return int(sum(len(t) for t in tags))
