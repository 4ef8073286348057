"""Scene files: the issue's cantilever loads unchanged; malformed scenes name the key."""

from pathlib import Path

import meshio
import numpy as np
import pytest

from springfem.errors import SceneError
from springfem.mesh import box_mesh
from springfem.scene import load_scene, parse_scene, scene_from_dict

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


def base() -> dict:
    """:data:`BASE` as a dict, for :func:`scene_from_dict` (a fresh copy each call)."""
    return {
        "name": "t",
        "mesh": {"generator": "box", "size": [1.0, 1.0, 1.0], "divisions": [2, 2, 2]},
        "material": {"law": "linear", "E": 1.0e3, "nu": 0.3},
        "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
    }


def put(path: str, value):
    """An edit setting ``value`` at the dotted ``path`` (list indices as numbers)."""

    def edit(d):
        *keys, last = path.split(".")
        for k in keys:
            d = d[int(k)] if isinstance(d, list) else d.setdefault(k, {})
        d[int(last) if isinstance(d, list) else last] = value

    return edit


def add(section: str, table: dict):
    """An edit appending ``table`` to the array of tables ``section``."""
    return lambda d: d.setdefault(section, []).append(table)


def rename(old: str, new: str):
    """An edit renaming the top-level ``old`` to ``new``."""
    return lambda d: d.update({new: d.pop(old)})


TRACTION = {"type": "traction", "value": [1.0, 0.0, 0.0]}


@pytest.mark.parametrize(
    "edit, message",
    [
        (put("material.E", "soft"), "material.E: must be a number"),
        (put("material.E", -1.0), "material.E: must be positive"),
        (put("material.nu", 0.5), "material.nu: must lie in"),
        (put("material.nu", float("nan")), "material.nu: must be finite"),
        (put("material.law", "rubber"), "material.law: 'rubber' is not one of"),
        (put("spring.torsion", "twisty"), "spring.torsion: 'twisty'"),
        (put("spring.bogus", 1), "spring.bogus: unknown key"),
        (put("material.colour", 1), "material.colour: unknown key"),
        (put("mesh.size", [1.0, 1.0]), "mesh.size: must be a list of 3 numbers"),
        (put("mesh.divisions", [2, 0, 2]), "mesh.divisions: entries must be positive"),
        (put("boundary.0.region", "left"), "boundary\\[0\\].region: unknown region 'left'"),
        (put("boundary.0.fix", ["w"]), "boundary\\[0\\].fix: must be a non-empty list"),
        (
            add("probe", {"name": "p", "point": [5.0, 0.0, 0.0]}),
            "probe\\[0\\].point: probe 'p' at \\[5.0, 0.0, 0.0\\] is outside the mesh",
        ),
        (
            add("load", {**TRACTION, "region": {"point": [1.0, 1.0, 1.0]}}),
            "contains no boundary facets",
        ),
        (
            add("load", {**TRACTION, "region": {"box": [[2.0, 2.0, 2.0], [3.0, 3.0, 3.0]]}}),
            "selects no nodes",
        ),
        (
            rename("material", "materials"),
            "\\[materials\\]: unknown section; did you mean \\[material\\]\\?",
        ),
        (put("mesh.divisions", [10000, 10000, 10000]), "would need about"),
        (put("axes", {"fiber": [1.0, 0.0, 0.0], "sheet": [2.0, 0.0, 0.0]}), "axes"),
        (put("unknown", 3), "unknown: unknown key"),
    ],
)
def test_malformed_scenes_name_the_key(edit, message):
    data = base()
    edit(data)
    with pytest.raises(SceneError, match=message) as info:
        scene_from_dict(data, path="bad.toml")
    assert "\n" not in str(info.value)
    assert str(info.value).startswith("bad.toml: ")


def test_malformed_toml_is_one_line_naming_the_file():
    with pytest.raises(SceneError, match="not valid TOML") as info:
        parse_scene(BASE + "\n[[load]\n", path="bad.toml")
    assert "\n" not in str(info.value)
    assert str(info.value).startswith("bad.toml: ")


def test_the_file_and_the_dict_give_the_same_scene():
    a, b = parse_scene(BASE), scene_from_dict(base())
    assert a.name == b.name and a.material == b.material
    np.testing.assert_array_equal(a.mesh.points, b.mesh.points)
    np.testing.assert_array_equal(a.frames, b.frames)
    np.testing.assert_array_equal(a.dirichlet()[0], b.dirichlet()[0])


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
    data = base()
    data["material"] = {"law": "neo-hookean", "formulation": "uncoupled"}
    data["material"].update(mu=100.0, kappa=1000.0)
    data["boundary"].append({"region": "x_max", "displacement": [0.1, 0.0, 0.0], "fix": ["x"]})
    s = scene_from_dict(data)
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


def drop(section: str, key: str, new: str):
    """An edit renaming ``key`` to ``new`` inside the table ``section``."""
    return lambda d: d[section].update({new: d[section].pop(key)})


@pytest.mark.parametrize(
    "edit, message",
    [
        (
            add("load", {"type": "gravity", "valeu": [0.0, 0.0, -9.81]}),
            "load[0].valeu: unknown key; did you mean 'value'?",
        ),
        (put("material.densty", 900.0), "material.densty: unknown key; did you mean 'density'?"),
        (
            put("boundary.0", {"regoin": "x_min", "fix": ["x"]}),
            "boundary[0].regoin: unknown key; did you mean 'region'?",
        ),
        (
            drop("mesh", "generator", "generater"),
            "mesh.generater: unknown key; did you mean 'generator'?",
        ),
        (put("material.colour", 1), "material.colour: unknown key"),
        (rename("material", "materail"), "[materail]: unknown section; did you mean [material]?"),
        (rename("boundary", "boundry"), "[boundry]: unknown section; did you mean [boundary]?"),
        (put("sprng", {"torsion": "energy"}), "[sprng]: unknown section; did you mean [spring]?"),
        (rename("material", "stuff"), "[stuff]: unknown section"),
        (put("nmae", "x"), "nmae: unknown key; did you mean 'name'?"),
    ],
)
def test_misspelt_keys_and_sections_are_named_with_a_suggestion(edit, message):
    """The misspelt word is named (not the key it hides) with the closest valid one."""
    data = base()
    edit(data)
    with pytest.raises(SceneError) as info:
        scene_from_dict(data, path="bad.toml")
    assert str(info.value) == "bad.toml: " + message


def test_a_misspelt_section_in_a_file_is_named():
    with pytest.raises(SceneError) as info:
        parse_scene(BASE.replace("[material]", "[materail]"), path="bad.toml")
    assert str(info.value) == "bad.toml: [materail]: unknown section; did you mean [material]?"


def test_the_mesh_description_shows_plain_numbers(capsys, tmp_path):
    """``inspect`` once printed ``box [np.float64(0.1), ...]`` (numpy 2 scalar repr)."""
    from studies.cli import main

    data = base()
    data["mesh"]["size"] = [0.1, 0.01, 0.01]
    assert (
        scene_from_dict(data).mesh.source == "box [0.1, 0.01, 0.01] divisions [2, 2, 2] split six"
    )
    path = tmp_path / "s.toml"
    path.write_text(BASE.replace("size = [1.0, 1.0, 1.0]", "size = [0.1, 0.01, 0.01]"))
    assert main(["inspect", str(path)]) == 0
    out = capsys.readouterr().out
    assert "box [0.1, 0.01, 0.01] divisions [2, 2, 2] split six" in out
    assert "np." not in out


def test_a_valid_key_is_never_taken_for_a_misspelling():
    # nu_cross is close to the missing E_cross (difflib ratio 0.8) but is itself valid
    data = base()
    data["material"] = {"law": "transverse-linear", "E_fiber": 3.0, "nu_cross": 0.3}
    data["material"].update(G_fiber=1.0, nu_fiber_cross=0.2)
    with pytest.raises(SceneError) as info:
        scene_from_dict(data, path="bad.toml")
    assert str(info.value) == "bad.toml: material.E_cross: missing (required)"


def test_model_sections_suggest_their_keys():
    data = base()
    data["fem"] = {"ordr": 2}
    with pytest.raises(SceneError) as info:
        scene_from_dict(data, path="bad.toml")
    assert str(info.value) == "bad.toml: fem.ordr: unknown key; did you mean 'order'?"


def test_numpy_scalars_in_a_programmatic_table_are_numbers():
    # a table built in Python often carries numpy scalars (np.int64 from an array, the
    # result of arithmetic on numpy values): they are numbers, and bools are still not
    table = {"name": "np", "material": {"law": "linear", "E": np.float32(1e4), "nu": 0.3},
             "mesh": {"generator": "box", "size": [1.0, 1.0, np.float64(2.0)],
                      "divisions": [np.int64(2), np.int32(1), 1]}}  # fmt: skip
    table["boundary"] = [{"region": {"point": [np.float64(0.0), 0, 0]}, "fix": ["x"]},
                         {"region": {"box": [[np.float32(-1), -1, -1], [0.1, 2, 3]]},
                          "fix": ["y"]}]  # fmt: skip
    scene = scene_from_dict(table)
    assert scene.mesh.n_tets == 2 * 1 * 1 * 6 and scene.material.E == pytest.approx(1e4)
    assert scene.dirichlet()[0].size == 1 + 4  # the corner's x, the x = 0 face's four y
    table["mesh"]["divisions"] = [np.bool_(True), 1, 1]
    with pytest.raises(SceneError, match="mesh.divisions: must be a list of numbers"):
        scene_from_dict(table)
    table["mesh"]["divisions"] = [np.float64(2.0), 1, 1]
    with pytest.raises(SceneError, match="mesh.divisions: must be a list of integers"):
        scene_from_dict(table)


def test_declared_units_scale_the_modulus_check():
    # a scene in mm and kPa (Land's): its moduli of a few kPa are soft tissue, not 10 Pa
    from studies.guards import modulus_warning

    for name in ("land-beam", "land-ventricle", "land-ventricle-fibres"):
        bundled = load_scene(SCENES / f"{name}.toml")
        assert bundled.units == "mm-kPa"
        assert modulus_warning(bundled.material, bundled.units) is None
    table = {"name": "u", "units": "mm-kPa", "material": {"law": "linear", "E": 5.0, "nu": 0.3},
             "mesh": {"generator": "box", "size": [1, 1, 1], "divisions": [1, 1, 1]}}  # fmt: skip
    scene = scene_from_dict(table)
    assert scene.units == "mm-kPa" and modulus_warning(scene.material, scene.units) is None
    assert modulus_warning(scene.material) is not None  # 5 Pa in SI: a unit slip
    table["material"]["E"] = 5.0e-3  # 5 Pa written in kPa
    line = modulus_warning(scene_from_dict(table).material, "mm-kPa")
    assert line == ("E = 0.005 kPa (5 Pa) is outside 10 Pa – 1e+09 Pa, the range of soft "
                    "tissue: check the units (the scene's: mm-kPa)")  # fmt: skip
    with pytest.raises(SceneError, match=r"units: 'cm-kPa' is not one of SI, mm-kPa, mm-MPa"):
        scene_from_dict({**table, "units": "cm-kPa"})


def test_model_sections_are_registered_not_named():
    """The core validates a model section only through the parser a package registers:
    the models' sections come from entry points, a new one can be registered at run time,
    a name is registered once, and a section nobody registered is unknown."""
    import springfem.scene.build as build
    from springfem.errors import SceneError
    from springfem.scene import model_sections, register_section, scene_from_dict

    assert {"spring", "fem", "output", "solver"} <= set(model_sections())
    box = {"generator": "box", "size": [1, 1, 1], "divisions": [1, 1, 1]}
    table = {"mesh": box, "material": {"law": "linear", "E": 1.0, "nu": 0.3}, "extra": {"a": 1}}
    with pytest.raises(SceneError, match=r"\[extra\]: unknown section"):
        scene_from_dict(table)

    def parse(r):
        value = r.get("a", "int")
        r.finish()
        return value

    register_section("extra", parse)
    try:
        assert scene_from_dict(table).options["extra"] == 1
        with pytest.raises(ValueError, match="registered twice"):
            register_section("extra", lambda r: None)
        with pytest.raises(ValueError, match="core section"):
            register_section("mesh", parse)
    finally:
        build._SECTION_PARSERS.pop("extra")


def test_load_scene_by_registered_name():
    from springfem.errors import SceneError

    assert load_scene("cantilever").name == "cantilever"
    with pytest.raises(SceneError, match=r"scene file cantilevr does not exist \(named scenes: "):
        load_scene("cantilevr")
