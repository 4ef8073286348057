"""Reliability: resource limits, output paths that stay put, scene files that stay data.

* A scene that needs more memory than the machine has is refused before anything is
  built, with the estimate (exit 2). Generated boxes are checked from their divisions. A
  mesh file can't be sized without reading it (its header formats differ and some have
  none), so it is checked right after reading: reading needs a small fraction of what the
  solvers need.
* The scene ``name`` becomes part of default output paths (``out/<name>-<model>``,
  ``out/compare-<name>``): whatever it holds, those paths stay inside ``out``.
* Scene files never execute code, and loading one never writes anything.
"""

from __future__ import annotations

import ast
import os
from pathlib import Path

import meshio
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import springfem.scene.limits as limits
from springfem.errors import SceneError
from springfem.files import safe_filename
from springfem.mesh import box_mesh
from springfem.scene import BYTES_PER_TET, load_scene, machine_memory, parse_scene
from studies.cli import main

ROOT = Path(__file__).resolve().parents[2]

SMALL = """\
name = {name}
[mesh]
generator = "box"
size = [0.04, 0.01, 0.01]
divisions = {divisions}
[material]
law = "linear"
E = 1.0e4
nu = 0.3
[[boundary]]
region = "x_min"
fix = ["x", "y", "z"]
[[load]]
type = "traction"
region = "x_max"
value = [0.0, 0.0, -0.1]
"""


def small(name='"s"', divisions="[2, 1, 1]") -> str:
    return SMALL.format(name=name, divisions=divisions)


# ------------------------------------------------------------------ memory


def test_1e8_tets_are_refused_up_front_with_the_estimate(tmp_path, capsys):
    # 1000 x 1000 x 20 hexahedra x 5 tets = 1e8 tets; building them alone would take
    # ~13 GB (points + tets), solving ~186 GiB at BYTES_PER_TET
    path = tmp_path / "huge.toml"
    path.write_text(small(divisions="[1000, 1000, 20]").replace("[mesh]", '[mesh]\nsplit = "five"'))
    assert main(["inspect", str(path)]) == 2
    err = capsys.readouterr().err
    need = 1e8 * BYTES_PER_TET / 2**30  # independent arithmetic: 186.26 GiB
    assert err.count("\n") == 1
    assert err.startswith(
        f"springfem: error: {path}: mesh.divisions: 1e+08 tets would need about {need:.3g} GiB"
    )
    mem = machine_memory()
    assert mem is not None and f"this machine has {mem / 2**30:.3g} GiB" in err


def test_solve_refuses_the_same_scene_with_exit_2(tmp_path, capsys):
    path = tmp_path / "huge.toml"
    path.write_text(small(divisions="[1000, 1000, 20]"))
    assert main(["solve", str(path), "--model", "fem", "--out", str(tmp_path / "o")]) == 2
    assert "would need about" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()  # refused before any output


def test_tet_limit_applies_on_machines_with_more_memory(monkeypatch):
    # 6 * 200^3 = 4.8e7 tets, more than MAX_TETS = 2e7, on a machine with 1 PiB
    monkeypatch.setattr(limits, "machine_memory", lambda: 2**50)
    with pytest.raises(SceneError) as info:
        parse_scene(small(divisions="[200, 200, 200]"), path="big.toml")
    assert str(info.value) == (
        "big.toml: mesh.divisions: 4.8e+07 tets would need about 89.4 GiB; "
        "the limit here is 2e+07 tets"
    )


def test_mesh_file_is_checked_after_reading(tmp_path, monkeypatch):
    m = box_mesh((1.0, 1.0, 1.0), (2, 2, 2))  # 48 tets
    meshio.write(tmp_path / "m.vtu", meshio.Mesh(m.points, [("tetra", m.tets)]))
    text = small().replace(
        'generator = "box"\nsize = [0.04, 0.01, 0.01]\ndivisions = [2, 1, 1]', 'file = "m.vtu"'
    )
    (tmp_path / "s.toml").write_text(text)
    assert load_scene(tmp_path / "s.toml").mesh.n_tets == 48
    monkeypatch.setattr(limits, "machine_memory", lambda: 48 * BYTES_PER_TET - 1)
    with pytest.raises(SceneError) as info:
        load_scene(tmp_path / "s.toml")
    assert str(info.value).startswith(f"{tmp_path / 's.toml'}: mesh.file: 48 tets would need")


# ------------------------------------------------------------------ output paths

ESCAPES = ["../../etc/x", "/abs", "..", ".", "a/../../b", "..\\..\\x", "C:/x", "x\u0000y", ""]


@pytest.mark.parametrize("name", ESCAPES)
def test_scene_name_cannot_escape_the_output_folder(tmp_path, monkeypatch, capsys, name):
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    toml_name = '"' + name.replace("\\", "\\\\").replace("\u0000", "\\u0000") + '"'
    (work / "s.toml").write_text(small(name=toml_name))
    assert main(["solve", "s.toml", "--model", "fem"]) == 0
    err = capsys.readouterr().err
    written = sorted(p for p in tmp_path.rglob("*") if p.is_file() and p.name != "s.toml")
    assert written and all(p.is_relative_to(work / "out") for p in written), written
    (folder,) = {p.parent for p in written}
    assert folder.parent == work / "out"  # exactly one level below out/
    assert folder.name == f"solve-{safe_filename(name)}-fem-p1"
    assert f"can't be part of a folder name; using {safe_filename(name)!r}" in err


@settings(max_examples=200, deadline=None, database=None, derandomize=True)
@given(name=st.text(max_size=120))
def test_any_name_gives_paths_inside_out(name):
    # the same property for every string, for both default paths (solve and compare)
    out = Path("/srv/out")
    safe = safe_filename(name)
    for path in (out / f"{safe}-spring", out / f"compare-{safe}"):
        assert Path(os.path.normpath(path)).parent == out
    assert safe and "/" not in safe and "\\" not in safe and not safe.startswith(".")
    assert safe.isprintable() and len(safe) <= 80


def test_plain_names_are_kept():
    for name in ("cantilever", "stretch-fiber", "Liver (coarse) v2.1", "é_ü"):
        s = parse_scene(small(name=f'"{name}"'))
        assert s.name == name and s.mesh.notes == []


# ------------------------------------------------------------------ data, not code

#: Calls that would turn scene text into code or objects.
FORBIDDEN = {"eval", "exec", "compile", "__import__", "import_module"}
FORBIDDEN_MODULES = {"pickle", "marshal", "shelve", "yaml", "runpy", "importlib"}


@pytest.mark.parametrize(
    "module",
    [
        *sorted(f"springfem/scene/{p.name}" for p in (ROOT / "springfem/scene").glob("*.py")),
        "springfem/regions.py",
        *sorted(f"springfem/mesh/{p.name}" for p in (ROOT / "springfem/mesh").glob("*.py")),
        "springfem/axes.py",
        "springmodel/options.py",
        "reference_fem/options.py",
    ],
)
def test_scene_loading_code_has_no_eval_exec_or_dynamic_imports(module):
    tree = ast.parse((ROOT / module).read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            f = node.func
            name = f.id if isinstance(f, ast.Name) else getattr(f, "attr", "")
            assert name not in FORBIDDEN, f"{module}.py line {node.lineno}: {name}()"
        if isinstance(node, ast.Import | ast.ImportFrom):
            names = [a.name for a in node.names] + [getattr(node, "module", None) or ""]
            assert not {n.split(".")[0] for n in names} & FORBIDDEN_MODULES, node.lineno


def test_code_in_every_string_and_a_python_mesh_file_is_never_run(tmp_path):
    marker = tmp_path / "pwned"
    payload = f"__import__('pathlib').Path({str(marker)!r}).touch()"
    (tmp_path / "evil.py").write_text(payload + "\n")
    text = (
        small(name=f'"{payload}"')
        .replace('law = "linear"', f'law = "{payload}"')
        .replace('region = "x_min"', f'region = "{payload}"')
    )
    (tmp_path / "s.toml").write_text(text)
    with pytest.raises(SceneError, match="law"):
        load_scene(tmp_path / "s.toml")
    mesh_from_py = small().replace(
        'generator = "box"\nsize = [0.04, 0.01, 0.01]\ndivisions = [2, 1, 1]', 'file = "evil.py"'
    )
    (tmp_path / "s.toml").write_text(mesh_from_py)
    with pytest.raises(SceneError, match="could not be read"):
        load_scene(tmp_path / "s.toml")
    assert not marker.exists()


def test_loading_a_scene_writes_nothing(tmp_path):
    m = box_mesh((0.04, 0.01, 0.01), (2, 1, 1))
    fib = np.tile([1.0, 0.0, 0.0], (m.n_tets, 1))
    meshio.write(
        tmp_path / "m.vtu", meshio.Mesh(m.points, [("tetra", m.tets)], cell_data={"fiber": [fib]})
    )
    text = (
        small().replace(
            'generator = "box"\nsize = [0.04, 0.01, 0.01]\ndivisions = [2, 1, 1]', 'file = "m.vtu"'
        )
        + '[axes]\ntype = "cells"\n'
    )
    (tmp_path / "s.toml").write_text(text)
    before = {p: (p.stat().st_mtime_ns, p.stat().st_size) for p in tmp_path.rglob("*")}
    load_scene(tmp_path / "s.toml")
    after = {p: (p.stat().st_mtime_ns, p.stat().st_size) for p in tmp_path.rglob("*")}
    assert after == before
