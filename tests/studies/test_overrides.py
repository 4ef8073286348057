"""``--set key=value``: dotted keys, TOML values, errors from the scene validation."""

import json

import numpy as np
import pytest

from springfem.errors import InputError, SceneError
from springmodel.options import SpringOptions
from studies.cli import main
from studies.overrides import (
    apply_overrides,
    load_scene_with,
    parse_assignment,
    parse_value,
)
from studies.scenes import scene_path

CANTILEVER = scene_path("cantilever")


@pytest.mark.parametrize(
    "text, value",
    [
        ("0.45", 0.45),
        ("3", 3),
        ("1e4", 1e4),
        ("true", True),
        ("[20,2,2]", [20, 2, 2]),
        ('"energy"', "energy"),
        ("energy", "energy"),  # bare word: a string
        ("{a = 1}", {"a": 1}),
    ],
)
def test_values_are_toml_typed(text, value):
    got = parse_value(text)
    assert got == value and type(got) is type(value)


@pytest.mark.parametrize("text", ["material.nu", "=3", "a..b=1", "x=[1,", 'x="open'])
def test_malformed_assignments_are_input_errors(text):
    with pytest.raises(InputError, match="--set"):
        parse_assignment(text)


def test_overrides_create_tables_and_index_arrays_of_tables():
    data = {"material": {"nu": 0.3}, "load": [{"value": [0, 0, -1]}], "probe": []}
    sets = [
        ("material.nu", 0.45),
        ("spring.torsion", "energy"),  # [spring] is created
        ("load.0.value", [0, 0, -2]),
        ("probe.0.name", "mid"),  # one past the end of an array of tables appends one
        ("probe.0.point", [0.05, 0.005, 0.005]),
    ]
    new = apply_overrides(data, sets)
    assert new["material"] == {"nu": 0.45}
    assert new["spring"] == {"torsion": "energy"}
    assert new["load"] == [{"value": [0, 0, -2]}]
    assert new["probe"] == [{"name": "mid", "point": [0.05, 0.005, 0.005]}]
    assert data == {"material": {"nu": 0.3}, "load": [{"value": [0, 0, -1]}], "probe": []}


@pytest.mark.parametrize(
    "key, needle",
    [
        ("load.5.value", "load has 1 entries"),
        ("load.type", "index it with a number"),
        ("material.nu.x", "material.nu is a value"),
    ],
)
def test_impossible_paths_are_one_line_input_errors(key, needle):
    with pytest.raises(InputError, match=needle):
        apply_overrides({"material": {"nu": 0.3}, "load": [{"value": 1}]}, [(key, 1)])


def test_scene_with_overrides_is_the_scene_the_file_would_give():
    s = load_scene_with(
        CANTILEVER,
        ["material.nu=0.45", "mesh.divisions=[20,2,2]", "spring.torsion=energy"],
    )
    # the six-tet split of a 20x2x2 box: 6 * 80 tets, 21 * 3 * 3 nodes (independent count)
    assert (s.mesh.n_tets, s.mesh.n_points) == (480, 189)
    assert s.material.nu == 0.45
    assert SpringOptions.of(s).torsion == "energy"
    assert s.name == "cantilever"  # everything else as the file says
    np.testing.assert_allclose(s.mesh.points.max(axis=0), [0.1, 0.01, 0.01])


@pytest.mark.parametrize(
    "sets, needle",
    [
        (["material.nuu=0.4"], "material.nuu: unknown key (from --set material.nuu=0.4)"),
        (["materail.nu=0.4"], "[materail]: unknown section"),
        (["material.nu=abc"], "material.nu: must be a number"),
        (["load.0.value=[0, 1]"], "load[0].value"),
        (["spring.torsion=twist"], "spring.torsion"),
    ],
)
def test_bad_overrides_report_the_key_and_the_set(sets, needle):
    with pytest.raises(SceneError) as info:
        load_scene_with(CANTILEVER, sets)
    msg = str(info.value)
    assert needle in msg and "\n" not in msg
    assert "--set" in msg


def test_cli_solve_with_set_is_linear_in_the_load(tmp_path, capsys):
    """Linear FEM: doubling the traction by --set doubles the tip displacement."""
    tips = []
    for q in (-0.1, -0.2):
        args = ["solve", "cantilever", "--model", "fem", "--order", "1", "--json"]
        args += ["--out", str(tmp_path / str(q)), "--set", "mesh.divisions=[10,1,1]"]
        args += ["--set", f"load.0.value=[0, 0, {q}]"]
        assert main(args) == 0
        res = json.loads(capsys.readouterr().out)
        assert res["counts"]["tets"] == 60  # 6 * 10 * 1 * 1
        tips.append(res["probes"]["tip"][2])
    assert tips[0] < 0
    # same mesh and matrix, right-hand side doubled: round-off / solver tolerance only
    assert tips[1] == pytest.approx(2 * tips[0], rel=1e-8)


def test_cli_unknown_key_exits_2_with_one_line(capsys):
    assert main(["solve", "cantilever", "--set", "material.nuu=0.4"]) == 2
    err = capsys.readouterr().err.strip()
    assert "material.nuu: unknown key" in err and "\n" not in err


def test_cli_compare_accepts_set(tmp_path, capsys, monkeypatch):
    from studies import compare_output

    def no_render(cmp, path):  # the figure is test_compare's; this test is about --set
        raise RuntimeError("not rendered here")

    monkeypatch.setattr(compare_output, "render_comparison", no_render)
    out = tmp_path / "cmp"
    args = ["compare", "cantilever", "--json", "--out", str(out)]
    assert main([*args, "--set", "mesh.divisions=[6,1,1]"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert {r["model"] for r in payload["rows"]} >= {"spring", "P1", "P2"}
    assert json.loads((out / "P1" / "result.json").read_text())["counts"]["tets"] == 36


def test_an_error_elsewhere_in_the_table_is_not_blamed_on_the_set(tmp_path):
    bad = tmp_path / "bad.toml"
    text = CANTILEVER.read_text().replace("E = 1.0e4", 'E = "x"')
    bad.write_text(text)
    with pytest.raises(SceneError) as info:
        load_scene_with(bad, ["material.nu=0.4"])
    assert "material.E: must be a number" in str(info.value)
    assert "--set" not in str(info.value)
