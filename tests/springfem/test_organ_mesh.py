"""The organ-scene generator (springfem.mesh.organ): the size asked for, the shape's volume
from gmsh's exact geometry, and the regions a scene needs."""

from __future__ import annotations

import numpy as np
import pytest

from springfem.errors import MeshError
from springfem.mesh.organ import organ_scene, organ_volume_mm3
from springfem.scene import load_scene


@pytest.mark.parametrize("tets", [600, 3000])
def test_the_organ_has_the_size_asked_for_and_its_exact_volume(tmp_path, tets):
    scene = load_scene(organ_scene(tmp_path, tets))
    mesh = scene.mesh
    assert abs(mesh.n_tets / tets - 1) < 0.15
    # the tets fill the curved body from inside: a few per cent short at 600 tets
    assert np.isclose(mesh.volumes().sum(), organ_volume_mm3(), rtol=0.06)
    assert (mesh.volumes() > 0).all()
    z = mesh.points[scene.boundaries[0].region.nodes, 2]
    assert len(z) > 3 and np.allclose(z, mesh.points[:, 2].max())  # the flat cut on top


def test_too_few_tets_is_one_clear_error(tmp_path):
    with pytest.raises(MeshError, match="too few"):
        organ_scene(tmp_path, 10)
