"""Tets across a thin wall (springfem.mesh.thickness) against meshes whose layers are known."""

import numpy as np
import pytest

from springfem.ellipsoid import ellipsoid_mesh
from springfem.mesh import box_mesh, read_mesh
from springfem.mesh.organ import organ_mesh
from springfem.mesh.thickness import face_neighbours, tets_across, thin_wall_note, wall_rays


@pytest.mark.parametrize("layers", [1, 2, 3])
def test_a_plate_has_as_many_tets_across_as_cell_layers(layers):
    plate = box_mesh((10.0, 10.0, 1.0), (10, 10, layers))
    across = tets_across(plate)
    length, _, area = wall_rays(plate)
    faces = np.isclose(length, 1.0)  # the rays from the two large faces cross the plate
    assert area[faces].sum() == pytest.approx(2 * 100.0)
    np.testing.assert_allclose(across[faces], layers, rtol=1e-9)
    assert (thin_wall_note(plate) is not None) == (layers == 1)


def test_face_neighbours_are_symmetric():
    m = box_mesh((1.0, 1.0, 1.0), (3, 3, 3))
    nb, face = face_neighbours(m.tets)
    t, i = np.nonzero(nb >= 0)
    assert (nb[nb[t, i], face[t, i]] == t).all()
    assert (nb < 0).sum() == len(m.boundary_facets())


def test_a_ventricle_one_tet_across_gets_the_note_and_a_solid_organ_none(tmp_path):
    lv = ellipsoid_mesh(size=3.0)  # wall 3 mm, tets of about 3 mm: one across
    assert np.median(tets_across(lv)) == pytest.approx(1.0, abs=0.1)
    note = thin_wall_note(lv)
    assert note is not None and note.startswith("thin wall:") and "\n" not in note
    finer = ellipsoid_mesh(size=1.5)  # two across
    assert np.median(tets_across(finer)) > 1.75 and thin_wall_note(finer) is None
    organ_mesh(tmp_path / "organ.msh", tets=2000)
    organ = read_mesh(tmp_path / "organ.msh")
    assert np.median(tets_across(organ)) > 4.0
    assert thin_wall_note(organ) is None
