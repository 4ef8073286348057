"""``[fem] geometry = "curved"``: P2 edge nodes on the true ellipsoids (isoparametric tets).

Independent references: the closed-form volumes of the truncated ellipsoid
(:func:`springfem.ellipsoid.wall_volume`, :func:`springfem.ellipsoid.cavity_volume`) and the
surface equations. Straight-sided P2 tets carry the faceted geometry's ``O(h^2)`` volume
error; curved ones must converge at a higher order.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from reference_fem.cavity import facet_nodes
from reference_fem.problem import curved_edge_nodes_of
from reference_fem.space import Space, edge_list
from springfem.ellipsoid import (
    ENDO,
    EPI,
    cavity_volume,
    curved_edge_nodes,
    ellipsoid_mesh,
    project_to_ellipsoid,
    wall_volume,
)
from springfem.errors import InputError, SceneError
from springfem.quadratic_facets import quadratic_facet_integral
from springfem.scene import scene_from_dict

SIZES = (6.0, 3.0)


def _errors(size: float) -> tuple[float, dict]:
    """Mean endocardial edge ``h`` and the relative wall / cavity volume errors, straight
    and curved."""
    mesh = ellipsoid_mesh(size=size)
    out = {}
    for name, nodes in (("straight", None), ("curved", curved_edge_nodes(mesh, edge_list(mesh)))):
        s = Space(mesh, 2, 2, nodes)
        rest = facet_nodes(s)(np.zeros(s.n_dofs), mesh.facet_sets["endo"])
        cav = abs(quadratic_facet_integral(rest, np.array([0.0, 0.0, 5.0])))  # base: (x-c).n = 0
        out[name] = (abs(s.dx.sum() / wall_volume() - 1), abs(cav / cavity_volume() - 1))
    tri = mesh.facet_sets["endo"]
    h = float(np.linalg.norm(mesh.points[tri[:, [1, 2, 0]]] - mesh.points[tri], axis=2).mean())
    return h, out


def test_curved_volumes_converge_faster_than_faceted():
    (h0, e0), (h1, e1) = (_errors(s) for s in SIZES)
    order = {k: [math.log(e0[k][i] / e1[k][i]) / math.log(h0 / h1) for i in (0, 1)]
             for k in e0}  # fmt: skip
    # faceted: the cavity's O(h^2) (measured 2.1)
    assert 1.5 < order["straight"][1] < 2.6
    # isoparametric P2: O(h^3) or better on both volumes (measured 4.4 / 4.2), far smaller
    assert min(order["curved"]) > 3.0
    assert e1["curved"][1] < 0.01 * e1["straight"][1]


def test_curved_edge_nodes_lie_on_the_surfaces():
    mesh = ellipsoid_mesh(size=5.0)
    edges = edge_list(mesh)
    x = curved_edge_nodes(mesh, edges)
    n = mesh.n_points
    keys = edges.min(axis=1) * n + edges.max(axis=1)
    for name, (a, c) in (("endo", ENDO), ("epi", EPI)):
        tri = mesh.facet_sets[name][:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2)
        on = np.isin(keys, tri.min(axis=1) * n + tri.max(axis=1))
        level = (x[on, 0] ** 2 + x[on, 1] ** 2) / a**2 + x[on, 2] ** 2 / c**2
        np.testing.assert_allclose(level, 1.0, atol=1e-12)
        assert x[on, 2].max() <= 5.0 + 1e-12  # the basal ring's nodes stay in the base plane
    inner = ~np.isin(keys, np.concatenate([
        (t := mesh.facet_sets[s][:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2)).min(axis=1) * n
        + t.max(axis=1) for s in ("endo", "epi")]))  # fmt: skip
    np.testing.assert_allclose(x[inner], mesh.points[edges[inner]].mean(axis=1), atol=0)


def test_projection_keeps_base_points_in_the_plane():
    p = project_to_ellipsoid(np.array([[5.0, 5.0, 5.0], [0.1, 0.0, -16.0]]), ENDO, 5.0)
    assert p[0, 2] == 5.0 and p[1, 2] < -16.9
    np.testing.assert_allclose((p[:, :2] ** 2).sum(1) / 49 + p[:, 2] ** 2 / 289, 1.0)


def _scene(mesh: dict, fem: dict):
    base = "base" if mesh["generator"] == "ellipsoid" else "x_min"
    return scene_from_dict({
        "mesh": mesh,
        "material": {"law": "neo-hookean", "E": 10.0, "nu": 0.3},
        "boundary": [{"region": base, "fix": ["x", "y", "z"]}],
        "fem": fem})  # fmt: skip


def test_curved_geometry_needs_an_ellipsoid_and_order_2():
    with pytest.raises(SceneError, match="geometry"):
        _scene({"generator": "ellipsoid", "size": 6.0}, {"order": 1, "geometry": "curved"})
    box = _scene({"generator": "box", "size": [1.0, 1.0, 1.0], "divisions": [1, 1, 1]},
                 {"order": 2, "geometry": "curved"})  # fmt: skip
    with pytest.raises(InputError, match='generator = "ellipsoid"'):
        curved_edge_nodes_of(box)
    ell = _scene({"generator": "ellipsoid", "size": 6.0}, {"order": 2, "geometry": "curved"})
    assert curved_edge_nodes_of(ell).shape == (len(edge_list(ell.mesh)), 3)
