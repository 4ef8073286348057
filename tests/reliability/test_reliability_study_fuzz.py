"""Every study that takes a user's scene runs on every kind of scene or says why not, in one
line: never an internal error.

The fuzz runs the studies that accept ``--scene`` on the bundled scenes and a gmsh box as
they are, and on variants of the box (nearly incompressible, neo-Hookean, a soft modulus,
fibres off the axes), each solve capped at :data:`MAX_TIME`. The contract
(docs/contract.rst#exit-codes): exit 0 with the study's outputs, 2 (bad input: the study
does not apply to this scene) or 3 (a solver failure), with one line on stderr for 2 and
3; exit 1 (an internal error) never. The default run takes a fixed sample of the cases;
``-m slow`` all of them.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import pytest
from support.meshes import gmsh_box
from support.toml import to_toml

from studies.cli import main
from studies.runner import REGISTRY
from studies.scenes import scene_path

BUNDLED = ("cantilever", "sag", "stretch-fiber", "land-beam", "drift-cube")
VARIANTS = {
    "as-is": {},
    "nu-0.499": {"material": {"nu": 0.499}},
    "neo-hookean": {"material": {"law": "neo-hookean"}},
    "soft": {"material": {"E": 5.0}},
    "off-axis": {"axes": {"fiber": [0.6, 0.8, 0.0], "sheet": [-0.8, 0.6, 0.0]}},
}
#: Cap of each solve (s): a scene the solvers cannot handle gives stopped rows, not a hang.
MAX_TIME = 10.0
#: The default run's sample: (study, scene, variant), one per study.
SAMPLE = (("accuracy", "gmsh", "off-axis"),)


def _user_studies() -> list[str]:
    return [n.replace("_", "-") for n, spec in REGISTRY.items() if spec.user_scenes is None]


def _scene_table(scene: str, folder: Path) -> dict:
    import tomllib

    if scene == "gmsh":
        gmsh_box(folder / "box.msh", 0.02)
        return {
            "name": "gbox",
            "mesh": {"file": str(folder / "box.msh")},
            "material": {"law": "linear", "E": 1.0e4, "nu": 0.3},
            "axes": {"fiber": [1.0, 0.0, 0.0], "sheet": [0.0, 1.0, 0.0]},
            "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
            "load": [{"type": "traction", "region": "x_max", "value": [0.0, 0.0, -0.1]}],
            "probe": [{"name": "tip", "point": [0.1, 0.01, 0.01]}],
        }
    path = scene_path(scene)
    table = tomllib.loads(Path(path).read_text())
    mesh = table.get("mesh", {})
    if "file" in mesh:  # relative to the bundled scene's folder
        mesh["file"] = str((Path(path).parent / mesh["file"]).resolve())
    return table


def _merged(table: dict, change: dict) -> dict:
    out = {k: (dict(v) if isinstance(v, dict) else v) for k, v in table.items()}
    for key, sub in change.items():
        out[key] = {**out.get(key, {}), **sub}
    return out


def _run(study: str, scene: str, variant: str, tmp: Path, capsys) -> None:
    table = _merged(_scene_table(scene, tmp), VARIANTS[variant])
    if variant == "soft" and table["material"].get("law") in ("guccione", "holzapfel-ogden"):
        table["material"]["C" if "C" in table["material"] else "a"] = 0.001
    f = tmp / f"{scene}-{variant}.toml"
    f.write_text(to_toml(table))
    argv = ["study", study, "--scene", str(f), "--quick", "--out", str(tmp / "out")]
    code = main([*argv, "--max-time", str(MAX_TIME)])
    err = capsys.readouterr().err
    assert "internal error" not in err, err
    assert code in (0, 2, 3), (code, err)
    if code in (2, 3):
        lines = [ln for ln in err.splitlines() if ln.startswith("springfem: ")]
        assert len(lines) == 1, err


@pytest.mark.parametrize(("study", "scene", "variant"), SAMPLE)
def test_study_on_a_user_scene_never_fails_internally(study, scene, variant, tmp_path, capsys):
    _run(study, scene, variant, tmp_path, capsys)


def _slow_cases() -> list[tuple[str, str, str]]:
    """Every study on every scene as it is, and on the gmsh box in every variant."""
    cases = itertools.chain(
        itertools.product(_user_studies(), ("gmsh", *BUNDLED), ("as-is",)),
        itertools.product(_user_studies(), ("gmsh",), tuple(VARIANTS)[1:]),
    )
    return [c for c in cases if c not in SAMPLE]


@pytest.mark.slow
@pytest.mark.parametrize(("study", "scene", "variant"), _slow_cases())
def test_every_study_on_every_scene_never_fails_internally(study, scene, variant, tmp_path, capsys):
    _run(study, scene, variant, tmp_path, capsys)
