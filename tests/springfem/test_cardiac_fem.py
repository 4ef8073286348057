"""The cardiac outputs of a FEM ventricle solve: the pressure-volume record over the load
steps, the cavity summary and the anisotropy fields of the VTU (a coarse Land problem 3)."""

from __future__ import annotations

import csv
from pathlib import Path

import meshio
import numpy as np
import pytest

import reference_fem
from springfem.result import write_result
from springfem.scene.reader import TableReader

SCENE = Path(__file__).resolve().parents[2] / "studies" / "scenes" / "land-ventricle-fibres.toml"


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    import tomllib

    from springfem.scene import scene_from_dict

    data = tomllib.loads(SCENE.read_text())
    data["mesh"]["size"] = 6.0
    data["fem"]["load_steps"] = 3
    scene = scene_from_dict(data, SCENE)
    sol = reference_fem.solve(scene)
    out = tmp_path_factory.mktemp("lv")
    write_result(out, sol.result, scene.mesh, sol.u_vertices, cell_data=sol.cell_data)
    return scene, sol, out


def test_pressure_volume_is_recorded_in_load_order(solved):
    scene, sol, _ = solved
    cav = sol.result.info["cavity"]
    rows = np.array(cav["pressure_volume"])
    assert rows[0, 0] == 0.0 and rows[-1, 0] == pytest.approx(1.0)
    assert (np.diff(rows[:, 0]) > 0).all()
    np.testing.assert_allclose(rows[:, 1], 15.0 * rows[:, 0])  # the scene's 15 kPa
    assert (np.diff(rows[:, 2]) > 0).all()  # inflation: the cavity grows with the pressure
    assert rows[-1, 2] == cav["final"] and rows[0, 2] == cav["initial"]
    # incompressible wall (mixed P2/P1): the constraint holds int (J - 1) = 0 in the form's
    # quadrature, volume_p2 integrates J with another one: equal to well under 0.1 %, while
    # the cavity has grown by far more than that
    assert sol.result.info["volume_p2"] == pytest.approx(sol.result.volume["initial"], rel=1e-3)
    assert cav["relative_change"] > 0.5


def test_the_p2_cavity_is_integrated_over_the_quadratic_facets(solved):
    from springfem.cardiac import QUADRATIC, cavity_volume

    scene, sol, _ = solved
    cav = sol.result.info["cavity"]
    assert cav["method"] == QUADRATIC
    # at rest the P2 facets are straight (the gmsh mesh is linear, the midside nodes are the
    # edge midpoints): the same polyhedron as the flat facets, to round-off
    assert cav["initial"] == pytest.approx(cavity_volume(scene.mesh, scene.mesh.points), rel=1e-12)
    # deformed, the flat facets through the vertices are another surface: the vertex-only
    # volume differs (it is the old value), yet both describe the same inflated cavity
    assert cav["final_flat"] == pytest.approx(
        cavity_volume(scene.mesh, scene.mesh.points + sol.u_vertices), rel=1e-12
    )
    assert abs(cav["final_flat"] / cav["final"] - 1) > 0.01  # on this coarse 6 mm mesh


def test_p2_epi_minus_endo_cavity_is_the_p2_wall_volume(solved):
    # divergence theorem on the deformed P2 body: its boundary is the curved endo and epi
    # facets and the (fixed, flat) base ring between the two rims, so the two quadratic-facet
    # cavities differ by int det F dX over the P2 elements (volume_p2, degree-3 exact) to
    # round-off; the flat-facet cavities differ by the vertex tets' volume instead
    from reference_fem.cavity import facet_nodes
    from springfem.cardiac import cavity_volume, oriented_facets

    scene, sol, _ = solved
    mesh, nodes = scene.mesh, facet_nodes(sol.problem.space)
    x = mesh.points + sol.u_vertices
    v = {n: cavity_volume(mesh, x, n, nodes(sol.u, oriented_facets(mesh, n)[0]))
         for n in ("endo", "epi")}  # fmt: skip
    assert v["endo"] == pytest.approx(sol.result.info["cavity"]["final"], rel=1e-12)
    assert v["epi"] - v["endo"] == pytest.approx(sol.result.info["volume_p2"], rel=1e-10)
    flat = cavity_volume(mesh, x, "epi") - cavity_volume(mesh, x, "endo")
    assert flat == pytest.approx(mesh.volumes(x).sum(), rel=1e-10)


def test_the_curve_and_the_fields_are_written(solved):
    scene, _, out = solved
    rows = list(csv.DictReader((out / "result_pressure_volume.csv").open()))
    assert float(rows[-1]["pressure"]) == pytest.approx(15.0)
    assert (out / "result_pressure_volume.png").stat().st_size > 0
    m = meshio.read(out / "result.vtu")
    for key in ("fiber", "sheet", "fiber_stretch", "transmural_depth"):
        assert key in m.cell_data, key
    np.testing.assert_allclose(m.cell_data["fiber"][0], scene.frames[:, 0])
    assert m.cell_data["fiber_stretch"][0].min() > 0.5  # J > 0 everywhere


def test_a_scene_without_endo_pressure_records_no_curve():
    from springfem.cardiac import pressure_volume
    from springfem.scene.sections import parse_mesh

    r = TableReader({"generator": "box", "size": [1, 1, 1], "divisions": [1, 1, 1]}, "mesh", "s")
    mesh = parse_mesh(r, Path("."))

    class S:  # just what pressure_volume looks at
        loads = []

    S.mesh = mesh
    assert pressure_volume(S, lambda u: u) is None


def test_the_apex_probes_are_the_apex_vertices(solved):
    # Land's apex: the lowest point of the rest endo / epi surface on the axis x = y = 0; the
    # gmsh ellipsoid has a vertex there (the scaled spheres' poles), so the probes read the
    # vertex's own displacement (no interpolation)
    scene, sol, _ = solved
    mesh = scene.mesh
    for name, z in (("endo_apex", -17.0), ("epi_apex", -20.0)):
        d = np.linalg.norm(mesh.points - [0.0, 0.0, z], axis=1)
        node = int(np.argmin(d))
        assert d[node] < 1e-9
        surface = np.unique(mesh.facet_sets[name.split("_")[0]])
        assert mesh.points[surface, 2].min() == pytest.approx(z, abs=1e-12)
        np.testing.assert_allclose(sol.result.probes[name], sol.u_vertices[node], atol=1e-9)
