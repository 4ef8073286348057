"""Uniform refinement (each tet into 8): volumes, boundary, regions (springfem.mesh.refine)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import Delaunay

from springfem.mesh import TetMesh, boundary_facets, box_mesh, refine_uniform, tet_volumes


def _delaunay_mesh(seed: int = 3) -> TetMesh:
    rng = np.random.default_rng(seed)
    pts = np.vstack([rng.random((40, 3)), np.array(np.meshgrid(*[[0, 1]] * 3)).reshape(3, -1).T])
    tets = Delaunay(pts).simplices.astype(np.int64)
    vol = tet_volumes(pts, tets)
    tets = tets[np.abs(vol) > 1e-9]
    neg = tet_volumes(pts, tets) < 0
    tets[neg] = tets[neg][:, [0, 2, 1, 3]]
    return TetMesh(pts, tets)


MESHES = {
    "six": lambda: box_mesh((1.0, 2.0, 0.5), (2, 1, 3), split="six"),
    "five": lambda: box_mesh((1.0, 1.0, 1.0), (2, 2, 2), split="five"),
    "delaunay": _delaunay_mesh,
}


def _keys(tri: np.ndarray) -> set[tuple[int, ...]]:
    return {tuple(t) for t in np.sort(tri, axis=1)}


@pytest.mark.parametrize("name", sorted(MESHES))
def test_children_fill_their_parent(name):
    m = MESHES[name]()
    r = refine_uniform(m)
    child = tet_volumes(r.points, r.tets).reshape(-1, 8)
    # every child positively oriented, and the 8 children add up to the parent (round-off)
    assert (child > 0).all()
    np.testing.assert_allclose(child.sum(axis=1), tet_volumes(m.points, m.tets), rtol=1e-12)
    # an edge midpoint per unique edge, shared by the tets around it (a conforming mesh)
    edges = {
        tuple(sorted(e)) for t in m.tets for e in zip(t[[0, 0, 0, 1, 1, 2]], t[[1, 2, 3, 2, 3, 3]])
    }
    assert r.n_points == m.n_points + len(edges)


@pytest.mark.parametrize("name", sorted(MESHES))
def test_boundary_preserved(name):
    m = MESHES[name]()
    outer = boundary_facets(m.tets)
    m.facet_sets["outer"] = outer
    r = refine_uniform(m)
    refined_outer = boundary_facets(r.tets)
    # conforming: exactly the 4 children of each old boundary triangle are on the boundary
    assert len(refined_outer) == 4 * len(outer)
    assert _keys(refined_outer) == _keys(r.facet_sets["outer"])

    def normals(pts, tri):
        return np.cross(pts[tri[:, 1]] - pts[tri[:, 0]], pts[tri[:, 2]] - pts[tri[:, 0]])

    # same area vector (summed over the surface, per outward orientation) and same area
    n_old, n_new = normals(m.points, outer), normals(r.points, r.facet_sets["outer"])
    np.testing.assert_allclose(
        np.linalg.norm(n_new, axis=1).sum(), np.linalg.norm(n_old, axis=1).sum(), rtol=1e-12
    )
    # facet-set children keep their parent's outward orientation
    parent = np.repeat(n_old, 4, axis=0)
    assert (np.einsum("ij,ij->i", parent, n_new) > 0).all()


def test_regions_follow():
    m = box_mesh((1.0, 1.0, 1.0), (2, 2, 2), split="six")
    x0 = np.flatnonzero(np.isclose(m.points[:, 0], 0.0))
    m.node_sets["x0"] = x0
    m.cell_sets["first"] = np.array([0, 5])
    m.cell_data["fiber"] = np.tile([1.0, 0.0, 0.0], (m.n_tets, 1))
    r = refine_uniform(m)
    # the refined x = 0 face: a 5 x 5 grid of nodes, all on the plane
    assert len(r.node_sets["x0"]) == 25
    assert np.allclose(r.points[r.node_sets["x0"], 0], 0.0)
    np.testing.assert_array_equal(r.cell_sets["first"], np.r_[0:8, 40:48])
    assert r.cell_data["fiber"].shape == (8 * m.n_tets, 3)
