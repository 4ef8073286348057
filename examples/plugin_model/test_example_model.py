"""The example model's own test: the conformance check every model passes (docs/plugins.rst).

An out-of-tree model runs :func:`springfem.testing.check_model` in its own tests: here on a
jittered Delaunay box (no element aligned with the axes), held to exact small strain since
it is linear P1. ``pytest`` in this folder runs it once the package is installed.
"""

from springfem_example_model import MODEL

from springfem.scene import scene_from_dict
from springfem.testing import check_model

SCENE = scene_from_dict({
    "name": "jittered-box",
    "mesh": {"generator": "box", "size": [0.06, 0.02, 0.02], "divisions": [6, 3, 3],
             "split": "delaunay"},
    "material": {"law": "linear", "E": 1.0e4, "nu": 0.3, "density": 1000.0},
    "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
    "load": [{"type": "traction", "region": "x_max", "value": [0.0, 0.0, -100.0]}],
})  # fmt: skip


def test_the_model_conforms():
    report = check_model(MODEL, SCENE, small_strain="exact")  # raises on a failed check
    print(report)
    assert report.status("small strain") == "passed"


if __name__ == "__main__":
    test_the_model_conforms()
