"""``[solver] precision`` sets both models' kernel precision; a model's own key wins."""

from __future__ import annotations

import numpy as np
import pytest

from reference_fem.explicit import ExplicitFem
from springfem.errors import SceneError
from springfem.scene import scene_from_dict
from springmodel.model import SpringModel

BASE = {
    "mesh": {"generator": "box", "size": [1.0, 1.0, 1.0], "divisions": [2, 2, 2]},
    "material": {"law": "neo-hookean", "E": 1.0e3, "nu": 0.3},
    "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
}


def scene(**sections):
    return scene_from_dict({**BASE, **sections})


def test_solver_precision_reaches_both_models():
    s = scene(solver={"precision": "float32"})
    assert SpringModel(s).kernel.precision == "float32"
    assert ExplicitFem(s).precision == "float32"
    # and the kernels really run in it: float32 forces differ from float64 at ~1e-7, not 0
    x = s.mesh.points * 1.01
    f32 = SpringModel(s).kernel.forces(x)
    f64 = SpringModel(scene()).kernel.forces(x)
    rel = np.abs(f32 - f64).max() / np.abs(f64).max()
    assert 1e-12 < rel < 1e-4


def test_model_section_overrides_solver_section():
    s = scene(solver={"precision": "float32"}, spring={"precision": "mixed"})
    assert SpringModel(s).kernel.precision == "mixed"
    assert ExplicitFem(s).precision == "float32"
    assert SpringModel(scene()).kernel.precision == "float64"


def test_bad_solver_key_names_it():
    with pytest.raises(SceneError, match="solver.precision: 'half' is not one of"):
        scene(solver={"precision": "half"})
