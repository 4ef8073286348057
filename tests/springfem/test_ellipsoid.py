"""Truncated-ellipsoid ventricle mesh (gmsh) and rule-based fibres.

References: the exact wall volume of the truncated ellipsoids; the surfaces' equations
for the facet regions; the exact Laplace solution of a spherical shell cut at its equator
(``d = (1/r_in - 1/r) / (1/r_in - 1/r_out)``, whose gradient is radial, so the natural
boundary condition on the plane z = 0 holds) for the transmural depth and the frames.
"""

import numpy as np
import pytest
from support.meshes import ventricle_mesh

from springfem.ellipsoid import ENDO, EPI, cavity_volume, ellipsoid_mesh, wall_volume
from springfem.errors import InputError
from springfem.fibres import rule_based_frames, transmural_depth


@pytest.fixture(scope="module")
def lv():
    return ventricle_mesh(2.0)


@pytest.fixture(scope="module")
def shell():
    return ellipsoid_mesh(size=1.5, endo=(7.0, 7.0), epi=(10.0, 10.0), base_z=0.0)


def test_regions_lie_on_their_surfaces(lv):
    x = lv.points
    for name, (a, c) in (("endo", ENDO), ("epi", EPI)):
        p = x[np.unique(lv.facet_sets[name])]
        level = (p[:, 0] ** 2 + p[:, 1] ** 2) / a**2 + p[:, 2] ** 2 / c**2
        assert np.abs(level - 1).max() < 1e-6  # gmsh puts boundary nodes on the CAD surface
    assert np.abs(x[np.unique(lv.facet_sets["base"]), 2] - 5.0).max() < 1e-9
    # the three regions are the whole boundary, each facet once
    n = sum(len(v) for v in lv.facet_sets.values())
    assert n == len(lv.boundary_facets())
    assert (lv.volumes() > 0).all()


def test_volume_converges_to_the_exact_wall_volume():
    # chords of length h sit ~h^2/(8R) inside a surface of curvature radius R: the
    # faceting error is O(h^2), so halving the size must cut it by clearly more than 2
    errs = [abs(ventricle_mesh(s).volumes().sum() / wall_volume() - 1) for s in (4.0, 2.0)]
    assert errs[1] < errs[0] / 2.5
    assert errs[1] < 5e-3
    assert cavity_volume() == pytest.approx(np.pi * 49 * (22 - (125 + 17**3) / (3 * 17**2)))


def test_bad_geometry_is_input_error():
    with pytest.raises(InputError, match="inside"):
        ellipsoid_mesh(endo=(11.0, 17.0))
    with pytest.raises(InputError, match="base_z"):
        ellipsoid_mesh(base_z=18.0)
    with pytest.raises(InputError, match="size"):
        ellipsoid_mesh(size=0.0)


def _sagitta_error(shell) -> float:
    """Depth error from the faceted inner sphere: sagitta h^2 / (8 r) times |d'(r)|."""
    bf = shell.boundary_facets()
    h = np.linalg.norm(shell.points[bf] - shell.points[np.roll(bf, 1, axis=1)], axis=2).max()
    return h**2 / (8 * 7) / (49 * (1 / 7 - 1 / 10))


def test_transmural_depth_of_a_spherical_shell(shell):
    d = transmural_depth(shell)
    r = np.linalg.norm(shell.points, axis=1)
    exact = (1 / 7 - 1 / r) / (1 / 7 - 1 / 10)
    # the faceted surface lies up to a sagitta h^2 / (8 r) inside the sphere, where P2 puts
    # boundary values: an error of that times |d'| = 1 / (r^2 (1/7 - 1/10)) at r = 7
    assert np.abs(d - exact).max() <= _sagitta_error(shell)


def test_frames_follow_the_rule_on_a_spherical_shell(shell):
    x = shell.centers()
    r_hat = x / np.linalg.norm(x, axis=1, keepdims=True)
    circ = np.cross([0.0, 0.0, 1.0], r_hat)
    ok = np.linalg.norm(circ, axis=1) > 0.3  # away from the apex, where c is arbitrary
    circ = circ[ok] / np.linalg.norm(circ[ok], axis=1, keepdims=True)
    frames, depth = rule_based_frames(shell, 0.0, 0.0)
    r = np.linalg.norm(x, axis=1)
    bound = _sagitta_error(shell)  # as for the nodal depth
    assert np.abs(depth - (1 / 7 - 1 / r) / (1 / 7 - 1 / 10)).max() <= bound
    # the sheet is transmural (radial, to the discretisation of grad d: the P2 gradient's
    # direction is off by O(h^2 / r^2) ~ 2%) and f is circumferential
    assert np.abs(np.einsum("ej,ej->e", frames[ok, 1], r_hat[ok])).min() > 0.98
    assert np.abs(np.einsum("ej,ej->e", frames[ok, 0], circ)).min() > 0.98
    frames, _ = rule_based_frames(shell, 90.0, 90.0)  # longitudinal
    assert np.abs(np.einsum("ej,ej->e", frames[ok, 0], circ)).max() < 0.2
    # the helix angle turns through the wall: cos(a) against the circumferential direction
    frames, depth = rule_based_frames(shell, 60.0, -60.0)
    cos_a = np.abs(np.einsum("ej,ej->e", frames[ok, 0], circ))
    expected = np.abs(np.cos(np.radians(60.0 - 120.0 * depth[ok])))
    assert np.abs(cos_a - expected).max() < 0.1
    # right-handed orthonormal frames
    assert np.allclose(np.linalg.det(frames), 1.0)


def test_axis_size_refines_the_apex_only():
    # element size: the edge of the regular tet of each tet's volume; near the axis (the
    # apex wall) about axis_size, far from it the uniform mesh's
    m = ellipsoid_mesh(size=4.0, axis_size=0.5)
    u = ellipsoid_mesh(size=4.0)

    def edge(mesh):
        return (6.0 * np.sqrt(2.0) * mesh.volumes()) ** (1 / 3)

    rho = np.hypot(*m.centers()[:, :2].T)
    assert np.median(edge(m)[rho < 0.5]) < 1.0 < 2.0 < np.median(edge(u))
    assert np.median(edge(m)[rho > 8.0]) == pytest.approx(np.median(edge(u)), rel=0.25)
    assert m.points[:, 2].min() == pytest.approx(-20.0, abs=1e-6)  # the apexes stay vertices
    assert np.abs(np.linalg.norm(m.points - [0, 0, -17.0], axis=1)).min() < 1e-6
    with pytest.raises(InputError, match="axis_size"):
        ellipsoid_mesh(size=2.0, axis_size=3.0)


def test_doctests():
    import doctest

    import springfem.ellipsoid
    import springfem.fibres

    assert doctest.testmod(springfem.ellipsoid).failed == 0
    assert doctest.testmod(springfem.fibres).failed == 0
