"""Parsers of the scene's sections: mesh, material, axes, regions, boundary, load, probe.

Each takes a :class:`~springfem.scene.reader.TableReader` over its table and returns the
section's object, or raises :class:`~springfem.errors.SceneError` naming the key.

Examples
--------
>>> r = TableReader({"law": "linear", "E": 1.0e3, "nu": 0.25}, "material", "<scene>")
>>> parse_material(r).kappa
666.6666666666666
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, get_args

import numpy as np

from .. import axes
from ..errors import InputError, SceneError
from ..materials.tissue import TISSUE_LAWS
from ..mesh import Split, TetMesh, box_mesh, nearest_boundary_point, read_mesh
from ..regions import Region, locate_points, resolve_region
from .cook import parse_cook
from .limits import check_mesh_size
from .load_time import TIME_KEYS, parse_time_table
from .reader import MAX_MAGNITUDE, TableReader, _show, is_number
from .tissue import TISSUE_KEYS, parse_tissue
from .types import (
    AXES_TYPES,
    COMPONENTS,
    FORMULATIONS,
    LAWS,
    LOAD_TYPES,
    VOLUMETRIC,
    Boundary,
    Load,
    Material,
    Probe,
    default_density,
)
from .ventricle import (
    ELLIPSOID_KEYS,
    LAND_KEYS,
    RULE_BASED_KEYS,
    parse_ellipsoid,
    parse_land,
    parse_rule_based,
)

#: The keys valid in each core section (messages suggest the closest for a misspelt one).
SECTION_KEYS = {
    "mesh": (
        *("file", "scale", "generator", "size", "divisions", "split", "origin", "jitter", "seed"),
        *ELLIPSOID_KEYS,
        "thickness",
    ),
    "material": (
        *("law", "density", "E", "nu", "mu", "kappa", "formulation", "volumetric"),
        *("E_fiber", "E_cross", "nu_fiber_cross", "nu_cross", "G_fiber"),
        *TISSUE_KEYS[1:],
    ),
    "axes": (
        *("type", "fiber_data", "sheet_data", "fiber", "sheet", "axis", "range", "angles"),
        *dict.fromkeys((*RULE_BASED_KEYS, *LAND_KEYS)),
    ),
    "boundary": ("region", "fix", "displacement"),
    "load": ("type", "value", "region", "time"),
    "probe": ("name", "point"),
}


def material_keys() -> tuple[str, ...]:
    """The ``[material]`` keys: the fixed ones and every registered tissue law's constants."""
    return (*SECTION_KEYS["material"], *sorted({k for ks in TISSUE_LAWS.values() for k in ks}))


#: A probe outside the mesh by at most this share of the nearest element's size (its mean
#: edge length) is snapped to the nearest boundary point, with a note; farther out it is
#: refused.
SNAP_DISTANCE = 0.5


def parse_mesh(r: TableReader, base: Path) -> TetMesh:
    """The ``[mesh]`` section: a mesh file (``file``, ``scale``), a box or an ellipsoid.

    Parameters
    ----------
    r
        Reader over the ``[mesh]`` table; every error names the file and key.
    base
        Folder that relative ``file`` paths are relative to.

    Returns
    -------
    TetMesh
        Validated; refused up front when too large (:func:`check_mesh_size`).
    """
    if r.has("file") and r.has("generator"):
        raise r.fail("file", "give either file or generator, not both")
    if r.has("file"):
        rel = r.get("file", "str")
        p = Path(rel)
        p = p if p.is_absolute() else base / p
        scale = r.get("scale", "float", default=1.0, positive=True)
        r.finish()
        try:
            mesh = read_mesh(p, scale=scale)
        except InputError as exc:
            raise SceneError(f"{r.file}: mesh.file: {exc}") from None
        # a file's size can't be judged before reading it; reading needs far less memory
        # than solving, so the estimate is checked right after
        too_big = check_mesh_size(mesh.n_tets)
        if too_big:
            raise r.fail("file", too_big)
        return mesh
    gen = r.get("generator", "str", choices=("box", "ellipsoid", "cook"))
    if gen == "ellipsoid":
        return parse_ellipsoid(r)
    if gen == "cook":
        return parse_cook(r)
    size = r.get("size", "vec", length=3, positive=True)
    div = r.get("divisions", "ivec", length=3, positive=True)
    split: Split = r.get("split", "str", default="six", choices=opt_splits())
    origin = r.get("origin", "vec", default=np.zeros(3), length=3)
    jitter, seed = 0.3, 0
    for key in ("jitter", "seed"):
        if r.has(key) and split != "delaunay":
            raise r.fail(key, f'applies to split = "delaunay" only (this box: split = "{split}")')
    if split == "delaunay":
        jitter = r.get("jitter", "float", default=0.3, nonneg=True)
        seed = r.get("seed", "int", default=0)
    r.finish()
    per_cell = 6 if split.startswith("six") or split == "delaunay" else 5
    n_tets = math.prod(int(d) for d in div) * per_cell
    too_big = check_mesh_size(n_tets)
    if too_big:
        raise r.fail("divisions", too_big)
    assert gen == "box"
    nx, ny, nz = (int(d) for d in div)
    x0, y0, z0 = (float(o) for o in origin)
    lx, ly, lz = (float(s) for s in size)
    try:
        if split == "delaunay":
            return box_mesh((lx, ly, lz), (nx, ny, nz), split, (x0, y0, z0), jitter, seed)
        return box_mesh((lx, ly, lz), (nx, ny, nz), split, (x0, y0, z0))
    except InputError as exc:
        raise r.fail("jitter" if "jitter" in str(exc) else "size", str(exc)) from None


def opt_splits() -> tuple[str, ...]:
    """The mesh splits a box generator accepts.

    Returns
    -------
    tuple of str
    """
    return get_args(Split)


def parse_material(r: TableReader, units: str = "SI") -> Material:
    """The ``[material]`` section: law, density and elastic constants.

    ``E`` and ``nu``, or ``mu`` and ``kappa``, for the isotropic laws; the five
    transversely isotropic constants for ``transverse-linear`` (checked for a positive
    definite compliance).

    Parameters
    ----------
    r
        Reader over the ``[material]`` table; every error names the file and key.
    units
        The scene's unit system: a ``density`` left out is 1000 kg/m³ in it
        (:func:`~springfem.scene.types.default_density`).

    Returns
    -------
    Material
    """
    law = r.get("law", "str", choices=LAWS)
    if law not in TISSUE_LAWS and r.has("active_tension"):
        raise r.fail(
            "active_tension",
            f"needs a law with fibres ({', '.join(TISSUE_LAWS)}), not law = {law!r}",
        )
    density = r.get("density", "float", default=default_density(units), positive=True)
    kw: dict[str, Any] = {"law": law, "density": density}
    if law == "transverse-linear":
        for k in ("E_fiber", "E_cross", "G_fiber"):
            kw[k] = r.get(k, "float", positive=True)
        kw["nu_fiber_cross"] = r.get("nu_fiber_cross", "float")
        kw["nu_cross"] = r.get("nu_cross", "float")
        if not -1.0 < kw["nu_cross"] < 1.0:
            raise r.fail("nu_cross", f"must lie in (-1, 1), got {kw['nu_cross']}")
        # positive definiteness of the compliance
        Ef, Ec, nfc, nc = kw["E_fiber"], kw["E_cross"], kw["nu_fiber_cross"], kw["nu_cross"]
        if 1 - nc - 2 * nfc**2 * Ec / Ef <= 0:
            raise r.fail(
                "nu_fiber_cross",
                f"{nfc} with nu_cross = {nc} gives an indefinite material "
                "(need 1 - nu_cross - 2 nu_fiber_cross^2 E_cross/E_fiber > 0)",
            )
        kw["E"], kw["nu"] = Ec, nc
    elif law in TISSUE_LAWS:
        kw.update(parse_tissue(r, law))
    else:
        if r.has("mu") or r.has("kappa"):
            if r.has("E") or r.has("nu"):
                raise r.fail("mu", "give either E and nu, or mu and kappa")
            mu = r.get("mu", "float", positive=True)
            kappa = r.get("kappa", "float", positive=True)
            kw["E"] = 9 * mu / (3 + mu / kappa)  # = 9 kappa mu / (3 kappa + mu), no overflow
            kw["nu"] = (3 - 2 * mu / kappa) / (2 * (3 + mu / kappa))
        else:
            kw["E"] = r.get("E", "float", positive=True)
            kw["nu"] = r.get("nu", "float")
        if not -1.0 < kw["nu"] < 0.5:
            raise r.fail("nu", f"must lie in (-1, 0.5), got {kw['nu']}")
        if law == "neo-hookean":
            kw["formulation"] = r.get("formulation", "str", default="coupled", choices=FORMULATIONS)
            kw["volumetric"] = r.get("volumetric", "str", default="log", choices=VOLUMETRIC)
    r.finish()
    return Material(**kw)


def parse_axes(r: TableReader, mesh: TetMesh) -> np.ndarray:
    """The ``[axes]`` section: ``uniform``, ``helix``, ``cells`` (mesh cell data) or
    ``rule-based`` (:func:`~springfem.scene.ventricle.parse_rule_based`) or
    ``land-ellipsoid`` (:func:`~springfem.scene.ventricle.parse_land`) frames.

    Parameters
    ----------
    r
        Reader over the ``[axes]`` table; every error names the file and key.
    mesh
        The scene's mesh (regions and probes are resolved on it).

    Returns
    -------
    numpy.ndarray
        ``(m, 3, 3)`` frames (rows: fiber, sheet, normal).
    """
    kind = r.get(
        "type", "str", default="uniform", choices=(*AXES_TYPES, "rule-based", "land-ellipsoid")
    )
    if kind == "rule-based":
        return parse_rule_based(r, mesh)
    if kind == "land-ellipsoid":
        return parse_land(r, mesh)
    try:
        if kind == "cells":
            fkey = r.get("fiber_data", "str", default="fiber")
            skey = r.get("sheet_data", "str", default="sheet")
            r.finish()
            if fkey not in mesh.cell_data:
                have = ", ".join(sorted(mesh.cell_data)) or "none"
                raise r.fail(
                    "fiber_data", f"mesh has no cell data {_show(fkey)} (has: {_show(have)})"
                )
            fib = np.asarray(mesh.cell_data[fkey], dtype=float).reshape(mesh.n_tets, -1)[:, :3]
            sh = mesh.cell_data.get(skey)
            sh = None if sh is None else np.asarray(sh, float).reshape(mesh.n_tets, -1)[:, :3]
            bad = np.flatnonzero(np.linalg.norm(fib, axis=1) < 1e-12)
            if bad.size:
                raise r.fail("fiber_data", f"zero fiber vector at elements {bad[:8].tolist()}")
            return axes.cell_frames(fib, sh)
        fiber = r.get("fiber", "vec", default=np.array([1.0, 0.0, 0.0]), length=3)
        sheet = r.get("sheet", "vec", default=np.array([0.0, 1.0, 0.0]), length=3)
        if kind == "uniform":
            r.finish()
            return axes.uniform_frames(mesh.n_tets, fiber, sheet)
        axis = r.get("axis", "str", default="x", choices=COMPONENTS)
        rng = r.get("range", "vec", length=2)
        angles = r.get("angles", "vec", length=2)
        r.finish()
        return axes.helix_frames(mesh.centers(), fiber, sheet, axis, tuple(rng), tuple(angles))
    except ValueError as exc:
        if isinstance(exc, SceneError):
            raise
        raise SceneError(f"{r.file}: axes: {exc}") from None


def _coordinate(x: Any) -> bool:
    """A number usable as a coordinate: finite and within :data:`MAX_MAGNITUDE`."""
    return is_number(x) and math.isfinite(x) and abs(x) <= MAX_MAGNITUDE


def parse_region(r: TableReader, mesh: TetMesh, key: str = "region") -> Region:
    """The region under ``key``: a name, ``{ box = [...] }`` or ``{ point = [...] }``.

    Parameters
    ----------
    r
        Reader over the ``boundary or load`` table; every error names the file and key.
    mesh
        The scene's mesh (regions and probes are resolved on it).
    key
        The key holding the region.

    Returns
    -------
    Region
        See :func:`~springfem.regions.resolve_region`.
    """
    if not r.has(key):
        raise r.missing(key)
    r.used.add(key)
    spec = r.t[key]
    if isinstance(spec, dict):
        if set(spec) == {"box"}:
            box = spec["box"]
            ok = (
                isinstance(box, list)
                and len(box) == 2
                and all(
                    isinstance(c, list)
                    and len(c) == 3
                    and all(is_number(x) and math.isfinite(x) for x in c)
                    for c in box
                )
            )
            if not ok:
                raise r.fail(key, "box must be [[x0, y0, z0], [x1, y1, z1]] (finite numbers)")
        elif set(spec) == {"point"}:
            p = spec["point"]
            if not (isinstance(p, list) and len(p) == 3 and all(_coordinate(x) for x in p)):
                raise r.fail(key, "point must be [x, y, z] (finite numbers)")
        else:
            raise r.fail(key, "must be a name, { box = [[..],[..]] } or { point = [x,y,z] }")
    elif not isinstance(spec, str):
        raise r.fail(key, "must be a name, { box = [[..],[..]] } or { point = [x,y,z] }")
    try:
        return resolve_region(mesh, spec, where=f"{r.file}: {r._key(key)}")
    except InputError as exc:
        raise SceneError(str(exc)) from None


def parse_boundary(r: TableReader, mesh: TetMesh) -> Boundary:
    """One ``[[boundary]]``: a region with ``fix`` components and/or a ``displacement``.

    Parameters
    ----------
    r
        Reader over the ``[[boundary]]`` table; every error names the file and key.
    mesh
        The scene's mesh (regions and probes are resolved on it).

    Returns
    -------
    Boundary
    """
    region = parse_region(r, mesh)
    if r.has("fix"):
        fix = r.t["fix"]
        r.used.add("fix")
        if not isinstance(fix, list) or not fix or not all(c in COMPONENTS for c in fix):
            raise r.fail("fix", f'must be a non-empty list of "x", "y", "z", got {_show(fix)}')
        comps = tuple(sorted({COMPONENTS.index(c) for c in fix}))
    else:
        comps = (0, 1, 2)
    if r.has("displacement"):
        value = r.get("displacement", "vec", length=3)
    elif r.has("fix"):
        value = np.zeros(3)
    else:
        raise r.fail("fix", "a boundary needs fix = [...] or displacement = [dx, dy, dz]")
    r.finish()
    return Boundary(region=region, components=comps, value=value)


def parse_load(r: TableReader, mesh: TetMesh) -> Load:
    """One ``[[load]]``: a traction, pressure, gravity or force.

    Parameters
    ----------
    r
        Reader over the ``[[load]]`` table; every error names the file and key.
    mesh
        The scene's mesh (regions and probes are resolved on it).

    Returns
    -------
    Load
        With its time function (``time``, :mod:`springfem.scene.load_time`), if any.
    """
    time = None
    if r.has("time"):  # read first: the scene-key reference reaches its keys this way
        r.used.add("time")
        time = parse_time_table(TableReader(r.t["time"], r._key("time"), r.file, keys=TIME_KEYS))
    kind = r.get("type", "str", choices=LOAD_TYPES)
    if kind == "pressure":
        value = np.array([r.get("value", "float")])
    else:
        value = r.get("value", "vec", length=3)
    region = None
    if kind != "gravity":
        region = parse_region(r, mesh)
        if kind in ("traction", "pressure") and region.facets.size == 0:
            raise r.fail("region", f"{region.name} contains no boundary facets for a {kind}")
        spec = r.t.get("region")
        if kind in ("traction", "pressure") and isinstance(spec, str):
            if spec in mesh.cell_sets and spec not in mesh.facet_sets:
                mesh.notes.append(_volume_region_note(r, mesh, region, kind))
    r.finish()
    return Load(type=kind, value=value, region=region, time=time)


def _volume_region_note(r: TableReader, mesh: TetMesh, region: Region, kind: str) -> str:
    """What a surface load on a volume (cell-set) region acts on, in one line."""
    from ..regions import facet_areas_normals

    area = float(facet_areas_normals(mesh.points, region.facets)[0].sum())
    closed = len(region.facets) == len(mesh.boundary_facets())
    line = (
        f"{r.file}: {r._key('region')}: {region.name} is a volume region; the {kind} acts on "
        f"the {len(region.facets)} boundary facets of its cells (area {area:.4g})"
    )
    if closed:
        line += ": the whole closed surface, so its net force is zero"
    return line


def parse_probe(r: TableReader, mesh: TetMesh) -> Probe:
    """One ``[[probe]]``: a named point inside the mesh (or within :data:`SNAP_DISTANCE` of
    an element outside it: snapped to the nearest boundary point, with a note on the mesh).

    Parameters
    ----------
    r
        Reader over the ``[[probe]]`` table; every error names the file and key.
    mesh
        The scene's mesh (regions and probes are resolved on it).

    Returns
    -------
    Probe
    """
    name = r.get("name", "str")
    point = r.get("point", "vec", length=3)
    r.finish()
    tet, bary = locate_points(mesh.points, mesh.tets, point[None])
    if tet[0] >= 0:
        return Probe(name=name, point=point, tet=int(tet[0]), bary=bary[0])
    near = nearest_boundary_point(mesh, point)
    if near.distance <= SNAP_DISTANCE * near.size:  # a curved surface's faceted mesh
        mesh.notes.append(
            f"{r.file}: probe {_show(name)} at {point.tolist()} is {near.distance:.3g} outside "
            f"the mesh (element size {near.size:.3g}): snapped to the nearest boundary point "
            f"{np.round(near.point, 12).tolist()}"
        )
        return Probe(name=name, point=near.point, tet=near.tet, bary=near.bary)
    lo, hi = mesh.bounding_box()
    raise r.fail(
        "point",
        f"probe {_show(name)} at {point.tolist()} is outside the mesh, {near.distance:.3g} "
        f"from its surface (more than {SNAP_DISTANCE:g} of an element, {near.size:.3g}; "
        f"bounding box {lo.tolist()} – {hi.tolist()})",
    )
