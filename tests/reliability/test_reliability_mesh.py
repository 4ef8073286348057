"""Reliability: every mesh defect gets its own exact message (docs/contract.rst#exit-codes).

What is refused (:class:`MeshError`, exit 2) and what is repaired or reported (a note on
stderr, exit 0), decided per defect:

======================  ===========  =====================================================
defect                  outcome      why
======================  ===========  =====================================================
inverted tets           repaired     orientation is a convention; reorienting is exact
sliver tets             note         legal and solvable; they lower the stable time step
zero-volume tets        error        no shape functions, no rays: nothing to repair
coincident nodes        error        merging would change the topology the user made
disconnected parts      note         several bodies are legal; each needs its own supports
non-manifold nodes      note         parts touching at a node/edge are solvable (a hinge)
non-manifold facets     error        a triangle in three tets means overlapping tets
folded tets             error        two tets on one side of their triangle overlap
other volume cells      note         dropped; the note warns the body lost them
surface/line cells      note         boundary decoration, dropped (named triangles kept)
empty region            error        a boundary or load on nothing is a scene mistake
======================  ===========  =====================================================

The cases already covered by ``tests/test_mesh.py`` and ``tests/test_scene.py`` (inverted
tets, a node repeated in a tet, duplicate tets, unreadable files, an empty box region) are
not repeated here; these tests add the missing defects, exact messages, and the path from a
mesh file through a scene to the command line. Node and tet ids in messages are those of
the file (before unused nodes are removed).
"""

from __future__ import annotations

import meshio
import numpy as np
import pytest

from springfem.errors import InputError, MeshError, SceneError
from springfem.mesh import (
    SLIVER_QUALITY,
    TetMesh,
    box_mesh,
    mean_ratio_quality,
    read_mesh,
    validate_mesh,
)
from springfem.scene import load_scene
from studies.cli import main

CORNERS = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
TET = np.array([[0, 1, 2, 3]])


def write(path, points, cells, **kw):
    meshio.write(path, meshio.Mesh(np.asarray(points, float), cells, **kw))
    return path


def scene_for(tmp_path, mesh_file: str, extra: str = "") -> str:
    """A scene on ``mesh_file``: linear material, one fixed region, no loads."""
    return (
        f'name = "m"\n[mesh]\nfile = "{mesh_file}"\n'
        '[material]\nlaw = "linear"\nE = 1.0e3\nnu = 0.3\n' + extra
    )


# -------------------------------------------------------------- notes (exit 0)


def test_inverted_tet_in_a_file_is_reoriented_and_the_cli_says_so(tmp_path, capsys):
    # end to end: the note reaches the user on stderr, the run succeeds (exit 0)
    write(tmp_path / "inv.vtu", CORNERS, [("tetra", TET[:, [0, 2, 1, 3]])])
    (tmp_path / "s.toml").write_text(scene_for(tmp_path, "inv.vtu"))
    assert main(["inspect", str(tmp_path / "s.toml"), "--json"]) == 0
    err = capsys.readouterr().err
    assert err == f"note: {tmp_path / 'inv.vtu'}: reoriented 1 inverted tets\n"
    assert read_mesh(tmp_path / "inv.vtu").volumes()[0] == pytest.approx(1 / 6, rel=1e-15)


def test_sliver_tets_are_noted_with_their_quality():
    # a tet whose fourth node sits 1e-4 above the opposite face: positive volume, quality
    # ~1e-3 (independent check: the mean-ratio formula on the same nodes), on top of a
    # regular neighbour below the shared face
    p = np.vstack([CORNERS[:3], [[0.3, 0.3, 1e-4]], [[0.3, 0.3, -1.0]]])
    t = np.array([[0, 1, 2, 3], [0, 2, 1, 4]])
    q = mean_ratio_quality(p, t)
    assert q[0] < SLIVER_QUALITY < q[1]
    m = validate_mesh(TetMesh(p, t), "s.vtu")
    assert m.notes == [f"s.vtu: 1 sliver tet (mean-ratio quality below 0.01, worst {q[0]:.2g}): 0"]


def test_flat_tet_below_the_volume_tolerance_is_zero_volume():
    # height 1e-13 on a unit base: |V| / l^3 = 1.7e-14 < 1e-12 -> zero volume, not a sliver
    p = np.vstack([CORNERS[:3], [[0.3, 0.3, 1e-13]]])
    with pytest.raises(MeshError) as info:
        validate_mesh(TetMesh(p, TET), "f.vtu")
    assert str(info.value) == "f.vtu: zero-volume tets 0"


def test_small_well_shaped_tets_next_to_large_ones_are_accepted():
    # the zero-volume test is relative to each tet's own edges, not to the mesh extent:
    # a 1e-5 m tet in a 1 m mesh has V = 1.7e-16 m^3 < 1e-12 (extent)^3 but is perfect
    p = np.vstack([CORNERS, 2.0 + 1e-5 * CORNERS])
    t = np.array([[0, 1, 2, 3], [4, 5, 6, 7]])
    m = validate_mesh(TetMesh(p, t), "r.vtu")
    np.testing.assert_allclose(m.volumes(), [1 / 6, 1e-15 / 6], rtol=1e-9)


def test_disconnected_parts_are_noted_with_sizes_and_a_tet_of_each():
    a = box_mesh((1.0, 1.0, 1.0), (1, 1, 1))  # 6 tets
    b = box_mesh((1.0, 1.0, 1.0), (1, 1, 1), origin=(3.0, 0.0, 0.0))
    p = np.vstack([a.points, b.points])
    t = np.vstack([a.tets, b.tets + a.n_points, TET + 2 * a.n_points])
    p = np.vstack([p, CORNERS + [0.0, 5.0, 0.0]])
    m = validate_mesh(TetMesh(p, t), "d.vtu")
    assert m.notes == [
        "d.vtu: 3 disconnected parts (no shared triangle between them) of 6, 6, 1 tets, "
        "containing tets 0, 6, 12; each part needs its own boundary conditions"
    ]


def test_disconnected_part_without_support_is_a_solver_failure_naming_the_piece(tmp_path, capsys):
    # the note's advice, checked: fixing one part leaves the other free -> exit 3
    a = box_mesh((1.0, 1.0, 1.0), (1, 1, 1))
    p = np.vstack([a.points, a.points + [3.0, 0.0, 0.0]])
    t = np.vstack([a.tets, a.tets + a.n_points])
    write(tmp_path / "two.vtu", p, [("tetra", t)])
    box = "{ box = [[-0.1, -0.1, -0.1], [0.1, 1.1, 1.1]] }"
    extra = f'[[boundary]]\nregion = {box}\nfix = ["x", "y", "z"]\n'
    (tmp_path / "s.toml").write_text(scene_for(tmp_path, "two.vtu", extra))
    code = main(["solve", str(tmp_path / "s.toml"), "--model", "fem", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 3
    assert "disconnected parts" in err.splitlines()[0]  # the note came first
    assert "singular stiffness matrix (mesh piece 2 of 2)" in err.splitlines()[-1]


def test_bow_tie_parts_touching_at_one_node_are_noted():
    # two tets sharing node 3 only (point reflection through it): non-manifold node 3
    p = np.vstack([CORNERS, 2 * CORNERS[3] - CORNERS[:3]])
    t = np.array([[0, 1, 2, 3], [3, 4, 5, 6]])
    m = validate_mesh(TetMesh(p, t), "b.vtu")
    assert m.notes == [
        "b.vtu: 2 disconnected parts (no shared triangle between them) of 1, 1 tets, "
        "containing tets 0, 1; each part needs its own boundary conditions",
        "b.vtu: 1 non-manifold node (parts touch only at a node or an edge there): 3",
    ]


def test_parts_touching_along_an_edge_name_both_nodes():
    p = np.vstack([CORNERS, [[0.5, -1.0, -1.0], [0.0, -1.0, 0.0]]])
    t = np.array([[0, 1, 2, 3], [0, 1, 4, 5]])
    m = validate_mesh(TetMesh(p, t), "e.vtu")
    assert m.notes[-1] == (
        "e.vtu: 2 non-manifold nodes (parts touch only at a node or an edge there): 0, 1"
    )


def test_a_box_mesh_has_no_topology_notes():
    # the independent control: a conforming mesh is one part with manifold nodes
    for split in ("five", "six", "five-mirrored", "six-mirrored"):
        b = box_mesh((1.0, 2.0, 1.0), (2, 3, 2), split)
        assert validate_mesh(TetMesh(b.points, b.tets), "box").notes == []


# -------------------------------------------------------------- errors (exit 2)


def test_triangle_shared_by_three_tets_is_a_non_manifold_error():
    # tets 1 and 2 both lie across face (1, 2, 3) from tet 0: they overlap
    p = np.vstack([CORNERS, [[1.0, 1.0, 1.0], [0.6, 0.6, 0.6]]])
    t = np.array([[0, 1, 2, 3], [1, 2, 3, 4], [1, 2, 3, 5]])
    with pytest.raises(MeshError) as info:
        validate_mesh(TetMesh(p, t), "n.vtu")
    assert str(info.value) == (
        "n.vtu: non-manifold facets: triangle [1, 2, 3] is shared by 3 tets (0, 1, 2); "
        "1 non-manifold triangle in all (overlapping tets)"
    )


def test_coincident_nodes_in_a_file_name_both_ids(tmp_path):
    # node 4 repeats node 1; tet 1 uses the copy, so the two tets are not connected
    p = np.vstack([CORNERS, CORNERS[1], [[1.0, 1.0, 1.0]]])
    path = write(tmp_path / "dup.vtu", p, [("tetra", np.array([[0, 1, 2, 3], [4, 2, 3, 5]]))])
    with pytest.raises(MeshError) as info:
        read_mesh(path)
    assert str(info.value) == f"{path}: duplicate nodes 1, 4 (coincident coordinates; merge them)"


def test_tets_folded_onto_the_same_side_of_a_triangle_are_refused():
    # both tets lie above the shared face (0, 1, 2): they overlap, though no face is shared
    # by three tets
    p = np.vstack([CORNERS, [[0.3, 0.3, 0.5]]])
    t = np.array([[0, 1, 2, 3], [0, 1, 2, 4]])
    with pytest.raises(MeshError) as info:
        validate_mesh(TetMesh(p, t), "f.vtu")
    assert str(info.value) == (
        "f.vtu: folded mesh: tets 0 and 1 lie on the same side of their shared triangle "
        "[0, 1, 2]; 1 such triangle in all (overlapping tets)"
    )


def test_hexahedra_next_to_tets_are_dropped_with_a_warning_note(tmp_path):
    """Non-tet cells - tets are kept, and the note says what was dropped."""
    cube = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]
    p = np.vstack([cube, CORNERS + [2.0, 0.0, 0.0]])
    write(tmp_path / "mixed.vtu", p, [("tetra", TET + 8), ("hexahedron", np.arange(8)[None])])
    m = read_mesh(tmp_path / "mixed.vtu")
    assert m.n_tets == len(TET)
    assert (
        f"{tmp_path / 'mixed.vtu'}: kept {len(TET)} tets, dropped 1 hexahedron; the dropped "
        "volume cells are missing from the body (split them into tets in the meshing tool "
        "to keep them)"
    ) in m.notes


def test_lines_and_quads_are_dropped_with_a_note(tmp_path):
    path = write(
        tmp_path / "deco.vtu",
        CORNERS,
        [("tetra", TET), ("line", np.array([[0, 1], [1, 2]])), ("quad", np.array([[0, 1, 2, 3]]))],
    )
    m = read_mesh(path)
    assert m.n_tets == 1 and m.notes == [f"{path}: kept 1 tets, dropped 2 line, 1 quad"]


def test_named_region_that_selects_nothing_names_the_key():
    # a node set that exists in the mesh but is empty (mesh formats that keep empty sets)
    from springfem.regions import resolve_region

    mesh = TetMesh(CORNERS.copy(), TET.copy(), node_sets={"empty": np.array([], np.int64)})
    with pytest.raises(InputError) as info:
        resolve_region(mesh, "empty", where="s.toml: boundary[0].region")
    assert str(info.value) == "s.toml: boundary[0].region: region empty selects no nodes"


def test_box_far_from_the_mesh_selects_nothing_through_the_cli(tmp_path, capsys):
    write(tmp_path / "one.vtu", CORNERS, [("tetra", TET)])
    extra = '[[boundary]]\nregion = { box = [[5.0, 5.0, 5.0], [6.0, 6.0, 6.0]] }\nfix = ["x"]\n'
    (tmp_path / "s.toml").write_text(scene_for(tmp_path, "one.vtu", extra))
    assert main(["inspect", str(tmp_path / "s.toml")]) == 2
    err = capsys.readouterr().err
    assert err == (
        f"springfem: error: {tmp_path / 's.toml'}: boundary[0].region: region "
        "box[[5.0, 5.0, 5.0], [6.0, 6.0, 6.0]] selects no nodes\n"
    )


def test_mesh_errors_reach_the_scene_with_file_and_key(tmp_path):
    p = np.vstack([CORNERS, [[1.0, 1.0, 1.0], [0.6, 0.6, 0.6]]])
    t = np.array([[0, 1, 2, 3], [1, 2, 3, 4], [1, 2, 3, 5]])
    write(tmp_path / "n.vtu", p, [("tetra", t)])
    (tmp_path / "s.toml").write_text(scene_for(tmp_path, "n.vtu"))
    with pytest.raises(SceneError) as info:
        load_scene(tmp_path / "s.toml")
    assert str(info.value).startswith(
        f"{tmp_path / 's.toml'}: mesh.file: {tmp_path / 'n.vtu'}: non-manifold facets"
    )


def test_scaled_mesh_is_validated_after_scaling(tmp_path):
    # scale = 1e-100 on 1e-100-sized nodes: edges of 1e-200, volumes underflow to zero
    write(tmp_path / "tiny.vtu", 1e-100 * CORNERS, [("tetra", TET)])
    (tmp_path / "s.toml").write_text(
        scene_for(tmp_path, "tiny.vtu").replace('"tiny.vtu"', '"tiny.vtu"\nscale = 1e-100')
    )
    with pytest.raises(SceneError) as info:
        load_scene(tmp_path / "s.toml")
    assert str(info.value) == (
        f"{tmp_path / 's.toml'}: mesh.file: {tmp_path / 'tiny.vtu'}: zero-volume tets 0"
    )
