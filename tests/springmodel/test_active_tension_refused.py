"""The spring model carries no active fibre tension
(docs/tissue.rst#active-tension-in-the-spring-model): a scene with ``[material]
active_tension`` is refused in one line, never solved passive."""

import pytest

from springfem.errors import InputError
from springfem.scene import scene_from_dict
from springmodel.model import SpringModel


def test_active_tension_is_refused_by_the_spring_model():
    scene = scene_from_dict(
        {
            "name": "active",
            "mesh": {"generator": "box", "size": [1, 1, 1], "divisions": [1, 1, 1]},
            "material": {
                "law": "guccione",
                "C": 2.0,
                "b_f": 8.0,
                "b_t": 2.0,
                "b_fs": 4.0,
                "kappa": 50.0,
                "active_tension": 1.0,
            },  # fmt: skip
            "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
        }
    )
    with pytest.raises(InputError, match=r"^active: material\.active_tension: .*--model fem$"):
        SpringModel(scene)
