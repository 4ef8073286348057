"""Land et al. 2015's problem-3 fibre field (springfem.land_fibres) against its definition:
points built from the ellipsoid's own parametrisation ``x(t, u, v)``, its tangents by finite
differences, the surface normal from the gradient of the implicit level function, the helix
angle on both surfaces; the ``[axes] type = "land-ellipsoid"`` scene key and the P2 fibres
at the quadrature points."""

from __future__ import annotations

import numpy as np
import pytest

from reference_fem.point_fibres import quadrature_frames
from reference_fem.space import Space
from springfem.errors import InputError, SceneError
from springfem.land_fibres import ellipsoid_parameter, land_basis, land_frames
from springfem.scene import scene_from_dict

RNG = np.random.default_rng(7)
N = 200
T = RNG.uniform(0.0, 1.0, N)
U = RNG.uniform(-np.pi + 0.05, -np.arccos(5.0 / 17.0), N)  # below the base plane z = 5
V = RNG.uniform(-np.pi, np.pi, N)


def _x(t, u, v):
    """Land's parametrisation of the ellipsoid ``t`` (radii 7 + 3t, 17 + 3t)."""
    a, c = 7.0 + 3.0 * t, 17.0 + 3.0 * t
    return np.stack([a * np.sin(u) * np.cos(v), a * np.sin(u) * np.sin(v), c * np.cos(u)], -1)


def _unit(w):
    return w / np.linalg.norm(w, axis=-1, keepdims=True)


def test_parameter_recovers_the_ellipsoid_of_each_point():
    # bisection to round-off: 1e-12 in t
    assert np.abs(ellipsoid_parameter(_x(T, U, V)) - T).max() < 1e-12


def test_tangents_are_the_finite_difference_derivatives():
    # e_u, e_v: the normalised dx/du, dx/dv (central differences, O(h^2) ~ 1e-10)
    _, e_u, e_v, n = land_basis(_x(T, U, V))
    h = 1e-5
    fd_u = _unit(_x(T, U + h, V) - _x(T, U - h, V))
    fd_v = _unit(_x(T, U, V + h) - _x(T, U, V - h))
    assert np.abs(e_u - fd_u).max() < 1e-8
    assert np.abs(e_v - fd_v).max() < 1e-8
    # the normal: the gradient of rho^2 / a^2 + z^2 / c^2 at fixed t, outwards
    x = _x(T, U, V)
    a, c = 7.0 + 3.0 * T, 17.0 + 3.0 * T
    grad = _unit(np.stack([x[:, 0] / a**2, x[:, 1] / a**2, x[:, 2] / c**2], -1))
    assert np.abs(n - grad).max() < 1e-12


def test_fibre_is_tangent_and_follows_the_helix_angle():
    x = _x(T, U, V)
    frames = land_frames(x)
    _, e_u, e_v, n = land_basis(x)
    f = frames[:, 0]
    assert np.allclose(np.einsum("pij,pkj->pik", frames, frames), np.eye(3), atol=1e-12)
    assert np.abs(np.einsum("pi,pi->p", f, n)).max() < 1e-12  # in the t surface
    # alpha = 90 - 180 t: sin(alpha) = f . e_u, cos(alpha) = f . e_v (Land's convention)
    alpha = np.degrees(np.arctan2(np.einsum("pi,pi->p", f, e_u), np.einsum("pi,pi->p", f, e_v)))
    assert np.abs(alpha - (90.0 - 180.0 * T)).max() < 1e-9


def test_endo_fibre_is_longitudinal_epi_too_and_midwall_circumferential():
    u, v = U[:5], V[:5]
    for t, along in ((0.0, "meridian"), (0.5, "parallel"), (1.0, "meridian")):
        x = _x(np.full(5, t), u, v)
        f = land_frames(x)[:, 0]
        meridian = _unit(_x(np.full(5, t), u + 1e-6, v) - x)
        parallel = np.stack([-np.sin(v), np.cos(v), np.zeros(5)], -1)
        ref = meridian if along == "meridian" else parallel
        assert np.abs(np.abs(np.einsum("pi,pi->p", f, ref)) - 1.0).max() < 1e-6, (t, along)


def test_points_outside_the_wall_are_clamped_or_refused():
    x = np.array([[0.0, 0.0, -30.0], [0.0, 0.0, -12.0], [1.0, 0.0, 0.0]])
    assert ellipsoid_parameter(x).tolist() == [1.0, 0.0, 0.0]
    with pytest.raises(InputError, match="outside the wall"):
        ellipsoid_parameter(x, tolerance=0.05)


LV = {
    "mesh": {"generator": "ellipsoid", "size": 6.0},
    "material": {"law": "guccione", "C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0,
                 "kappa": 100.0},
    "axes": {"type": "land-ellipsoid"},
    "boundary": [{"region": "base", "fix": ["x", "y", "z"]}],
}  # fmt: skip


def test_scene_key_gives_the_closed_form_at_barycentres_and_quadrature_points():
    scene = scene_from_dict(LV)
    c = scene.mesh.centers()
    assert np.allclose(scene.frames, land_frames(c), atol=1e-12)
    assert np.allclose(scene.mesh.cell_data["transmural_depth"], ellipsoid_parameter(c))
    # P2: each quadrature point's own fibre, at x = sum_i lambda_i x_i of its tet
    space = Space(scene.mesh, 2, 4)
    q = quadrature_frames(scene, space)
    from skfem.quadrature import get_quadrature
    from skfem.refdom import RefTet

    X, _ = get_quadrature(RefTet, 4)
    lam = np.vstack([1.0 - X.sum(axis=0), X])  # (4, nq) barycentric coordinates
    pts = np.einsum("iq,eij->eqj", lam, scene.mesh.points[scene.mesh.tets])
    assert q.shape == (scene.mesh.n_tets, X.shape[1], 3, 3)
    assert np.allclose(q, land_frames(pts), atol=1e-12)


def test_radii_that_do_not_fit_the_mesh_are_one_clear_error():
    data = {**LV, "axes": {"type": "land-ellipsoid", "endo_radii": [3.0, 8.0],
                           "epi_radii": [4.0, 9.0]}}  # fmt: skip
    with pytest.raises(SceneError, match="endo_radii"):
        scene_from_dict(data)
    data = {**LV, "axes": {"type": "land-ellipsoid", "epi_radii": [5.0, 20.0]}}
    with pytest.raises(SceneError, match="epi_radii"):
        scene_from_dict(data)
