"""Transversely isotropic block in uniaxial stress at fiber angles 0-90 degrees.

Reference: the off-axis modulus of a transversely isotropic material,
``1/E(theta) = cos^4/E_f + sin^4/E_c + (1/G_f - 2 nu_fc/E_f) sin^2 cos^2``, and the full
strain ``eps = S sigma`` of the rotated compliance. The bundled ``stretch-fiber`` scene's
supports (``x_min`` sliding, two pins) admit the homogeneous uniaxial-stress state, shear
coupling included, so the FE solution is exact up to round-off.
"""

from pathlib import Path

import numpy as np
import pytest

from reference_fem import solve
from reference_fem.assembly import displacement_gradient
from reference_fem.materials import material_matrix
from springfem.axes import uniform_frames
from springfem.scene import load_scene

SCENE = Path(__file__).resolve().parents[2] / "studies" / "scenes" / "stretch-fiber.toml"


def off_axis_modulus(theta, E_f, E_c, nu_fc, G_f):
    c, s = np.cos(theta), np.sin(theta)
    return 1.0 / (c**4 / E_f + s**4 / E_c + (1.0 / G_f - 2.0 * nu_fc / E_f) * s**2 * c**2)


@pytest.fixture(scope="module")
def scene():
    return load_scene(SCENE)


def with_fiber_angle(scene, deg, out_of_plane=0.0):
    th, ph = np.radians(deg), np.radians(out_of_plane)
    fiber = [np.cos(th) * np.cos(ph), np.sin(th) * np.cos(ph), np.sin(ph)]
    sheet = [-np.sin(th), np.cos(th), 0.0]
    scene.frames = uniform_frames(scene.mesh.n_tets, fiber, sheet)
    return scene


CASES = [(1, deg) for deg in (0, 30, 45, 60, 90)] + [(2, deg) for deg in (0, 45, 90)]


@pytest.mark.parametrize("order,deg", CASES)
def test_effective_modulus_matches_off_axis_formula(scene, order, deg):
    m = scene.material
    with_fiber_angle(scene, deg)
    sol = solve(scene, order=order)
    L, traction = 0.01, scene.loads[0].value[0]
    X, U = scene.mesh.points, sol.u_vertices
    end = np.abs(X[:, 0] - L) < 1e-12
    E_eff = traction / (U[end, 0].mean() / L)
    expect = off_axis_modulus(np.radians(deg), m.E_fiber, m.E_cross, m.nu_fiber_cross, m.G_fiber)
    # 0.5 % required; the state is homogeneous, so the error is the solver's round-off
    assert E_eff == pytest.approx(expect, rel=0.005)
    assert E_eff == pytest.approx(expect, rel=1e-9)
    assert sol.result.law == "transverse-linear"


def test_strain_of_oblique_fibers_is_compliance_times_stress(scene):
    """All six strain components, with shear coupling, for a fiber out of every plane."""
    with_fiber_angle(scene, 35, out_of_plane=25)
    sol = solve(scene, order=1)
    S = np.linalg.inv(material_matrix(scene.material, scene.frames[:1])[0])
    eps_expect = S[:, 0] * scene.loads[0].value[0]  # Voigt, engineering shears
    H = displacement_gradient(sol.problem.space, sol.u.reshape(-1, 3))[:, 0]
    eps = 0.5 * (H + np.swapaxes(H, 1, 2))
    voigt = np.stack(
        [
            eps[:, 0, 0],
            eps[:, 1, 1],
            eps[:, 2, 2],
            2 * eps[:, 1, 2],
            2 * eps[:, 0, 2],
            2 * eps[:, 0, 1],
        ],
        axis=1,
    )
    np.testing.assert_allclose(
        voigt, np.broadcast_to(eps_expect, voigt.shape), atol=1e-10 * np.abs(eps_expect).max()
    )
