"""The cavity volume over quadratic (6-node) facets: the volume a P2 field encloses.

References independent of the code under test: exact monomial integrals on the triangle,
the volume of a polynomially mapped polyhedron integrated as ``int det(grad phi) dX`` over
its cone tets with scikit-fem's tet quadrature, a fine flat subdivision of the curved
surface, the cube law of uniform scalings and the truncated ellipsoid's closed-form volume.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from skfem.quadrature import get_quadrature
from skfem.refdom import RefTet
from support.meshes import ventricle_mesh

from springfem.cardiac import cavity_volume, oriented_facets
from springfem.ellipsoid import BASE_Z, ellipsoid_mesh
from springfem.ellipsoid import cavity_volume as exact_cavity
from springfem.errors import InputError
from springfem.quadratic_facets import quadratic_facet_integral, straight_facet_nodes, triangle_rule

A, B, G = 0.01, 0.02, 0.01  # 1/mm: grad phi triangular, diagonal >= 0.56, det >= 0.3 (one-to-one)


def phi(x):
    """A quadratic map that keeps the base plane z = 5 in itself (u_z = 0 there)."""
    x = np.asarray(x, dtype=float)
    X, Y, Z = x[..., 0], x[..., 1], x[..., 2] - BASE_Z
    return np.stack([X + A * X * Z, Y + B * Y**2, x[..., 2] + G * Z**2], axis=-1)


def det_grad_phi(x):
    Y, Z = x[..., 1], x[..., 2] - BASE_Z
    # grad phi = [[1 + A Z, 0, A X], [0, 1 + 2 B Y, 0], [0, 0, 1 + 2 G Z]]
    return (1 + A * Z) * (1 + 2 * B * Y) * (1 + 2 * G * Z)


@pytest.fixture(scope="module")
def lv():
    m = ventricle_mesh(4.0)
    tris, rim = oriented_facets(m)
    return m, tris, rim


def mapped_volume(m, tris, rim):
    """int det(grad phi) dX over the rest cavity, as signed cone tets from the rim centroid
    (in the base plane, so the cap's cone is flat), with a degree-3-exact tet rule."""
    c = m.points[rim].mean(axis=0)
    X, W = get_quadrature(RefTet, 3)  # exact for det's degree 3
    total = 0.0
    for t in m.points[tris]:
        v = np.vstack([c, t])  # (4, 3); barycentric map of the reference tet
        J = (v[1:] - v[0]).T
        pts = v[0] + (J @ X).T
        total += np.linalg.det(J) * (W @ det_grad_phi(pts))
    return -total  # facet normals point into the cavity


def test_the_triangle_rule_integrates_degree_5_exactly():
    p, w = triangle_rule()
    for a in range(6):
        for b in range(6 - a):
            exact = math.factorial(a) * math.factorial(b) / math.factorial(a + b + 2)
            got = w @ (p[:, 0] ** a * p[:, 1] ** b)
            assert got == pytest.approx(exact, rel=1e-13, abs=1e-16), (a, b)
    # and no further: the integrand of degree 4 needs the margin, degree 6 is already off
    assert abs(w @ p[:, 0] ** 6 - 2 / math.factorial(8)) > 1e-6


def test_a_quadratic_map_gives_the_mapped_body_volume_exactly(lv):
    m, tris, rim = lv
    ref = mapped_volume(m, tris, rim)
    nodes = phi(straight_facet_nodes(m.points, tris))  # P2 interpolates a quadratic exactly
    p2 = cavity_volume(m, phi(m.points), facet_nodes=nodes)
    flat = cavity_volume(m, phi(m.points))
    assert p2 == pytest.approx(ref, rel=1e-12)  # exact up to round-off
    # the vertex-only volume misses the curved facets' bulge: visibly off on this mesh
    assert abs(flat / ref - 1) > 1e-4
    assert abs(flat / ref - 1) > 1e6 * abs(p2 / ref - 1)


def test_a_fine_flat_subdivision_of_the_curved_facets_converges_to_it(lv):
    # a second, independent reference: split each rest facet into n^2 flat triangles, map
    # their corners by phi, sum det/6: converges as 1/n^2 to the curved surface's volume
    m, tris, rim = lv
    c = phi(m.points[rim]).mean(axis=0)
    p2 = cavity_volume(m, phi(m.points), facet_nodes=phi(straight_facet_nodes(m.points, tris)))

    def subdivided(n):
        ij = [(i, j) for i in range(n + 1) for j in range(n + 1 - i)]
        idx = {k: q for q, k in enumerate(ij)}
        sub = []
        for i, j in ij:
            if i + j < n:
                sub.append((idx[i, j], idx[i + 1, j], idx[i, j + 1]))
            if i + j < n - 1:
                sub.append((idx[i + 1, j], idx[i + 1, j + 1], idx[i, j + 1]))
        lam = np.array([(1 - (i + j) / n, i / n, j / n) for i, j in ij])
        pts = phi(np.einsum("pa,kai->kpi", lam, m.points[tris])) - c
        s = np.asarray(sub)
        return -np.linalg.det(np.stack([pts[:, s[:, a]] for a in range(3)], axis=2)).sum() / 6

    v16, v32 = subdivided(16), subdivided(32)
    assert abs(v32 / p2 - 1) < 0.3 * abs(v16 / p2 - 1)  # second order: ~1/4 per halving
    # Richardson's (4 v32 - v16) / 3 removes the 1/n^2 term: the rest is O(1/n^4) ~ 1e-9,
    # a thousand times below the vertex-only volume's error on this mesh (> 1e-4)
    assert (4 * v32 - v16) / 3 == pytest.approx(p2, rel=1e-8)


def test_affine_maps_scale_both_volumes_by_the_determinant(lv):
    m, tris, _ = lv
    rng = np.random.default_rng(3)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.linalg.det(q))
    lam = 1.2
    moved = lam * m.points @ q.T + [1.0, -2.0, 3.0]
    nodes = lam * straight_facet_nodes(m.points, tris) @ q.T + [1.0, -2.0, 3.0]
    v0 = cavity_volume(m, m.points)
    assert cavity_volume(m, moved) == pytest.approx(lam**3 * v0, rel=1e-12)
    assert cavity_volume(m, moved, facet_nodes=nodes) == pytest.approx(lam**3 * v0, rel=1e-12)


def test_at_rest_straight_p2_facets_equal_the_flat_ones_and_curved_ones_converge_faster():
    # the gmsh mesh is linear: reference_fem puts the P2 midside nodes at the edge midpoints,
    # so at rest the P2 cavity is the inscribed polyhedron (O(h^2) short of the ellipsoid).
    # Midside nodes moved onto the ellipsoid make the facets curved: O(h^3) or better.
    errs = {}
    for size in (4.0, 2.0):
        m = ellipsoid_mesh(size=size)
        tris, _ = oriented_facets(m)
        straight = straight_facet_nodes(m.points, tris)
        flat = cavity_volume(m, m.points)
        assert cavity_volume(m, m.points, facet_nodes=straight) == pytest.approx(flat, rel=1e-13)
        on_surface = _onto_endo(straight)
        curved = cavity_volume(m, m.points, facet_nodes=on_surface)
        errs[size] = (abs(flat / exact_cavity() - 1), abs(curved / exact_cavity() - 1))
    (f4, c4), (f2, c2) = errs[4.0], errs[2.0]
    assert f2 < 0.35 * f4  # flat: second order (h^2 -> 1/4)
    assert c2 < 0.125 * c4  # curved: at least third order (h^3 -> 1/8)
    assert c2 < 0.01 * f2  # and far closer on the same mesh


def _onto_endo(nodes, a=7.0, c=17.0):
    """Move the midside nodes onto the endocardial ellipsoid (the rim's within the base)."""
    out = nodes.copy()
    for e in range(3, 6):
        p = out[:, e]
        level = np.sqrt((p[:, 0] ** 2 + p[:, 1] ** 2) / a**2 + p[:, 2] ** 2 / c**2)
        q = p / level[:, None]
        base = np.abs(p[:, 2] - BASE_Z) < 1e-9
        r = a * math.sqrt(1 - BASE_Z**2 / c**2) / np.hypot(p[base, 0], p[base, 1])
        q[base] = np.column_stack([p[base, 0] * r, p[base, 1] * r, p[base, 2]])
        out[:, e] = q
    return out


def test_a_corner_tet_is_its_own_volume():
    x = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]])
    nodes = straight_facet_nodes(x, np.array([[0, 1, 2]]))
    assert quadratic_facet_integral(nodes, np.zeros(3)) == pytest.approx(1 / 6, rel=1e-14)


def test_wrongly_shaped_facet_nodes_are_a_one_line_error(lv):
    m, tris, _ = lv
    with pytest.raises(InputError, match=r"facet_nodes must be \(\d+, 6, 3\)"):
        cavity_volume(m, m.points, facet_nodes=np.zeros((len(tris), 3, 3)))
