"""The command line: exit codes and one-line errors (docs/contract.rst#exit-codes)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from studies.cli import main

ROOT = Path(__file__).resolve().parents[2]
CANTILEVER = ROOT / "studies" / "scenes" / "cantilever.toml"


def test_inspect_cantilever_json(capsys):
    assert main(["inspect", str(CANTILEVER), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["nodes"] == 1025 and out["tets"] == 3840
    assert out["volume"] == pytest.approx(1e-5, rel=1e-12)
    assert out["all_rays_hit"] == 3840
    # 6-tet split of a 2.5 mm cube: regular-ish tets, quality well inside (0, 1]
    assert 0.3 < out["quality_min"] <= out["quality_max"] <= 1.0


def test_bundled_scene_by_name(capsys):
    assert main(["inspect", "cantilever"]) == 0
    assert "3840" in capsys.readouterr().out


@pytest.mark.parametrize(
    "content, needle",
    [
        ('[mesh]\ngenerator = "box"\n', "[material]: missing section"),
        ("this is = = not toml", "not valid TOML"),
    ],
)
def test_malformed_scene_exits_2_with_one_line(tmp_path, capsys, content, needle):
    bad = tmp_path / "bad.toml"
    bad.write_text(content)
    assert main(["inspect", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and "\n" not in err and "Traceback" not in err


def test_missing_scene_exits_2(capsys):
    assert main(["inspect", "no-such-scene"]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_console_script_subprocess(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(
        '[mesh]\ngenerator = "box"\nsize = [1.0, 1.0, 1.0]\ndivisions = [1, 1, 1]\n'
        '[material]\nlaw = "linear"\nE = "x"\nnu = 0.3\n'
    )
    proc = subprocess.run(
        [sys.executable, "-m", "studies.cli", "inspect", str(bad)],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )
    assert proc.returncode == 2
    assert proc.stderr.strip().count("\n") == 0
    assert "material.E: must be a number" in proc.stderr
