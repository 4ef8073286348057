"""Scene files: the issue's cantilever loads unchanged; malformed scenes name the key."""

from pathlib import Path

import meshio
import numpy as np
import pytest

import reference_fem  # noqa: F401  (registers the [fem] section, validated on load)
import springmodel  # noqa: F401  (registers the [spring] section)
from springfem.errors import SceneError
from springfem.mesh import box_mesh
from springfem.scene import load_scene, parse_scene

SCENES = Path(__file__).resolve().parents[2] / "studies" / "scenes"

BASE = """
name = "t"
[mesh]
generator = "box"
size = [1.0, 1.0, 1.0]
divisions = [2, 2, 2]
[material]
law = "linear"
E = 1.0e3
nu = 0.3
[[boundary]]
region = "x_min"
fix = ["x", "y", "z"]
"""


def test_cantilever_scene_loads():
    s = load_scene(SCENES / "cantilever.toml")
    assert s.name == "cantilever"
    assert (s.mesh.n_points, s.mesh.n_tets) == (1025, 3840)
    assert s.mesh.volumes().sum() == pytest.approx(1e-5, rel=1e-12)
    assert s.material.E == 1e4 and s.material.nu == 0.3
    np.testing.assert_allclose(s.frames[:, 0], np.tile([1.0, 0, 0], (3840, 1)), atol=1e-15)
    dofs, vals = s.dirichlet()
    assert len(dofs) == 3 * 25 and not vals.any()
    (p,) = s.probes
    # the tip probe interpolates the position of the point itself exactly
    np.testing.assert_allclose(p.bary @ s.mesh.points[s.mesh.tets[p.tet]], [0.1, 0.005, 0.005])


@pytest.mark.parametrize("path", sorted(SCENES.glob("*.toml")), ids=lambda p: p.stem)
def test_bundled_scenes_load(path):
    s = load_scene(path)
    assert s.mesh.n_tets > 0 and len(s.boundaries) > 0


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda t: t.replace("E = 1.0e3", 'E = "soft"'), "material.E: must be a number"),
        (lambda t: t.replace("E = 1.0e3", "E = -1.0"), "material.E: must be positive"),
        (lambda t: t.replace("nu = 0.3", "nu = 0.5"), "material.nu: must lie in"),
        (lambda t: t.replace("nu = 0.3", "nu = nan"), "material.nu: must be finite"),
        (
            lambda t: t.replace('law = "linear"', 'law = "rubber"'),
            "material.law: 'rubber' is not one of",
        ),
        (lambda t: t + '\n[spring]\ntorsion = "twisty"\n', "spring.torsion: 'twisty'"),
        (lambda t: t + "\n[spring]\nbogus = 1\n", "spring.bogus: unknown key"),
        (
            lambda t: t.replace("[material]", "[material]\ncolour = 1"),
            "material.colour: unknown key",
        ),
        (
            lambda t: t.replace("size = [1.0, 1.0, 1.0]", "size = [1.0, 1.0]"),
            "mesh.size: must be a list of 3 numbers",
        ),
        (
            lambda t: t.replace("divisions = [2, 2, 2]", "divisions = [2, 0, 2]"),
            "mesh.divisions: entries must be positive",
        ),
        (
            lambda t: t.replace('region = "x_min"', 'region = "left"'),
            "boundary\\[0\\].region: unknown region 'left'",
        ),
        (
            lambda t: t.replace('fix = ["x", "y", "z"]', 'fix = ["w"]'),
            "boundary\\[0\\].fix: must be a non-empty list",
        ),
        (
            lambda t: t + '\n[[probe]]\nname = "p"\npoint = [5.0, 0.0, 0.0]\n',
            "probe\\[0\\].point: probe 'p' at \\[5.0, 0.0, 0.0\\] is outside the mesh",
        ),
        (
            lambda t: (
                t + '\n[[load]]\ntype = "traction"\nregion = { point = [1.0, 1.0, 1.0] }'
                "\nvalue = [1.0, 0.0, 0.0]\n"
            ),
            "contains no boundary facets",
        ),
        (
            lambda t: (
                t + '\n[[load]]\ntype = "traction"\nregion = { box = [[2.0, 2.0, 2.0],'
                " [3.0, 3.0, 3.0]] }\nvalue = [1.0, 0.0, 0.0]\n"
            ),
            "selects no nodes",
        ),
        (
            lambda t: t.replace("[material]", "[materials]"),
            "\\[materials\\]: unknown section; did you mean \\[material\\]\\?",
        ),
        (
            lambda t: t.replace("divisions = [2, 2, 2]", "divisions = [10000, 10000, 10000]"),
            "would need about",
        ),
        (lambda t: t + "\n[axes]\nfiber = [1.0, 0.0, 0.0]\nsheet = [2.0, 0.0, 0.0]\n", "axes"),
        (lambda t: t + "\nunknown = 3\n", "unknown: unknown key"),
        (lambda t: t + "\n[[load]\n", "not valid TOML"),
    ],
)
def test_malformed_scenes_name_the_key(edit, message):
    with pytest.raises(SceneError, match=message) as info:
        parse_scene(edit(BASE), path="bad.toml")
    assert "\n" not in str(info.value)
    assert str(info.value).startswith("bad.toml: ")


def test_mesh_file_relative_to_scene_with_cell_fibers(tmp_path):
    m = box_mesh((1.0, 1.0, 1.0), (2, 2, 2))
    rng = np.random.default_rng(0)
    fib = rng.normal(size=(m.n_tets, 3))
    (tmp_path / "meshes").mkdir()
    meshio.write(
        tmp_path / "meshes" / "m.vtu",
        meshio.Mesh(m.points, [("tetra", m.tets)], cell_data={"fiber": [fib]}),
    )
    text = (
        BASE.replace(
            'generator = "box"\nsize = [1.0, 1.0, 1.0]\ndivisions = [2, 2, 2]',
            'file = "meshes/m.vtu"',
        )
        + '\n[axes]\ntype = "cells"\n'
    )
    (tmp_path / "s.toml").write_text(text)
    s = load_scene(tmp_path / "s.toml")
    expected = fib / np.linalg.norm(fib, axis=1, keepdims=True)
    np.testing.assert_allclose(s.frames[:, 0], expected, atol=1e-12)


def test_mu_kappa_and_prescribed_displacement():
    text = BASE.replace("E = 1.0e3\nnu = 0.3", "mu = 100.0\nkappa = 1000.0").replace(
        'law = "linear"', 'law = "neo-hookean"\nformulation = "uncoupled"'
    )
    text += '\n[[boundary]]\nregion = "x_max"\ndisplacement = [0.1, 0.0, 0.0]\nfix = ["x"]\n'
    s = parse_scene(text)
    assert s.material.mu == pytest.approx(100.0)
    assert s.material.kappa == pytest.approx(1000.0)
    dofs, vals = s.dirichlet()
    right = s.boundaries[1].region.nodes
    assert set(right * 3) <= set(dofs)
    assert vals[np.isin(dofs, right * 3)] == pytest.approx(0.1)
    assert not np.isin(right * 3 + 1, dofs).any()


def test_scene_never_executes_code(tmp_path):
    marker = tmp_path / "pwned"
    text = BASE.replace('name = "t"', f"name = \"__import__('os').mkdir('{marker}')\"")
    s = parse_scene(text)
    assert not marker.exists() and s.name.startswith("__import__")
