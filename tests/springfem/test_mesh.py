"""Mesh generators, validation and meshio round trips."""

import meshio
import numpy as np
import pytest

from springfem.errors import MeshError
from springfem.mesh import (
    TetMesh,
    boundary_facets,
    box_mesh,
    mean_ratio_quality,
    read_mesh,
    validate_mesh,
    write_vtu,
)

SPLITS = ["five", "six", "five-mirrored", "six-mirrored"]


@pytest.mark.parametrize("split", SPLITS)
def test_box_volume_counts_and_conformity(split):
    size, div = (0.3, 0.2, 0.1), (3, 4, 2)
    m = box_mesh(size, div, split)
    per_hex = 6 if split.startswith("six") else 5
    assert m.n_points == 4 * 5 * 3
    assert m.n_tets == per_hex * 3 * 4 * 2
    v = m.volumes()
    assert (v > 0).all()
    assert v.sum() == pytest.approx(np.prod(size), rel=1e-13)
    # conforming: the boundary is exactly the box surface, 2 triangles per face quad
    bf = m.boundary_facets()
    n_quads = 2 * (3 * 4 + 4 * 2 + 3 * 2)
    assert len(bf) == 2 * n_quads
    # outward normals: divergence theorem, sum(n_x x_c A) equals the volume
    x = m.points[bf]
    a = 0.5 * np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    assert (a[:, 0] * x.mean(1)[:, 0]).sum() == pytest.approx(np.prod(size), rel=1e-12)
    assert np.abs(a.sum(0)).max() < 1e-15


def test_mirrored_six_is_symmetric():
    """The mirrored split is invariant under reflection through the box centre planes."""
    m = box_mesh((2.0, 2.0, 2.0), (2, 2, 2), "six-mirrored")
    key = {tuple(sorted(map(tuple, np.round(m.points[t], 9)))) for t in m.tets}
    mirrored = {tuple(sorted((2 - a, b, c) for a, b, c in t)) for t in key}
    assert key == {tuple(sorted(t)) for t in mirrored}
    plain = box_mesh((2.0, 2.0, 2.0), (2, 2, 2), "six")
    key2 = {tuple(sorted(map(tuple, np.round(plain.points[t], 9)))) for t in plain.tets}
    mirrored2 = {tuple(sorted((2 - a, b, c) for a, b, c in t)) for t in key2}
    assert key2 != mirrored2


def test_quality_of_regular_tet_is_one():
    p = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], float)
    assert mean_ratio_quality(p, np.array([[0, 1, 2, 3]]))[0] == pytest.approx(1.0)
    flat = p.copy()
    flat[3] = (p[0] + p[1] + p[2]) / 3 + 1e-6
    assert mean_ratio_quality(flat, np.array([[0, 1, 2, 3]]))[0] < 1e-3


def _one_tet():
    return np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]), np.array([[0, 1, 2, 3]])


def test_inverted_tets_are_reoriented():
    p, t = _one_tet()
    m = validate_mesh(TetMesh(p, t[:, [0, 2, 1, 3]]))
    assert m.volumes()[0] == pytest.approx(1 / 6)
    assert any("reoriented 1 inverted" in n for n in m.notes)


@pytest.mark.parametrize(
    "mutate, message",
    [
        (
            lambda p, t: (np.vstack([p, [[np.nan, 0, 0]]]), np.vstack([t, [[0, 1, 2, 4]]])),
            "non-finite coordinates at nodes 4",
        ),
        (lambda p, t: (p, np.vstack([t, t[:, [1, 0, 2, 3]]])), "duplicate tets 0, 1"),
        (
            lambda p, t: (np.vstack([p, [[0.5, 0.5, 0]]]), np.vstack([t, [[0, 1, 2, 4]]])),
            "zero-volume tets 1",
        ),
        (lambda p, t: (p, np.array([[0, 1, 2, 2]])), "zero-volume tets 0"),
        (lambda p, t: (p, np.array([[0, 1, 2, 7]])), "reference nodes that do not exist"),
        (
            lambda p, t: (np.vstack([p, [[1, 0, 0]]]), np.vstack([t, [[4, 2, 3, 0]]])),
            "duplicate nodes",
        ),
    ],
)
def test_bad_meshes_are_rejected_with_ids(mutate, message):
    p, t = mutate(*_one_tet())
    with pytest.raises(MeshError, match=message.replace("(", r"\(")):
        validate_mesh(TetMesh(p, t), "bad.vtu")


def test_unreferenced_nodes_are_removed():
    p, t = _one_tet()
    p = np.vstack([[9, 9, 9], p])
    m = validate_mesh(TetMesh(p, t + 1))
    assert m.n_points == 4 and m.tets.max() == 3
    assert any("removed 1 nodes" in n for n in m.notes)


@pytest.mark.parametrize("split", SPLITS)
@pytest.mark.parametrize("ext", ["vtu", "vtk", "msh", "mesh", "inp"])
def test_round_trip(tmp_path, split, ext):
    m = box_mesh((1.0, 2.0, 3.0), (2, 2, 1), split)
    path = tmp_path / f"m.{ext}"
    if ext == "vtu":
        write_vtu(path, m, point_data={"u": m.points}, cell_data={"q": m.quality()})
    else:
        kw = {"file_format": "gmsh22", "binary": False} if ext == "msh" else {}
        meshio.write(path, meshio.Mesh(m.points, [("tetra", m.tets)]), **kw)
    r = read_mesh(path)
    np.testing.assert_allclose(r.points, m.points, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(np.sort(r.tets, 1), np.sort(m.tets, 1))


def test_gmsh_physical_groups_become_regions_and_triangles_facets(tmp_path):
    m = box_mesh((1.0, 1.0, 1.0), (2, 2, 2), "six")
    bf = boundary_facets(m.tets)
    on_x0 = np.isclose(m.points[bf][:, :, 0], 0).all(1)
    tris = bf[on_x0]
    mm = meshio.Mesh(
        m.points,
        [("triangle", tris), ("tetra", m.tets), ("vertex", np.array([[0]]))],
        cell_data={
            "gmsh:physical": [np.full(len(tris), 7), np.full(m.n_tets, 3), np.array([1])],
            "gmsh:geometrical": [np.full(len(tris), 1), np.full(m.n_tets, 1), np.array([1])],
        },
        field_data={"left": np.array([7, 2]), "body": np.array([3, 3])},
    )
    path = tmp_path / "g.msh"
    meshio.write(path, mm, file_format="gmsh22", binary=False)
    r = read_mesh(path)
    assert len(r.facet_sets["left"]) == len(tris)
    assert len(r.cell_sets["body"]) == m.n_tets
    assert any("dropped 1 vertex" in n for n in r.notes)


def test_tetra10_is_reduced_to_corners(tmp_path):
    p, t = _one_tet()
    mids = [(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)]
    pts = np.vstack([p, [(p[a] + p[b]) / 2 for a, b in mids]])
    path = tmp_path / "q.vtu"
    meshio.write(path, meshio.Mesh(pts, [("tetra10", np.arange(10)[None])]))
    r = read_mesh(path)
    assert r.n_points == 4 and r.n_tets == 1


def test_unreadable_and_tetless_files(tmp_path):
    with pytest.raises(MeshError, match="does not exist"):
        read_mesh(tmp_path / "nope.vtu")
    bad = tmp_path / "bad.vtu"
    bad.write_text("this is not a mesh")
    with pytest.raises(MeshError, match="could not be read"):
        read_mesh(bad)
    tri = tmp_path / "tri.vtu"
    meshio.write(tri, meshio.Mesh(np.eye(3), [("triangle", np.array([[0, 1, 2]]))]))
    with pytest.raises(MeshError, match="contains no tetrahedra"):
        read_mesh(tri)


def test_delaunay_box_is_unstructured_and_fills_the_box_exactly():
    """split = "delaunay": the box's volume exactly, faces kept planar, no axis-aligned
    hexahedral pattern (tets per cell not a constant), seeded (same mesh twice)."""
    from springfem.mesh import box_mesh
    from springfem.regions import resolve_region
    from springfem.scene import scene_from_dict

    size, div = (2.0, 1.0, 0.5), (8, 4, 2)
    m = box_mesh(size, div, "delaunay", origin=(1.0, -1.0, 0.0), jitter=0.3, seed=4)
    V = m.volumes()
    assert (V > 0).all() and abs(V.sum() - 1.0) < 1e-12
    lo, hi = m.points.min(axis=0), m.points.max(axis=0)
    np.testing.assert_allclose(lo, [1.0, -1.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(hi, [3.0, 0.0, 0.5], atol=1e-15)
    h = np.array(size) / np.array(div)
    interior = np.all((m.points > lo + 1e-9) & (m.points < hi - 1e-9), axis=1)
    grid = np.array([1.0, -1.0, 0.0]) + np.round((m.points - [1.0, -1.0, 0.0]) / h) * h
    assert np.abs(m.points[interior] - grid[interior]).max() > 0.1 * h.min()  # moved
    again = box_mesh(size, div, "delaunay", origin=(1.0, -1.0, 0.0), jitter=0.3, seed=4)
    assert np.array_equal(again.tets, m.tets)
    scene = scene_from_dict({
        "mesh": {"generator": "box", "size": list(size), "divisions": list(div),
                 "split": "delaunay", "seed": 4, "origin": [1.0, -1.0, 0.0]},
        "material": {"law": "linear", "E": 1.0, "nu": 0.3},
    })  # fmt: skip
    assert np.array_equal(scene.mesh.tets, m.tets)
    # the x_max face's nodes all lie on the plane x = 3 (faces move within themselves)
    x_max = resolve_region(scene.mesh, "x_max").nodes
    assert x_max.size >= (div[1] + 1) * (div[2] + 1)
    assert np.allclose(m.points[x_max][:, 0], 3.0)


def test_delaunay_keys_are_refused_on_a_structured_split():
    from springfem.errors import SceneError
    from springfem.scene import scene_from_dict

    mesh = {"generator": "box", "size": [1, 1, 1], "divisions": [2, 2, 2], "jitter": 0.2}
    table = {"mesh": mesh, "material": {"law": "linear", "E": 1.0, "nu": 0.3}}
    with pytest.raises(SceneError, match='mesh.jitter: applies to split = "delaunay" only'):
        scene_from_dict(table)
