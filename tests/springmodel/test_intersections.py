"""Tests of springmodel.intersections (spec §1.1, eqs. 2.22–2.25).

The references are independent of the module's barycentric ray casting: hit points come
from intersecting the ray with the four face planes, shape-function gradients from
inverting the 4x4 matrix of homogeneous vertex coordinates, area coordinates from the
area test of eqs. 2.23–2.24, vertex forces from ``np.add.at``.

Tolerances: coefficients are barycentric coordinates computed from ``J^-1``, so their
round-off grows like ``eps * cond`` with ``cond = L^3 / (6 V)`` (``L`` the longest edge);
tests on well-shaped tets use fixed tolerances of about 1e-12 (``cond`` below ~100), tests
on slivers scale them by ``cond``.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from springfem.axes import orthonormal_frame, rotation_matrix
from springfem.errors import MeshError
from springfem.mesh import box_mesh
from springmodel.intersections import (
    RayCast,
    axis_gradients,
    axis_vectors,
    barycenters,
    cast_rays,
    intersection_coefficients,
    intersection_matrix,
    intersection_points,
    point_in_triangle,
    shape_gradients,
)

EPS = np.finfo(float).eps
# face opposite vertex i, as vertex triples (a, b, c)
OPPOSITE = np.array([[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]])


# ---------------------------------------------------------------- independent references
def random_frames(rng: np.random.Generator, m: int) -> np.ndarray:
    """Random proper rotations (rows = axes) from QR of Gaussian matrices."""
    Q, R = np.linalg.qr(rng.normal(size=(m, 3, 3)))
    Q = Q * np.sign(np.diagonal(R, axis1=1, axis2=2))[:, None, :]  # Haar-distributed
    Q[np.linalg.det(Q) < 0, :, 2] *= -1
    return np.ascontiguousarray(Q.transpose(0, 2, 1))


def separate_tets(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points and tets for ``x (m, 4, 3)``, each tet with its own four nodes."""
    return x.reshape(-1, 3).copy(), np.arange(4 * len(x)).reshape(-1, 4)


def random_tets(rng: np.random.Generator, m: int, min_quality: float = 1e-2) -> np.ndarray:
    """Random well-shaped tets ``(m, 4, 3)``, positively oriented, ``6V / L^3 >= min_quality``."""
    out = np.empty((0, 4, 3))
    while len(out) < m:
        x = rng.normal(size=(2 * m, 4, 3)) * rng.uniform(0.1, 10, size=(2 * m, 1, 1))
        x += rng.uniform(-5, 5, size=(2 * m, 1, 3))
        keep = quality(x) >= min_quality
        out = np.concatenate([out, x[keep]])
    return orient(out[:m])


def near_sliver_tets(rng: np.random.Generator, m: int, h: np.ndarray) -> np.ndarray:
    """Tets whose fourth vertex lies at height ``h * L`` over the plane of the first three.

    Its foot point ranges over and well beyond the base triangle, giving caps (foot
    inside), slivers and wedges (foot outside) with ``6V / L^3`` down to about ``h``.
    """
    base = random_tets(rng, m)[:, :3]
    a, b, c = base[:, 0], base[:, 1], base[:, 2]
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    uv = rng.uniform(-1.0, 2.0, size=(m, 2))
    foot = a + uv[:, :1] * (b - a) + uv[:, 1:] * (c - a)
    size = np.linalg.norm(b - a, axis=1, keepdims=True)
    top = foot + np.asarray(h).reshape(-1, 1) * size * n
    return orient(np.stack([a, b, c, top], axis=1))


def quality(x: np.ndarray) -> np.ndarray:
    """``6 |V| / L^3`` with ``L`` the longest of the six edges."""
    e = x[:, 1:] - x[:, :1]
    det = np.linalg.det(e)
    pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    L = np.max([np.linalg.norm(x[:, i] - x[:, j], axis=1) for i, j in pairs], axis=0)
    return np.abs(det) / L**3


def orient(x: np.ndarray) -> np.ndarray:
    x = x.copy()
    neg = np.linalg.det(x[:, 1:] - x[:, :1]) < 0
    x[neg] = x[neg][:, [0, 2, 1, 3]]
    return x


def reference_gradients(x: np.ndarray) -> np.ndarray:
    """``grad N_i`` from the inverse of ``M = [[1, 1, 1, 1], [x_0 x_1 x_2 x_3]]``."""
    M = np.ones((len(x), 4, 4))
    M[:, 1:, :] = x.transpose(0, 2, 1)
    return np.linalg.inv(M)[:, :, 1:]  # lambda = M^-1 (1, x): grad lambda_i = row i, cols 1:


def reference_hits(x: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Ray-plane intersections ``x_b + t d`` with the smallest positive ``t`` over the four
    face planes, for ``x (m, 4, 3)`` and directions ``d (m, 3)``. Returns ``t`` and face."""
    xb = x.mean(axis=1)
    tf = np.full((len(x), 4), np.inf)
    for i, (a, b, c) in enumerate(OPPOSITE):
        n = np.cross(x[:, b] - x[:, a], x[:, c] - x[:, a])
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            t = np.einsum("kc,kc->k", n, x[:, a] - xb) / np.einsum("kc,kc->k", n, d)
        tf[:, i] = np.where(t > 0, t, np.inf)
    return tf.min(axis=1), tf.argmin(axis=1)


def check_invariants(x: np.ndarray, frames: np.ndarray, tol: np.ndarray | float) -> RayCast:
    """All invariants of one ray cast on separate tets ``x (m, 4, 3)``; ``tol`` per tet."""
    pts, tets = separate_tets(x)
    m = len(x)
    tol = np.broadcast_to(np.asarray(tol, dtype=float), (m,))
    rc = cast_rays(pts, tets, frames)
    C = rc.coefficients
    assert rc.all_hit.all()
    # partition of unity, designated opposite vertex exactly 0, all in [0, 1]
    np.testing.assert_allclose(C.sum(axis=1), 1.0, rtol=0, atol=8 * EPS)
    assert (np.take_along_axis(C, rc.faces[:, None, :], axis=1) == 0.0).all()
    assert ((C >= 0.0) & (C <= 1.0)).all()
    # eq. 2.25 against the independent ray-plane intersection, at the same face
    q = intersection_points(pts, tets, C)
    xb = x.mean(axis=1)
    L = np.linalg.norm(x[:, :, None] - x[:, None], axis=-1).max(axis=(1, 2))
    for j in range(6):
        d = frames[:, j // 2] * (1 if j % 2 == 0 else -1)
        t, face = reference_hits(x, d)
        err = np.linalg.norm(q[:, j] - (xb + t[:, None] * d), axis=1) / L
        assert (err <= tol).all(), f"ray {j}: max rel. error {err.max():.3g}"
        # the designated face is the hit face, or the hit is on an edge shared with it
        other = np.take_along_axis(C[:, :, j], face[:, None], axis=1)[:, 0]
        assert ((rc.faces[:, j] == face) | (other <= tol)).all()
    # docs/theory.rst#the-fast-kernel-identity identity: C[i, 2l] - C[i, 2l+1] = grad N_i . zeta_l^0
    zeta = axis_vectors(pts, tets, C)
    Gref = reference_gradients(x)
    rhs = np.einsum("kic,klc->kil", Gref, zeta)
    err = np.abs(axis_gradients(C) - rhs).max(axis=(1, 2))
    assert (err <= tol).all(), f"identity: max error {err.max():.3g}"
    return rc


# ---------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def jittered_mesh():
    """A 6-tet box mesh with jittered interior nodes and random frames (shared nodes)."""
    rng = np.random.default_rng(7)
    mesh = box_mesh((2.0, 1.0, 1.5), (4, 3, 3), split="six")
    h = 0.25
    pts = mesh.points + rng.uniform(-0.15 * h, 0.15 * h, mesh.points.shape)
    x = pts[mesh.tets]
    tets = mesh.tets.copy()
    neg = np.linalg.det(x[:, 1:] - x[:, :1]) < 0
    tets[neg] = tets[neg][:, [0, 2, 1, 3]]
    return pts, tets, random_frames(rng, len(tets))


# ---------------------------------------------------------------------- basic pieces
def test_barycenters_are_vertex_means(jittered_mesh):
    pts, tets, _ = jittered_mesh
    ref = np.array([pts[t].sum(axis=0) / 4 for t in tets])  # eq. 2.22, element by element
    np.testing.assert_allclose(barycenters(pts, tets), ref, rtol=0, atol=1e-15)


def test_shape_gradients_match_inverse_and_interpolate(jittered_mesh):
    pts, tets, _ = jittered_mesh
    G = shape_gradients(pts, tets)
    x = pts[tets]
    # grad entries are O(1/h) = O(10): 1e-12 is ~100 eps relative
    np.testing.assert_allclose(G, reference_gradients(x), rtol=0, atol=1e-12)
    # N_i is linear with N_i(x_j) = delta_ij: grad N_i . (x_j - x_0) = delta_ij - delta_i0
    dots = np.einsum("kic,kjc->kij", G, x - x[:, :1])
    expect = np.eye(4)[None] - np.eye(4)[:, :1][None]
    np.testing.assert_allclose(dots, np.broadcast_to(expect, dots.shape), atol=1e-13)


def test_cast_rays_returns_named_fields_and_matches_coefficients(jittered_mesh):
    pts, tets, frames = jittered_mesh
    rc = cast_rays(pts, tets, frames)
    m = len(tets)
    assert rc.coefficients.shape == (m, 4, 6) and rc.coefficients.dtype == np.float64
    assert rc.faces.shape == (m, 6) and rc.faces.dtype == np.int64
    assert rc.all_hit.shape == (m,) and rc.all_hit.dtype == bool
    np.testing.assert_array_equal(intersection_coefficients(pts, tets, frames), rc.coefficients)


def test_empty_mesh():
    rc = cast_rays(np.zeros((0, 3)), np.zeros((0, 4), dtype=np.int64), np.zeros((0, 3, 3)))
    assert rc.coefficients.shape == (0, 4, 6) and rc.faces.shape == (0, 6)
    assert rc.all_hit.shape == (0,)
    assert intersection_matrix(np.zeros((0, 4), dtype=np.int64), rc.coefficients, 5).shape == (
        0,
        5,
    )


def test_unit_tet_by_hand():
    """Unit tet, coordinate axes: hits worked out on paper."""
    pts = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    C = intersection_coefficients(pts, np.array([[0, 1, 2, 3]]), np.eye(3)[None])[0]
    for l in range(3):
        plus = np.full(4, 0.25)
        plus[0], plus[l + 1] = 0.0, 0.5  # x_b + e_l / 4 on the face x + y + z = 1
        minus = np.full(4, 0.25)
        minus[0], minus[l + 1] = 0.5, 0.0  # x_b - e_l / 4 on the face x_l = 0
        np.testing.assert_allclose(C[:, 2 * l], plus, atol=1e-15)
        np.testing.assert_allclose(C[:, 2 * l + 1], minus, atol=1e-15)


# ---------------------------------------------------------------------- invariants
def test_invariants_on_jittered_mesh(jittered_mesh):
    pts, tets, frames = jittered_mesh
    check_invariants(pts[tets], frames, tol=1e-12)


def test_invariants_on_random_tets():
    rng = np.random.default_rng(1)
    x = random_tets(rng, 2000, min_quality=1e-2)
    check_invariants(x, random_frames(rng, len(x)), tol=1e-12)


def test_points_lie_on_their_face_with_matching_area_coordinates(jittered_mesh):
    pts, tets, frames = jittered_mesh
    rc = cast_rays(pts, tets, frames)
    C = rc.coefficients
    q = intersection_points(pts, tets, C)
    x = pts[tets]
    for j in range(6):
        abc = OPPOSITE[rc.faces[:, j]]  # (m, 3) local vertex indices of the hit face
        a, b, c = (np.take_along_axis(x, abc[:, k, None, None], axis=1)[:, 0] for k in range(3))
        inside, xi, eta = point_in_triangle(q[:, j], a, b, c, tol=1e-9)  # eqs. 2.23–2.24
        assert inside.all()
        # xi, eta, 1 - xi - eta weigh a, b, c: they are the C entries of those vertices
        w = np.take_along_axis(C[:, :, j], abc, axis=1)
        np.testing.assert_allclose(np.column_stack([xi, eta, 1 - xi - eta]), w, atol=1e-12)
        # and the point is in the face plane (the area balance is blind to that to 1st order)
        n = np.cross(b - a, c - a)
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        np.testing.assert_allclose(np.einsum("kc,kc->k", q[:, j] - a, n), 0.0, atol=1e-14)


def test_axis_points_are_collinear_with_barycenter_on_opposite_sides(jittered_mesh):
    pts, tets, frames = jittered_mesh
    C = intersection_coefficients(pts, tets, frames)
    q = intersection_points(pts, tets, C)
    xb = barycenters(pts, tets)
    for l in range(3):
        d = frames[:, l]
        up, down = q[:, 2 * l] - xb, q[:, 2 * l + 1] - xb
        assert (np.einsum("kc,kc->k", up, d) > 0).all()
        assert (np.einsum("kc,kc->k", down, d) < 0).all()
        np.testing.assert_allclose(np.cross(up, d), 0.0, atol=1e-14)
        np.testing.assert_allclose(np.cross(down, d), 0.0, atol=1e-14)
    # zeta_l = q_2l - q_2l+1 points along +axis l
    zeta = axis_vectors(pts, tets, C)
    unit = zeta / np.linalg.norm(zeta, axis=2, keepdims=True)
    np.testing.assert_allclose(unit, frames, atol=1e-12)


def test_rigid_motion_leaves_coefficients_unchanged(jittered_mesh):
    pts, tets, frames = jittered_mesh
    C = intersection_coefficients(pts, tets, frames)
    R = rotation_matrix([0.3, -1.0, 0.7], 2.1)
    moved = pts @ R.T + np.array([3.0, -7.0, 0.5])
    C2 = intersection_coefficients(moved, tets, frames @ R.T)  # rotate mesh AND frames
    np.testing.assert_allclose(C2, C, rtol=0, atol=1e-12)


def test_affine_deformation_keeps_points_on_deformed_faces(jittered_mesh):
    """Eq. 2.25 with rest C is exact under affine maps: q(A x + b) = A q(x) + b, on faces."""
    pts, tets, frames = jittered_mesh
    rc = cast_rays(pts, tets, frames)
    A = np.array([[1.3, 0.2, -0.1], [0.05, 0.8, 0.3], [0.0, -0.2, 1.1]])
    moved = pts @ A.T + 1.0
    q = intersection_points(moved, tets, rc.coefficients)
    np.testing.assert_allclose(
        q, intersection_points(pts, tets, rc.coefficients) @ A.T + 1.0, atol=1e-13
    )
    x = moved[tets]
    for j in range(6):
        a, b, c = (
            np.take_along_axis(x, OPPOSITE[rc.faces[:, j]][:, k, None, None], axis=1)[:, 0]
            for k in range(3)
        )
        assert point_in_triangle(q[:, j], a, b, c)[0].all()


def test_vertex_permutation_permutes_rows():
    rng = np.random.default_rng(3)
    x = random_tets(rng, 300)
    frames = random_frames(rng, len(x))
    pts, tets = separate_tets(x)
    C = intersection_coefficients(pts, tets, frames)
    perm = np.array([2, 0, 3, 1])  # even permutation: orientation kept
    np.testing.assert_allclose(
        intersection_coefficients(pts, tets[:, perm], frames), C[:, perm], atol=1e-13
    )
    swap = np.array([1, 0, 2, 3])  # odd permutation: inverted tets are accepted too
    np.testing.assert_allclose(
        intersection_coefficients(pts, tets[:, swap], frames), C[:, swap], atol=1e-13
    )


def test_coefficients_do_not_depend_on_axis_lengths(jittered_mesh):
    pts, tets, frames = jittered_mesh
    C = intersection_coefficients(pts, tets, frames)
    scaled = frames * np.array([3.7, 0.01, 250.0])[None, :, None]
    np.testing.assert_allclose(intersection_coefficients(pts, tets, scaled), C, atol=1e-14)


def test_axis_gradients_reproduce_axis_vectors(jittered_mesh):
    """Fast-kernel form: zeta_l = sum_i G[i, l] x_i equals q_2l - q_2l+1
    (docs/theory.rst#the-fast-kernel-identity)."""
    pts, tets, frames = jittered_mesh
    C = intersection_coefficients(pts, tets, frames)
    G = axis_gradients(C)
    np.testing.assert_array_equal(G, C[:, :, [0, 2, 4]] - C[:, :, [1, 3, 5]])
    rng = np.random.default_rng(0)
    deformed = pts + 0.05 * rng.normal(size=pts.shape)
    zeta = np.einsum("kil,kic->klc", G, deformed[tets])
    np.testing.assert_allclose(zeta, axis_vectors(deformed, tets, C), atol=1e-14)


# ---------------------------------------------------------------------- sparse map
def test_intersection_matrix_maps_points_and_forces(jittered_mesh):
    pts, tets, frames = jittered_mesh
    C = intersection_coefficients(pts, tets, frames)
    S = intersection_matrix(tets, C, len(pts))
    assert sp.issparse(S) and S.format == "csr"
    assert S.shape == (6 * len(tets), len(pts)) and S.nnz == 24 * len(tets)
    assert (np.diff(S.indices.reshape(-1, 4), axis=1) > 0).all()  # sorted, as flagged
    np.testing.assert_allclose(
        S @ pts, intersection_points(pts, tets, C).reshape(-1, 3), rtol=0, atol=1e-14
    )
    # forces on intersection points go to vertices with the same coefficients
    rng = np.random.default_rng(5)
    F = rng.normal(size=(6 * len(tets), 3))
    expect = np.zeros_like(pts)
    contrib = np.einsum("kij,kjc->kic", C, F.reshape(-1, 6, 3))
    np.add.at(expect, tets, contrib)
    np.testing.assert_allclose(S.T @ F, expect, rtol=0, atol=1e-13)
    np.testing.assert_allclose(np.asarray(S.sum(axis=1)).ravel(), 1.0, atol=1e-15)


def test_intersection_matrix_rejects_wrong_shape(jittered_mesh):
    pts, tets, frames = jittered_mesh
    C = intersection_coefficients(pts, tets, frames)
    with pytest.raises(ValueError, match="C must have shape"):
        intersection_matrix(tets[1:], C, len(pts))


# ---------------------------------------------------------------------- edges and vertices
CORNER_TET = np.array([[0.0, 0, 0], [4, 0, 0], [0, 4, 0], [0, 0, 4]])  # x_b = (1, 1, 1)


def test_ray_through_a_vertex_exactly():
    """-(1,1,1) from x_b = (1,1,1) runs into vertex 0: three coordinates reach 0 at once,
    ties exact in floating point. The opposite ray hits the centroid of face 1-2-3."""
    frame = orthonormal_frame(-np.ones(3), [1.0, -1.0, 0.0])[None]
    rc = cast_rays(CORNER_TET, np.array([[0, 1, 2, 3]]), frame)
    C = rc.coefficients[0]
    assert rc.all_hit.all()
    assert rc.faces[0, 0] == 1  # first of the tied vertices 1, 2, 3
    np.testing.assert_allclose(C[:, 0], [1.0, 0.0, 0.0, 0.0], atol=1e-15)
    assert (C[1:, 0] == 0.0).all()  # the tie is exact, so are all three zeros
    assert rc.faces[0, 1] == 0
    np.testing.assert_allclose(C[:, 1], [0.0, 1 / 3, 1 / 3, 1 / 3], atol=1e-15)
    q = intersection_points(CORNER_TET, np.array([[0, 1, 2, 3]]), rc.coefficients)[0]
    np.testing.assert_allclose(q[0], [0.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(q[1], [4 / 3, 4 / 3, 4 / 3], atol=1e-15)


def test_ray_through_an_edge_exactly():
    """(1,1,-1) from x_b runs into the midpoint (2,2,0) of edge 1-2 (faces 0 and 3 tie);
    the opposite ray hits the midpoint (0,0,2) of the opposite edge 0-3."""
    frame = orthonormal_frame([1.0, 1.0, -1.0], [1.0, -1.0, 0.0])[None]
    rc = cast_rays(CORNER_TET, np.array([[0, 1, 2, 3]]), frame)
    C = rc.coefficients[0]
    assert rc.all_hit.all()
    assert rc.faces[0, 0] == 0  # first of the tied vertices 0 and 3
    np.testing.assert_allclose(C[:, 0], [0.0, 0.5, 0.5, 0.0], atol=1e-15)
    assert C[0, 0] == 0.0 and C[3, 0] == 0.0
    np.testing.assert_allclose(C[:, 1], [0.5, 0.0, 0.0, 0.5], atol=1e-15)


@pytest.mark.parametrize("seed", range(5))
def test_rays_through_vertices_and_edge_midpoints_of_general_tets(seed):
    """Ties up to round-off: the designated entry is exactly 0, the other tied ones ~0,
    none negative, and the column is the vertex (edge midpoint) to round-off."""
    rng = np.random.default_rng(seed)
    x = random_tets(rng, 1)[0]
    xb = x.mean(axis=0)
    tet = np.array([[0, 1, 2, 3]])
    for v in range(4):  # through vertex v; back through the centroid of the opposite face
        frame = orthonormal_frame(x[v] - xb, rng.normal(size=3))[None]
        rc = cast_rays(x, tet, frame)
        C = rc.coefficients[0]
        assert rc.all_hit.all() and (C >= 0).all()
        assert rc.faces[0, 0] != v and C[rc.faces[0, 0], 0] == 0.0
        np.testing.assert_allclose(C[:, 0], np.eye(4)[v], atol=1e-13)
        back = np.full(4, 1 / 3)
        back[v] = 0.0
        np.testing.assert_allclose(C[:, 1], back, atol=1e-13)
    for a, b in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]:
        # through the midpoint of edge a-b; back through the midpoint of the opposite edge
        frame = orthonormal_frame((x[a] + x[b]) / 2 - xb, rng.normal(size=3))[None]
        rc = cast_rays(x, tet, frame)
        C = rc.coefficients[0]
        assert rc.all_hit.all() and (C >= 0).all()
        assert rc.faces[0, 0] not in (a, b) and C[rc.faces[0, 0], 0] == 0.0
        expect = np.zeros(4)
        expect[[a, b]] = 0.5
        np.testing.assert_allclose(C[:, 0], expect, atol=1e-13)
        np.testing.assert_allclose(C[:, 1], 0.5 - expect, atol=1e-13)


def test_axis_parallel_to_a_face():
    """Along (1,-1,0) the coordinate of vertex 3 (face z = 0) stays at its value 1/4."""
    pts = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    frame = orthonormal_frame([1.0, -1.0, 0.0], [0.0, 0.0, 1.0])[None]
    rc = cast_rays(pts, np.array([[0, 1, 2, 3]]), frame)
    C = rc.coefficients[0]
    assert rc.all_hit.all()
    np.testing.assert_allclose(C[3, :2], 0.25, atol=1e-15)
    np.testing.assert_allclose(C[:, 0], [0.25, 0.5, 0.0, 0.25], atol=1e-15)  # hits y = 0
    np.testing.assert_allclose(C[:, 1], [0.25, 0.0, 0.5, 0.25], atol=1e-15)  # hits x = 0


# ---------------------------------------------------------------------- slivers, degeneracy
@pytest.mark.parametrize("h", [1e-2, 1e-4, 1e-6])
def test_classic_sliver(h):
    """Four nearly coplanar points on a square's corners, all edges long (a sliver)."""
    x = np.array([[[0.0, 0, 0], [1, 1, 0], [1, 0, h], [0, 1, h]]])
    x = orient(x)
    rng = np.random.default_rng(int(-np.log10(h)))
    frames = random_frames(rng, 200)
    x = np.repeat(x, 200, axis=0)
    check_invariants(x, frames, tol=1e-13 / quality(x))


@pytest.mark.parametrize("h", [1e-3, 1e-6])
def test_near_sliver_caps_wedges_and_slivers(h):
    rng = np.random.default_rng(11)
    x = near_sliver_tets(rng, 1000, np.full(1000, h))
    check_invariants(x, random_frames(rng, len(x)), tol=1e-13 / quality(x))


def test_degenerate_tets_are_rejected_by_id():
    rng = np.random.default_rng(2)
    x = random_tets(rng, 6)
    x[2, 3] = (x[2, 0] + x[2, 1] + x[2, 2]) / 3  # coplanar: zero volume
    x[4, 1] = x[4, 0]  # coincident vertices
    pts, tets = separate_tets(x)
    frames = random_frames(rng, 6)
    for f in (cast_rays, intersection_coefficients):
        with pytest.raises(ValueError, match=r"degenerate .*tets 2, 4\b") as info:
            f(pts, tets, frames)
        assert isinstance(info.value, MeshError)
    with pytest.raises(MeshError, match="tets 2, 4"):
        shape_gradients(pts, tets)


def test_bad_frames_are_rejected():
    x = random_tets(np.random.default_rng(0), 3)
    pts, tets = separate_tets(x)
    frames = np.repeat(np.eye(3)[None], 3, axis=0)
    with pytest.raises(ValueError, match=r"shape \(3, 3, 3\)"):
        cast_rays(pts, tets, frames[:2])
    frames[1, 2] = 0.0
    with pytest.raises(ValueError, match="axes at elements 1"):
        cast_rays(pts, tets, frames)


# ---------------------------------------------------------------------- point in triangle
def test_point_in_triangle_area_coordinates():
    rng = np.random.default_rng(4)
    a, b, c = rng.normal(size=(3, 500, 3))
    w = rng.dirichlet(np.ones(3), size=500)
    q = w[:, :1] * a + w[:, 1:2] * b + w[:, 2:] * c
    inside, xi, eta = point_in_triangle(q, a, b, c)
    good = quality(np.stack([a, b, c, a + np.cross(b - a, c - a)], 1)) > 1e-3
    assert inside[good].all()
    np.testing.assert_allclose(xi[good], w[good, 0], atol=1e-10)
    np.testing.assert_allclose(eta[good], w[good, 1], atol=1e-10)
    # outside: one weight negative
    out = w.copy()
    out[:, 0] = -0.1
    out[:, 1:] *= 1.1 / out[:, 1:].sum(axis=1, keepdims=True)
    q = out[:, :1] * a + out[:, 1:2] * b + out[:, 2:] * c
    assert not point_in_triangle(q, a, b, c)[0][good].any()


def test_point_in_triangle_on_edges_and_vertices():
    a, b, c = np.array([0.0, 0, 0]), np.array([1.0, 0, 0]), np.array([0.0, 1, 0])
    for q, weights in [(a, (1, 0)), (b, (0, 1)), (c, (0, 0)), ((a + b) / 2, (0.5, 0.5))]:
        inside, xi, eta = point_in_triangle(q, a, b, c)
        assert inside
        np.testing.assert_allclose([xi, eta], weights, atol=1e-15)
    assert not point_in_triangle(np.array([0.6, 0.6, 0.0]), a, b, c)[0]


# ---------------------------------------------------------------------- property tests
unit_coord = st.floats(-10.0, 10.0, allow_nan=False, allow_infinity=False, allow_subnormal=False)


def budgets(n: int):
    """Parametrize a property test over a fifth of its ``n`` examples and (``-m slow``) all."""
    return pytest.mark.parametrize(
        "n_examples",
        [
            pytest.param(n // 5, id="quick"),
            pytest.param(n, id="full", marks=pytest.mark.slow),
        ],
    )


def single_tet_property(n_examples: int):
    """The single-tet property (:func:`_single_tets`), searching ``n_examples`` cases."""
    # found by hypothesis: all_hit once used a fixed 1e-12 bound, too tight for slivers
    found = example(
        base=np.array([[1.0, 1.0, 1.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
        uv=(0.0, 0.0),
        log_h=-6.0,
        frame_seed=np.array([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0], [1.0, 1.0, 1.0]]),
    )
    cases = given(
        base=arrays(np.float64, (3, 3), elements=unit_coord),
        uv=st.tuples(st.floats(-1.0, 2.0), st.floats(-1.0, 2.0)),
        log_h=st.floats(-6.0, 0.0),
        frame_seed=arrays(np.float64, (3, 3), elements=st.floats(-1.0, 1.0)),
    )
    return settings(
        max_examples=n_examples, deadline=None, suppress_health_check=[HealthCheck.filter_too_much]
    )(found(cases(_single_tets)))


def _single_tets(base, uv, log_h, frame_seed):
    """Random base triangle, fourth vertex at height 10^log_h L over a point of its plane
    (inside or outside the triangle): caps, wedges, slivers, with 6V/L^3 down to ~1e-6."""
    a, b, c = base
    n = np.cross(b - a, c - a)
    size = max(np.linalg.norm(b - a), np.linalg.norm(c - a), np.linalg.norm(c - b))
    assume(size > 1e-3 and np.linalg.norm(n) > 0.05 * size**2)  # a proper base triangle
    assume(abs(np.linalg.det(frame_seed)) > 1e-2)
    top = a + uv[0] * (b - a) + uv[1] * (c - a) + 10.0**log_h * size * n / np.linalg.norm(n)
    x = orient(np.array([[a, b, c, top]]))
    assume(quality(x)[0] > 5e-7)
    Q, _ = np.linalg.qr(frame_seed)
    frames = (Q * np.sign(np.linalg.det(Q))).T[None]
    check_invariants(x, frames, tol=1e-13 / quality(x))


@budgets(250)
def test_property_single_tets(n_examples):
    single_tet_property(n_examples)()


def _batches(seed, log_h):
    """Tens of thousands of tets: batches of 200 random tets, half of them near-slivers."""
    rng = np.random.default_rng(seed)
    x = np.concatenate(
        [random_tets(rng, 100), near_sliver_tets(rng, 100, 10.0 ** rng.uniform(log_h, 0, 100))]
    )
    check_invariants(x, random_frames(rng, len(x)), tol=1e-13 / quality(x))


@budgets(100)
def test_property_batches(n_examples):
    cases = given(seed=st.integers(0, 2**32 - 1), log_h=st.floats(-6.0, 0.0))
    settings(max_examples=n_examples, deadline=None)(cases(_batches))()
