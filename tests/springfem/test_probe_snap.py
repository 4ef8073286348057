"""A probe on a curved surface lies off its faceted mesh: within half an element it snaps to
the nearest boundary point (with a note), farther out it is refused.

The nearest point is checked against a brute-force search (every boundary triangle sampled
on a fine barycentric grid), which is independent of the projection-and-edges construction
of :func:`springfem.mesh.nearest.closest_on_triangles`.
"""

from __future__ import annotations

import numpy as np
import pytest

from springfem.errors import SceneError
from springfem.mesh import boundary_facets, read_mesh
from springfem.mesh.nearest import closest_on_triangles, nearest_boundary_point
from springfem.scene import scene_from_dict

R = 0.02  # sphere radius (m)


def _grid(n: int = 40) -> np.ndarray:
    """Barycentric points of a triangle on a grid of spacing 1/n."""
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    keep = i + j <= n
    a, b = i[keep] / n, j[keep] / n
    return np.column_stack([1 - a - b, a, b])


def _brute_force(p: np.ndarray, tri: np.ndarray, n: int = 40) -> float:
    """Smallest distance from ``p`` to points sampled on every triangle (an upper bound of
    the true distance, within the grid's spacing)."""
    pts = np.einsum("gk,tkd->tgd", _grid(n), tri)
    return float(np.linalg.norm(pts - p, axis=2).min())


@pytest.fixture(scope="module")
def sphere(tmp_path_factory):
    gmsh = pytest.importorskip("gmsh")
    path = tmp_path_factory.mktemp("snap") / "sphere.msh"
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("sphere")
        gmsh.model.occ.addSphere(0, 0, 0, R)
        gmsh.model.occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.3 * R)
        gmsh.model.addPhysicalGroup(3, [1], name="body")
        gmsh.model.mesh.generate(3)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return path


def _scene(path, point):
    return scene_from_dict(
        {
            "mesh": {"file": str(path)},
            "material": {"law": "linear", "E": 5e3, "nu": 0.3},
            "probe": [{"name": "side", "point": list(map(float, point))}],
        }
    )


def test_closest_points_on_random_triangles_match_a_brute_force_search():
    rng = np.random.default_rng(3)
    for _ in range(20):
        tri = rng.normal(size=(1, 3, 3))
        p = rng.normal(size=3) * 2.0
        q = closest_on_triangles(p, tri)[0]
        d = np.linalg.norm(q - p)
        # the sampled distance is at least the true one, and at most a grid spacing more
        h = max(np.linalg.norm(tri[0][i] - tri[0][j]) for i, j in ((0, 1), (1, 2), (0, 2)))
        sampled = _brute_force(p, tri, n=200)
        assert d <= sampled + 1e-12
        assert sampled - d <= h / 200


def test_a_probe_on_the_curved_surface_snaps_to_the_nearest_facet_point(sphere):
    """Points of the true sphere between its mesh nodes lie outside the flat facets (by at
    most the facets' sagitta, far below half an element): each snaps, with a note, to the
    boundary point the brute-force search finds."""
    mesh = read_mesh(sphere)
    tri = mesh.points[boundary_facets(mesh.tets)]
    rng = np.random.default_rng(0)
    directions = rng.normal(size=(8, 3))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    snapped = 0
    for d in directions:
        point = R * d
        scene = _scene(sphere, point)
        probe = scene.probes[0]
        near = nearest_boundary_point(scene.mesh, point)
        if not scene.mesh.notes:  # the point fell on or inside a facet: found as is
            assert np.allclose(probe.point, point)
            continue
        snapped += 1
        assert "snapped to the nearest boundary point" in scene.mesh.notes[-1]
        dist = float(np.linalg.norm(probe.point - point))
        assert dist <= _brute_force(point, tri) + 1e-12
        assert dist == pytest.approx(near.distance, rel=1e-12)
        assert dist < 0.5 * near.size
        # the snapped point is inside the mesh: its tet's interpolation reproduces it
        x = scene.mesh.points[scene.mesh.tets[probe.tet]]
        assert np.allclose(probe.bary @ x, probe.point, atol=1e-15)
        assert probe.bary.min() >= 0.0 and probe.bary.sum() == pytest.approx(1.0)
    assert snapped >= 4  # most points of a sphere lie outside its facets


def test_a_probe_more_than_half_an_element_out_is_refused(sphere):
    mesh = read_mesh(sphere)
    lo, hi = mesh.bounding_box()
    h = np.linalg.norm(hi - lo) / 6.0  # more than an element of this mesh (0.3 R)
    with pytest.raises(SceneError, match=r"probe 'side' .* is outside the mesh, .* from its"):
        _scene(sphere, [R + h, 0.0, 0.0])
