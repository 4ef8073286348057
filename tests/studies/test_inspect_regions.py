"""``springfem inspect`` lists the mesh file's named regions with their sizes, and names
the scene's own key when it warns of locking (docs/recipes.rst#keeping-region-names).

The sizes are checked against geometry computed independently: an unstructured gmsh box
whose volume and faces are known exactly, and a gmsh ellipsoid cut flat, whose cut is an
ellipse of known area.
"""

from __future__ import annotations

import json
import math
import os
import runpy
import sys

import pytest
from support.commands import ROOT
from support.meshes import gmsh_box

from springfem.mesh import read_mesh
from springfem.regions import named_sets
from springfem.scene import load_scene
from studies.cli import main

DIMS = (0.1, 0.02, 0.03)


def _scene(tmp_path, material: str) -> str:
    gmsh_box(tmp_path / "box.msh", 0.01, DIMS, x_faces=("clamp", "tip"))
    scene = tmp_path / "box.toml"
    scene.write_text(
        f'name = "box"\n[mesh]\nfile = "box.msh"\n[material]\n{material}\n'
        '[[boundary]]\nregion = "clamp"\nfix = ["x", "y", "z"]\n'
    )
    return str(scene)


def test_named_sets_have_the_sizes_of_the_geometry(tmp_path):
    mesh = load_scene(_scene(tmp_path, 'law = "linear"\nE = 1e4\nnu = 0.3')).mesh
    sets = {s.name: s for s in named_sets(mesh)}
    assert set(sets) == {"body", "clamp", "tip"}
    body, clamp, tip = sets["body"], sets["clamp"], sets["tip"]
    assert (body.kind, body.count, body.nodes) == ("cells", mesh.n_tets, mesh.n_points)
    # a box's volume and faces are exact on any tet mesh of it
    assert body.size == pytest.approx(DIMS[0] * DIMS[1] * DIMS[2], rel=1e-12)
    assert clamp.kind == tip.kind == "facets"
    assert clamp.size == pytest.approx(DIMS[1] * DIMS[2], rel=1e-12)
    assert tip.size == pytest.approx(DIMS[1] * DIMS[2], rel=1e-12)


def test_inspect_prints_the_regions_and_their_sizes(tmp_path, capsys):
    scene = _scene(tmp_path, 'law = "linear"\nE = 1e4\nnu = 0.3')
    assert main(["inspect", scene]) == 0
    out = capsys.readouterr().out
    assert "regions" in out and "body: " in out and "clamp: " in out
    assert f"area {DIMS[1] * DIMS[2]:.4g}" in out
    assert main(["inspect", scene, "--json"]) == 0
    regions = {r["name"]: r for r in json.loads(capsys.readouterr().out)["regions"]}
    assert regions["tip"]["kind"] == "facets"
    assert regions["body"]["size"] == pytest.approx(DIMS[0] * DIMS[1] * DIMS[2], rel=1e-12)


def test_a_generated_box_names_no_region_of_a_file(capsys):
    assert main(["inspect", "cantilever"]) == 0
    assert "none named in the mesh file" in capsys.readouterr().out


def test_the_tutorial_organ_cut_is_an_ellipse(tmp_path):
    # the tutorial's mesh (docs/tutorial/organ_mesh.py): the flat cut at x = c of the
    # ellipsoid x²/a² + y²/b² + z²/c_z² = 1 is an ellipse of area π b c_z (1 - c²/a²); the
    # inscribed polygon of a coarse mesh is a little smaller
    script = ROOT / "docs" / "tutorial" / "organ_mesh.py"
    pytest.importorskip("gmsh")
    cwd, argv = os.getcwd(), sys.argv
    os.chdir(tmp_path)
    sys.argv = [str(script), "0.006"]
    try:
        ns = runpy.run_path(str(script))
    finally:
        os.chdir(cwd)
        sys.argv = argv
    a, b, cz = ns["SEMI_AXES"]
    c = ns["CUT_X"]
    sets = {s.name: s for s in named_sets(read_mesh(tmp_path / "organ.msh"))}
    ellipse = math.pi * b * cz * (1.0 - (c / a) ** 2)
    assert 0.95 * ellipse < sets["hilum"].size < ellipse
    assert sets["organ"].kind == "cells" and sets["capsule"].kind == "facets"


@pytest.mark.parametrize(
    "material, named, not_named",
    [
        ('law = "linear"\nE = 1e4\nnu = 0.49', "nu = 0.49", None),
        ('law = "neo-hookean"\nmu = 1e4\nkappa = 5e5', "kappa = 500000 (50 mu)", "nu ="),
        ('law = "guccione"\nC = 2.0\nb_f = 8.0\nb_t = 2.0\nb_fs = 4.0\nincompressible = true',
         "incompressible = true", "nu ="),
    ],
)  # fmt: skip
def test_the_locking_warning_names_nu_only_when_the_scene_sets_it(
    tmp_path, capsys, material, named, not_named
):
    assert main(["inspect", _scene(tmp_path, material)]) == 0
    lines = [ln for ln in capsys.readouterr().err.splitlines() if "locks" in ln]
    assert lines and all(named in ln for ln in lines)
    if not_named:
        assert not any(not_named in ln for ln in lines)
