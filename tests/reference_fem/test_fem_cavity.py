"""The FEM hands the cavity volume its P2 facet nodes: the space's vertex and edge nodes
of each endocardial facet plus the nodal displacement (P1: none, the facets are flat)."""

from __future__ import annotations

import numpy as np

from reference_fem.cavity import facet_nodes
from reference_fem.space import Space
from springfem.cardiac import oriented_facets
from springfem.ellipsoid import ellipsoid_mesh
from springfem.quadratic_facets import straight_facet_nodes


def _phi(x):  # any quadratic map: P2 interpolates it exactly at every node
    return x + 0.01 * np.stack([x[:, 1] * x[:, 2], x[:, 0] ** 2, x[:, 0] * x[:, 1]], axis=1)


def test_p2_facet_nodes_are_the_mapped_vertices_and_edge_midpoints():
    mesh = ellipsoid_mesh(size=5.0)
    space = Space(mesh, order=2)
    tris, _ = oriented_facets(mesh)
    u = (_phi(space.node_coordinates) - space.node_coordinates).ravel()
    # independent: the rest facets' own vertices and edge midpoints, mapped
    want = _phi(straight_facet_nodes(mesh.points, tris).reshape(-1, 3)).reshape(-1, 6, 3)
    nodes = facet_nodes(space)
    np.testing.assert_allclose(nodes(u, tris), want, rtol=0, atol=1e-12)
    # the mixed formulation's state has the vertex pressures after the displacement block
    mixed = np.concatenate([u, np.full(mesh.n_points, 7.0)])
    np.testing.assert_allclose(nodes(mixed, tris), want, rtol=0, atol=1e-12)


def test_p1_has_no_facet_nodes():
    assert facet_nodes(Space(ellipsoid_mesh(size=5.0), order=1)) is None
