"""Mesh files through meshio: read (tets kept, named sets and cell data carried), write VTU.

Examples
--------
>>> import meshio, numpy as np
>>> m = mesh_from_meshio(meshio.Mesh(np.eye(4)[:, :3], [("tetra", [[3, 0, 1, 2]])]))
>>> m.n_tets, m.notes
(1, [])
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..errors import MeshError
from .tetmesh import TetMesh
from .validate import validate_mesh

_TET_TYPES = {"tetra": 4, "tetra10": 10}
_TRI_TYPES = {"triangle": 3, "triangle6": 6}


def read_mesh(path: str | os.PathLike, scale: float = 1.0) -> TetMesh:
    """Read a tetrahedral mesh with meshio, scale its coordinates and validate it.

    Tets (``tetra``, or ``tetra10`` reduced to its corners) are kept; lower-dimensional
    cells (vertices, lines, triangles, quads) are dropped with a note, except triangles,
    which become named boundary facet sets when a gmsh physical group or cell set names
    them. Other volume cells (hexahedra, wedges, pyramids …) are dropped too, and the note
    says so and that the body lost that part (split them into tets in the meshing tool to
    keep it). Node sets (``point_sets``) and tet cell sets
    become named regions; per-tet cell data (e.g. ``fiber``) is kept.

    Parameters
    ----------
    path
        Any file meshio reads (``.msh``, ``.vtu``, ``.vtk``, ``.mesh``, …).
    scale
        Factor on the coordinates (e.g. ``1e-3`` for a file in millimetres).

    Returns
    -------
    TetMesh
        Validated (:func:`~springfem.mesh.validate_mesh`), with what was dropped or
        repaired in ``notes``.

    Raises
    ------
    MeshError
        If the file can't be read or holds no usable tets.
    """
    import meshio

    path = os.fspath(path)
    if not os.path.isfile(path):
        raise MeshError(f"mesh file {path} does not exist")
    import contextlib
    import io

    chatter = io.StringIO()
    try:
        # meshio prints to stderr and may call sys.exit on unreadable files
        with contextlib.redirect_stderr(chatter), contextlib.redirect_stdout(chatter):
            m = meshio.read(path)
    except (Exception, SystemExit) as exc:  # meshio raises many types; report one line
        text = str(exc).strip() if not isinstance(exc, SystemExit) else chatter.getvalue()
        text = " ".join(text.split()) or type(exc).__name__
        text = text if len(text) <= 200 else text[:199] + "…"
        raise MeshError(f"mesh file {path} could not be read: {text}") from None
    return mesh_from_meshio(m, path, scale=scale)


#: meshio cell types that fill a volume (besides tets): dropped with a warning note.
_VOLUME_TYPES: tuple[str, ...] = (
    *("hexahedron", "wedge", "pyramid", "hexahedron20", "hexahedron27", "wedge15"),
    *("pyramid13", "pyramid14", "wedge18", "hexahedron24", "polyhedron", "VTK_LAGRANGE"),
)


def mesh_from_meshio(m, name: str = "mesh", scale: float = 1.0) -> TetMesh:
    """Build a validated :class:`TetMesh` from a ``meshio.Mesh`` (see :func:`read_mesh`).

    Parameters
    ----------
    m
        The ``meshio.Mesh``.
    name
        What to call it in notes and errors (the file name).
    scale
        Factor on the coordinates.

    Returns
    -------
    TetMesh
    """
    try:
        pts = np.asarray(m.points, dtype=np.float64) * scale
    except (TypeError, ValueError) as exc:
        raise MeshError(f"{name}: node coordinates are not numbers ({exc})") from None
    if pts.ndim != 2 or pts.shape[0] == 0:
        raise MeshError(f"{name}: contains no nodes")
    if pts.shape[1] == 2:
        raise MeshError(f"{name}: is two-dimensional; a tetrahedral mesh is needed")
    pts = pts[:, :3]
    tet_blocks: list[tuple[int, np.ndarray]] = []  # (block index, connectivity)
    tri_blocks: list[tuple[int, np.ndarray]] = []
    dropped: dict[str, int] = {}
    volume: dict[str, int] = {}
    for block in m.cells:
        if block.type.startswith(_VOLUME_TYPES):
            volume[block.type] = volume.get(block.type, 0) + len(block.data)
    for b, block in enumerate(m.cells):
        if block.type in _TET_TYPES:
            tet_blocks.append((b, np.asarray(block.data)[:, :4]))
            if block.type == "tetra10":
                dropped["tetra10 mid-edge nodes"] = dropped.get("tetra10 mid-edge nodes", 0) + 1
        elif block.type in _TRI_TYPES:
            tri_blocks.append((b, np.asarray(block.data)[:, :3]))
        else:
            dropped[block.type] = dropped.get(block.type, 0) + len(block.data)
    if not tet_blocks:
        kinds = ", ".join(sorted({c.type for c in m.cells})) or "none"
        raise MeshError(f"{name}: contains no tetrahedra (cell types: {kinds})")
    tets = np.concatenate([t for _, t in tet_blocks]).astype(np.int64)
    offsets = np.cumsum([0] + [len(t) for _, t in tet_blocks])
    block_offset = {b: int(o) for (b, _), o in zip(tet_blocks, offsets)}
    cell_sets: dict[str, np.ndarray] = {}
    facet_sets: dict[str, np.ndarray] = {}
    for set_name, per_block in getattr(m, "cell_sets", {}).items():
        if set_name.startswith("gmsh:"):
            continue  # meshio's own bookkeeping (gmsh:bounding_entities holds entity tags)
        tet_ids, tris = [], []
        for b, ids in enumerate(per_block):
            if ids is None or len(ids) == 0:
                continue
            ids = np.asarray(ids, dtype=np.int64)
            if b in block_offset:
                tet_ids.append(ids + block_offset[b])
            else:
                for bb, data in tri_blocks:
                    if bb == b:
                        tris.append(data[ids])
        if tet_ids:
            cell_sets[set_name] = np.concatenate(tet_ids)
        if tris:
            facet_sets[set_name] = np.concatenate(tris).astype(np.int64)
    # gmsh physical tags without names: expose as "tag:<n>"
    phys = m.cell_data.get("gmsh:physical")
    if phys is not None:
        names_by_tag = {}
        for nm, (tag, _dim) in getattr(m, "field_data", {}).items():
            names_by_tag[int(tag)] = nm
        for b, tags in enumerate(phys):
            tags = np.asarray(tags).astype(np.int64)
            for tag in np.unique(tags):
                nm = names_by_tag.get(int(tag), f"tag:{int(tag)}")
                ids = np.flatnonzero(tags == tag)
                if b in block_offset:
                    cell_sets.setdefault(nm, ids + block_offset[b])
                else:
                    for bb, data in tri_blocks:
                        if bb == b:
                            facet_sets.setdefault(nm, data[ids].astype(np.int64))
    region = m.cell_data.get(REGION_FIELD)
    if region is not None and phys is None:
        # springfem's own VTU: tet region ids named by the FieldData table
        names_by_id = {int(np.ravel(v)[0]): nm for nm, v in getattr(m, "field_data", {}).items()}
        for b, _ in tet_blocks:
            ids_b = np.asarray(region[b]).astype(np.int64)
            for rid in np.unique(ids_b[ids_b > 0]):
                nm = names_by_id.get(int(rid), f"region:{int(rid)}")
                cell_sets.setdefault(nm, np.flatnonzero(ids_b == rid) + block_offset[b])
    cell_data: dict[str, np.ndarray] = {}
    for key, per_block in m.cell_data.items():
        if key.startswith("gmsh:") or key.startswith("medit:") or key == REGION_FIELD:
            continue
        arrays = [np.asarray(per_block[b]) for b, _ in tet_blocks]
        try:
            cell_data[key] = np.concatenate(arrays).astype(np.float64)
        except (ValueError, TypeError):
            continue
    node_sets = {k: np.asarray(v, dtype=np.int64) for k, v in getattr(m, "point_sets", {}).items()}
    mesh = TetMesh(
        points=pts,
        tets=tets,
        node_sets=node_sets,
        cell_sets=cell_sets,
        facet_sets=facet_sets,
        cell_data=cell_data,
        source=name,
    )
    if dropped:
        what = ", ".join(f"{n} {k}" for k, n in sorted(dropped.items()))
        warn = (
            "; the dropped volume cells are missing from the body (split them into tets in "
            "the meshing tool to keep them)"
            if volume
            else ""
        )
        mesh.notes.append(f"{name}: kept {len(tets)} tets, dropped {what}{warn}")
    return validate_mesh(mesh, name)


def write_vtu(
    path: str | os.PathLike,
    mesh: TetMesh,
    point_data: dict[str, np.ndarray] | None = None,
    cell_data: dict[str, np.ndarray] | None = None,
) -> None:
    """Write the mesh with point and cell data as VTU, atomically (temp file + rename).

    Parameters
    ----------
    path
        The ``.vtu`` file.
    mesh
        The mesh.
    point_data
        Name -> per-node array (first axis ``n``).
    cell_data
        Name -> per-tet array (first axis ``m``).

    Returns
    -------
    None
        The file is written; named regions are added as the ``region`` cell field, with
        their names in its FieldData.
    """
    import meshio

    path = os.fspath(path)
    cdata = {k: [np.asarray(v)] for k, v in (cell_data or {}).items()}
    table = region_table(mesh)
    if table and REGION_FIELD not in cdata:
        ids = np.zeros(mesh.n_tets, dtype=np.int32)
        for name, rid in table.items():
            ids[np.asarray(mesh.cell_sets[name], dtype=np.int64)] = rid
        cdata[REGION_FIELD] = [ids]
    out = meshio.Mesh(
        mesh.points,
        [("tetra", mesh.tets)],
        point_data={k: np.asarray(v) for k, v in (point_data or {}).items()},
        cell_data=cdata,
    )
    tmp = f"{path}.tmp-{os.getpid()}.vtu"
    meshio.write(tmp, out, file_format="vtu")
    if table and REGION_FIELD in cdata:
        _add_field_data(tmp, table)
    os.replace(tmp, path)


#: Cell data of a written VTU: the id of each tet's region (0: none), named in its FieldData.
REGION_FIELD = "region"


def region_table(mesh: TetMesh) -> dict[str, int]:
    """Region name -> id (1, 2, … in name order) of the mesh's tet sets.

    A tet in several sets gets the id of the last (in name order) in the ``region`` cell
    data; each set is still named in the table.

    Parameters
    ----------
    mesh
        The mesh.

    Returns
    -------
    dict
    """
    return {name: i + 1 for i, name in enumerate(sorted(mesh.cell_sets))}


def _add_field_data(path: str, table: dict[str, int]) -> None:
    """Insert a VTK ``<FieldData>`` with one Int32 array per region name (its id).

    meshio does not write field data to VTU but reads it back (as ParaView does), so the
    names survive a round trip: ``field_data = {name: [id]}``, gmsh's convention.
    """
    from xml.sax.saxutils import quoteattr

    text = Path(path).read_text(encoding="utf-8")
    rows = "".join(
        f'<DataArray type="Int32" Name={quoteattr(name)} NumberOfTuples="1" '
        f'format="ascii">{rid}</DataArray>\n'
        for name, rid in table.items()
    )
    i = text.index("<Piece")
    Path(path).write_text(text[:i] + f"<FieldData>\n{rows}</FieldData>\n" + text[i:],
                          encoding="utf-8")  # fmt: skip
