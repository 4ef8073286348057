"""Cavity volume (divergence theorem over the endocardium closed by the base cap), the
pressure-volume record and the anisotropy fields of the VTU."""

from __future__ import annotations

import csv
from types import SimpleNamespace

import numpy as np
import pytest
from support.meshes import ventricle_mesh

from springfem.cardiac import (
    PressureVolume,
    cavity_summary,
    cavity_volume,
    oriented_facets,
    write_pressure_volume,
)
from springfem.ellipsoid import cavity_volume as exact_cavity
from springfem.errors import InputError
from springfem.result import frame_cell_data


@pytest.fixture(scope="module")
def lv():
    return ventricle_mesh(3.0)


def test_undeformed_cavity_converges_to_the_truncated_ellipsoid():
    # the facets are chords of the ellipsoid: the inscribed polyhedron misses O(h^2) of
    # the volume, so halving the size must cut the error by well over half
    errs = [abs(cavity_volume(m, m.points) / exact_cavity() - 1) for m in
            (ventricle_mesh(4.0), ventricle_mesh(2.0))]  # fmt: skip
    assert errs[1] < 0.6 * errs[0]
    assert errs[1] < 0.02  # h = 2 mm on radii >= 7 mm: chord sag (h/2)^2/(2R) ~ 1 %


def test_a_uniform_scaling_multiplies_the_volume_by_its_cube(lv):
    v0 = cavity_volume(lv, lv.points)
    for lam in (0.8, 1.25):
        assert cavity_volume(lv, lam * lv.points) == pytest.approx(lam**3 * v0, rel=1e-12)
    s = cavity_summary(lv, 0.1 * lv.points)
    assert s["relative_change"] == pytest.approx(1.1**3 - 1, rel=1e-12)


def test_the_volume_is_invariant_under_rigid_motions(lv):
    rng = np.random.default_rng(0)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.linalg.det(q))
    moved = lv.points @ q.T + [3.0, -2.0, 7.0]
    assert cavity_volume(lv, moved) == pytest.approx(cavity_volume(lv, lv.points), rel=1e-12)


def test_epi_cavity_minus_endo_cavity_is_the_wall_volume(lv):
    # both caps lie in the base plane and the base facets fill the ring between them, so the
    # two closed surfaces differ by exactly the mesh's tets (divergence theorem)
    rng = np.random.default_rng(1)
    x = lv.points.copy()
    on_base = np.abs(x[:, 2] - 5.0) < 1e-9
    x[~on_base] += 0.2 * rng.normal(size=(int((~on_base).sum()), 3))
    wall = lv.volumes(x).sum()
    diff = cavity_volume(lv, x, "epi") - cavity_volume(lv, x, "endo")
    assert diff == pytest.approx(wall, rel=1e-10)


def test_facet_vertex_order_does_not_matter(lv):
    from dataclasses import replace

    flipped = replace(lv, facet_sets={**lv.facet_sets, "endo": lv.facet_sets["endo"][:, ::-1]})
    tris, rim = oriented_facets(lv)
    tris2, rim2 = oriented_facets(flipped)
    assert np.array_equal(np.sort(tris, axis=1), np.sort(tris2, axis=1))
    np.testing.assert_array_equal(rim, rim2)
    assert np.allclose(lv.points[rim][:, 2], 5.0)  # the rim lies on the base plane


def test_a_missing_facet_set_is_a_one_line_error(lv):
    with pytest.raises(InputError, match="'lumen'.*mesh has: base, endo, epi"):
        cavity_volume(lv, lv.points, "lumen")


def test_pressure_volume_records_each_step_and_writes_csv(lv, tmp_path):
    pv = PressureVolume(lv, 10.0, lambda s: s.reshape(-1, 3))
    for lf in (0.5, 1.0):
        pv(lf, (lf * 0.1) * lv.points.ravel())
    v0 = exact = cavity_volume(lv, lv.points)
    rows = pv.summary(0.1 * lv.points)["pressure_volume"]
    assert [r[:2] for r in rows] == [[0.0, 0.0], [0.5, 5.0], [1.0, 10.0]]
    assert rows[1][2] == pytest.approx(1.05**3 * v0, rel=1e-12)
    assert rows[2][2] == pytest.approx(1.1**3 * exact, rel=1e-12)
    csv_path, png = write_pressure_volume(tmp_path / "pv", rows, "t")
    back = list(csv.DictReader(csv_path.open()))
    assert [float(r["pressure"]) for r in back] == [0.0, 5.0, 10.0]
    assert png.stat().st_size > 0


def test_fibre_stretch_is_the_length_of_F_f():
    from springfem.mesh import box_mesh

    m = box_mesh((1.0, 2.0, 1.0), (2, 2, 2))
    rng = np.random.default_rng(2)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    frames = np.tile(q.T, (m.n_tets, 1, 1))  # rows: fibre, sheet, normal
    F = np.array([[1.2, 0.1, 0.0], [0.0, 0.9, 0.2], [0.05, 0.0, 1.1]])
    u = m.points @ (F - np.eye(3)).T
    d = frame_cell_data(SimpleNamespace(mesh=m, frames=frames), u)
    np.testing.assert_allclose(d["fiber_stretch"], np.linalg.norm(F @ q[:, 0]), rtol=1e-12)
    np.testing.assert_allclose(d["sheet"], np.tile(q[:, 1], (m.n_tets, 1)))
    assert "transmural_depth" not in d
