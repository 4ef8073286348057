"""``springfem inspect --modes``: near-zero eigenvalues of each model's tangent at rest.

Independent references: a free body has the six rigid motions; a block clamped on one
face has none; fixing only ``x`` on a face leaves the two in-plane translations and the
rotation about ``x`` (3); springs along the three axes alone carry no shear, so even a
clamped jittered Delaunay block of them has zero-energy shear modes, which the report must
name as spurious.
"""

import numpy as np
import pytest

from springfem.scene import scene_from_dict
from studies.cli import main
from studies.modes_report import scene_modes

EXACT = {"volume": "axes", "torsion": "energy", "calibration": "exact"}


def _block(boundary, spring=EXACT):
    return scene_from_dict({
        "mesh": {"generator": "box", "size": [1.0, 0.6, 0.4], "divisions": [3, 2, 2],
                 "split": "delaunay"},
        "material": {"law": "linear", "E": 1e3, "nu": 0.3},
        "boundary": boundary, "spring": spring,
    })  # fmt: skip


@pytest.mark.parametrize(
    ("boundary", "expected"),
    [
        ([], 6),
        ([{"region": "x_min", "fix": ["x"]}], 3),
        ([{"region": "x_min", "fix": ["x", "y", "z"]}], 0),
    ],  # fmt: skip
)
def test_stable_elements_show_only_the_free_rigid_motions(boundary, expected):
    for r in scene_modes(_block(boundary)):
        assert (r.count, r.expected, r.spurious) == (expected, expected, 0), r.line


def test_axial_springs_alone_have_spurious_modes_and_the_report_names_them():
    axial = {"torsion": "off", "volume": False}
    (spring,) = scene_modes(_block([{"region": "x_min", "fix": ["x", "y", "z"]}], axial),
                            ("spring",))  # fmt: skip
    assert spring.expected == 0 and spring.spurious > 0
    assert f"{spring.spurious} SPURIOUS modes" in spring.line


def test_cli_prints_one_line_per_model(capsys, tmp_path):
    scene = tmp_path / "block.toml"  # the bundled cantilever's eigenproblem takes ~30 s
    scene.write_text(
        '[mesh]\ngenerator = "box"\nsize = [1.0, 0.6, 0.4]\ndivisions = [3, 2, 2]\n'
        'split = "delaunay"\n[material]\nlaw = "linear"\nE = 1e3\nnu = 0.3\n'
        '[[boundary]]\nregion = "x_min"\nfix = ["x", "y", "z"]\n'
    )
    assert main(["inspect", str(scene), "--modes"]) == 0
    lines = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("modes (")]
    assert len(lines) == 2 and all("no spurious modes" in ln for ln in lines)
    assert np.all(["0 expected" in ln for ln in lines])  # clamped at x_min
