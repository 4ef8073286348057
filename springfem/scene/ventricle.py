"""Scene parsers of the ventricle: ``[mesh] generator = "ellipsoid"``,
``[axes] type = "rule-based"`` and ``[axes] type = "land-ellipsoid"``.

The ellipsoid is Land et al. 2015's truncated ellipsoid (:mod:`springfem.ellipsoid`); the
rule-based frames are :func:`springfem.fibres.rule_based_frames`, whose transmural depth is
kept as the mesh's cell data ``transmural_depth`` (it is written into the VTU). The
``land-ellipsoid`` frames are Land's closed-form problem-3 field
(:func:`springfem.land_fibres.land_frames`) at the element barycentres; its ellipsoid
parameter ``t`` is kept as ``transmural_depth`` too. A P2 FEM evaluates either rule at its
quadrature points (:mod:`reference_fem.point_fibres`).

Examples
--------
>>> from springfem.scene.reader import TableReader
>>> r = TableReader({"generator": "ellipsoid", "size": 4.0}, "mesh", "<scene>")
>>> m = parse_ellipsoid(r)
>>> sorted(m.facet_sets)
['base', 'endo', 'epi']
>>> frames = parse_rule_based(TableReader({"type": "rule-based"}, "axes", "<scene>"), m)
>>> frames.shape == (m.n_tets, 3, 3), "transmural_depth" in m.cell_data
(True, True)
"""

from __future__ import annotations

import math

import numpy as np

from .. import ellipsoid
from ..errors import InputError
from ..fibres import rule_based_frames
from ..land_fibres import (
    LAND_ENDO,
    LAND_ENDO_ANGLE,
    LAND_EPI,
    LAND_EPI_ANGLE,
    T_TOLERANCE,
    ellipsoid_parameter,
    land_frames,
)
from ..mesh import TetMesh
from .limits import check_mesh_size
from .reader import TableReader

#: ``[mesh]`` keys of the ellipsoid generator, ``[axes]`` keys of the rule-based frames.
ELLIPSOID_KEYS = ("endo", "epi", "base_z", "axis_size")
RULE_BASED_KEYS = ("endo_angle", "epi_angle", "endo", "epi")
LAND_KEYS = ("endo_angle", "epi_angle", "endo_radii", "epi_radii")
#: Defaults of the ``land-ellipsoid`` ``[axes]`` keys (Land et al. 2015, problem 3).
LAND_DEFAULTS = {"endo_angle": LAND_ENDO_ANGLE, "epi_angle": LAND_EPI_ANGLE,
                 "endo_radii": LAND_ENDO, "epi_radii": LAND_EPI}  # fmt: skip
#: Defaults of the rule-based ``[axes]`` keys.
RULE_BASED_DEFAULTS = {"endo_angle": 60.0, "epi_angle": -60.0, "axis": "z", "endo": "endo",
                       "epi": "epi"}  # fmt: skip


def rule_based_settings(table) -> dict | None:
    """The keywords of :func:`springfem.fibres.rule_based_frames` of a validated ``[axes]``
    table (``axis`` as a vector), or ``None`` when its frames are not rule-based.

    Parameters
    ----------
    table
        The scene's ``[axes]`` table as given (already checked by :func:`parse_rule_based`).

    Returns
    -------
    dict or None

    Examples
    --------
    >>> rule_based_settings({"type": "rule-based", "endo_angle": -90.0})["epi_angle"]
    -60.0
    >>> rule_based_settings({"fiber": [1, 0, 0]}) is None
    True
    """
    if not isinstance(table, dict) or table.get("type") != "rule-based":
        return None
    kw = {k: table.get(k, v) for k, v in RULE_BASED_DEFAULTS.items()}
    kw["axis"] = np.eye(3)["xyz".index(kw["axis"])]
    return kw


def land_settings(table) -> dict | None:
    """The keywords of :func:`springfem.land_fibres.land_frames` of a validated ``[axes]``
    table, or ``None`` when its frames are not ``land-ellipsoid``.

    Parameters
    ----------
    table
        The scene's ``[axes]`` table as given (already checked by :func:`parse_land`).

    Returns
    -------
    dict or None

    Examples
    --------
    >>> land_settings({"type": "land-ellipsoid"})["endo"]
    (7.0, 17.0)
    >>> land_settings({"type": "rule-based"}) is None
    True
    """
    if not isinstance(table, dict) or table.get("type") != "land-ellipsoid":
        return None
    kw = {k: table.get(k, v) for k, v in LAND_DEFAULTS.items()}
    return {"endo_angle": float(kw["endo_angle"]), "epi_angle": float(kw["epi_angle"]),
            "endo": tuple(map(float, kw["endo_radii"])),
            "epi": tuple(map(float, kw["epi_radii"]))}  # fmt: skip


#: Volume of an average gmsh tet of target size ``h``, over ``h^3`` (a regular tet has
#: 1/(6 sqrt 2) = 0.118; gmsh's are a little smaller): for the size check before meshing.
_TET_VOLUME_FACTOR = 0.08


def parse_ellipsoid(r: TableReader) -> TetMesh:
    """``[mesh] generator = "ellipsoid"``: ``size``, ``endo``, ``epi``, ``base_z`` and
    ``axis_size`` (finer elements along the long axis, :func:`springfem.ellipsoid.ellipsoid_mesh`).

    Parameters
    ----------
    r
        Reader over the ``[mesh]`` table (``generator`` may be read already).

    Returns
    -------
    TetMesh
        With facet sets ``endo``, ``epi`` and ``base``.
    """
    r.get("generator", "str", choices=("ellipsoid",))
    size = r.get("size", "float", default=2.0, positive=True)
    endo = r.get("endo", "vec", default=np.array(ellipsoid.ENDO), length=2, positive=True)
    epi = r.get("epi", "vec", default=np.array(ellipsoid.EPI), length=2, positive=True)
    base_z = r.get("base_z", "float", default=ellipsoid.BASE_Z)
    axis_size = r.get("axis_size", "float", default=None, positive=True)
    r.finish()
    if axis_size is not None and axis_size > size:
        raise r.fail("axis_size", f"{axis_size} must not exceed size = {size}")
    if not (endo[0] < epi[0] and endo[1] < epi[1]):
        raise r.fail("epi", f"radii {epi.tolist()} must exceed endo radii {endo.tolist()}")
    if not -endo[1] < base_z < endo[1]:
        raise r.fail("base_z", f"{base_z} must lie within (-{endo[1]:g}, {endo[1]:g})")
    volume = ellipsoid.wall_volume(tuple(endo), tuple(epi), base_z)
    estimate = volume / (_TET_VOLUME_FACTOR * size**3)
    if axis_size is not None:  # the apex's wall, sizes a + g rho: int 2 pi rho / (a + g rho)^3
        g = ellipsoid.AXIS_GRADING
        estimate += math.pi * (epi[1] - endo[1]) / (g**2 * axis_size) / _TET_VOLUME_FACTOR
    too_big = check_mesh_size(int(min(estimate, 1e15)))
    if too_big:
        raise r.fail("size", too_big)
    try:
        mesh = ellipsoid.ellipsoid_mesh(size, tuple(endo), tuple(epi), base_z, axis_size)
    except InputError as exc:
        raise r.fail("size", str(exc)) from None
    too_big = check_mesh_size(mesh.n_tets)
    if too_big:
        raise r.fail("size", too_big)
    return mesh


def parse_rule_based(r: TableReader, mesh: TetMesh) -> np.ndarray:
    """``[axes] type = "rule-based"``: ``endo_angle``, ``epi_angle`` (degrees), ``axis``
    (the long axis, ``"z"`` by default), ``endo`` and ``epi`` (facet-set names).

    Parameters
    ----------
    r
        Reader over the ``[axes]`` table.
    mesh
        The mesh; its cell data gets ``transmural_depth``.

    Returns
    -------
    numpy.ndarray
        ``(m, 3, 3)`` frames (rows: fiber, sheet, normal).
    """
    r.get("type", "str", choices=("rule-based",))
    d = RULE_BASED_DEFAULTS
    endo_angle = r.get("endo_angle", "float", default=d["endo_angle"])
    epi_angle = r.get("epi_angle", "float", default=d["epi_angle"])
    axis = r.get("axis", "str", default=d["axis"], choices=("x", "y", "z"))
    endo = r.get("endo", "str", default=d["endo"])
    epi = r.get("epi", "str", default=d["epi"])
    r.finish()
    for key, angle in (("endo_angle", endo_angle), ("epi_angle", epi_angle)):
        if not (math.isfinite(angle) and abs(angle) <= 360.0):
            raise r.fail(key, f"must be an angle in degrees within [-360, 360], got {angle}")
    for key, name in (("endo", endo), ("epi", epi)):
        if name not in mesh.facet_sets:
            have = ", ".join(sorted(mesh.facet_sets)) or "none"
            raise r.fail(key, f"mesh has no facet region {name!r} (has: {have})")
    if endo == epi:
        raise r.fail("epi", f"must differ from endo ({endo!r})")
    k = np.eye(3)["xyz".index(axis)]
    try:
        frames, depth = rule_based_frames(mesh, endo_angle, epi_angle, k, endo, epi)
    except InputError as exc:
        raise r.fail("type", str(exc)) from None
    mesh.cell_data["transmural_depth"] = depth
    return frames


def parse_land(r: TableReader, mesh: TetMesh) -> np.ndarray:
    """``[axes] type = "land-ellipsoid"``: ``endo_angle``, ``epi_angle`` (degrees, +90 and
    -90 by default), ``endo_radii`` and ``epi_radii`` (``(r_short, r_long)``, Land's 7/17
    and 10/20 by default; the long axis is ``z``).

    Parameters
    ----------
    r
        Reader over the ``[axes]`` table.
    mesh
        The mesh; its cell data gets ``transmural_depth`` (the ellipsoid parameter ``t``).

    Returns
    -------
    numpy.ndarray
        ``(m, 3, 3)`` frames (rows: fiber, sheet, normal) at the element barycentres.
    """
    r.get("type", "str", choices=("land-ellipsoid",))
    d = LAND_DEFAULTS
    endo_angle = r.get("endo_angle", "float", default=d["endo_angle"])
    epi_angle = r.get("epi_angle", "float", default=d["epi_angle"])
    endo = r.get("endo_radii", "vec", default=np.array(d["endo_radii"]), length=2, positive=True)
    epi = r.get("epi_radii", "vec", default=np.array(d["epi_radii"]), length=2, positive=True)
    r.finish()
    for key, angle in (("endo_angle", endo_angle), ("epi_angle", epi_angle)):
        if not (math.isfinite(angle) and abs(angle) <= 360.0):
            raise r.fail(key, f"must be an angle in degrees within [-360, 360], got {angle}")
    if not (endo[0] < epi[0] and endo[1] < epi[1]):
        raise r.fail("epi_radii", f"{epi.tolist()} must exceed endo_radii {endo.tolist()}")
    try:  # the vertices lie on the surfaces: a wall that does not fit is refused
        ellipsoid_parameter(mesh.points, tuple(endo), tuple(epi), tolerance=T_TOLERANCE)
    except InputError as exc:
        raise r.fail("endo_radii", str(exc)) from None
    centres = mesh.centers()
    frames = land_frames(centres, endo_angle, epi_angle, tuple(endo), tuple(epi))
    mesh.cell_data["transmural_depth"] = ellipsoid_parameter(centres, tuple(endo), tuple(epi))
    return frames
