"""Pressure loads: Lamé's thick-walled cylinder, and hydrostatic pressure at large strain.

The cylinder is a quarter in plane strain (symmetry planes sliding, ends fixed in z),
meshed by mapping a box mesh to polar coordinates. The large-strain test checks that the
pressure follows the deformed surface: under hydrostatic pressure a cube shrinks
homogeneously, ``F = lambda I``, and the Cauchy stress equals ``-p I``.
"""

import dataclasses

import numpy as np
import pytest
from scipy.optimize import brentq

from reference_fem import solve
from reference_fem.options import FemOptions
from reference_fem.scenes import thick_cylinder_scene
from springfem.materials.laws.neo_hookean import NeoHookean
from springfem.mesh import box_mesh
from springfem.scene import Material, scene_from_dict

A, B, E, NU = 1.0, 2.0, 1000.0, 0.3


def lame_radial_displacement(r, p, a=A, b=B, E=E, nu=NU):
    """Plane-strain Lamé solution for internal pressure ``p`` (no external pressure)."""
    return (1 + nu) * p * a**2 / (E * (b**2 - a**2)) * ((1 - 2 * nu) * r + b**2 / r)


def radial(sol):
    X = sol.problem.scene.mesh.points
    U = sol.u_vertices
    R = np.hypot(X[:, 0], X[:, 1])
    return R, (U[:, 0] * X[:, 0] + U[:, 1] * X[:, 1]) / R


@pytest.mark.parametrize("order,divisions", [(2, (4, 12, 1)), (1, (16, 32, 1))])
def test_thick_cylinder_matches_lame(order, divisions):
    sol = solve(thick_cylinder_scene(A, B, 1.0, divisions, E, NU, order=order), order=order)
    R, ur = radial(sol)
    err = np.abs(ur / lame_radial_displacement(R, 1.0) - 1)
    # 2 %: discretisation plus the polygonal boundary (measured 0.4 % P2, 0.7 % P1)
    assert err.max() < 0.02
    assert np.abs(sol.u_vertices[:, 2]).max() < 1e-14  # plane strain
    # reaction on a symmetry plane: the hoop force per unit height integrates to
    # int_a^b sigma_tt dr = p a (Lamé), times the height 0.2 a
    hoop = sol.result.reactions["y_min"][1]
    assert -hoop == pytest.approx(1.0 * A * 0.2 * A, rel=0.02)


@pytest.mark.parametrize(
    "law", ["neo-hookean/coupled", "neo-hookean/uncoupled/log", "neo-hookean/uncoupled/quadratic"]
)
def test_neo_hookean_cylinder_at_small_pressure_equals_linear(law):
    p = 1e-4 * E  # strains ~ 3e-4: geometric and material nonlinearity ~ 1e-4 relative
    scene = thick_cylinder_scene(A, B, p, (3, 8, 1), E, NU, law="neo-hookean", order=2)
    nonlinear = solve(scene, law=law)
    linear = solve(scene, law="linear")
    diff = np.abs(nonlinear.u_vertices - linear.u_vertices).max()
    assert diff < 0.005 * np.abs(linear.u_vertices).max()
    assert nonlinear.result.info["pressure"].startswith("follower")


def hydrostatic_stretch(law: NeoHookean, p: float) -> float:
    """Stretch ``lambda`` with Cauchy stress ``-p I`` for ``F = lambda I`` (from psi only).

    For ``F = lambda I`` the stress is isotropic; ``sigma = (1 / (3 lambda^2)) dpsi/dlambda``
    (the power ``3 lambda^2 sigma dlambda``-per-unit-reference-volume identity).
    """

    def psi(lam):
        return law.energy(lam * np.eye(3))

    def sigma(lam, h=1e-7):
        return (psi(lam + h) - psi(lam - h)) / (2 * h) / (3 * lam**2)

    # sigma is monotonic on each side of lambda = 1 within the bracket (not for large
    # tension: the log volumetric function has a maximum tensile stress kappa / e)
    lo, hi = (0.3, 1.0) if p > 0 else (1.0, 1.5)
    return brentq(lambda lam: sigma(lam) + p, lo, hi, xtol=1e-14)


@pytest.mark.parametrize(
    "formulation,volumetric",
    [
        ("coupled", "log"),
        ("uncoupled", "log"),
        ("uncoupled", "quadratic"),
        ("uncoupled", "simo-taylor"),
    ],
)
@pytest.mark.parametrize("p_over_E", [0.25, -0.15])
def test_follower_pressure_hydrostatic_large_strain(formulation, volumetric, p_over_E):
    E_, nu = 1.0e3, 0.3
    material = Material("neo-hookean", E_, nu, formulation=formulation, volumetric=volumetric)
    mesh = box_mesh((1.0, 1.0, 1.0), (2, 2, 2))
    p = p_over_E * E_
    scene = scene_from_dict(
        {
            "mesh": mesh,
            "material": material,
            "boundary": [{"region": f"{c}_min", "fix": [c]} for c in "xyz"],
            "load": [{"type": "pressure", "value": p, "region": f"{c}_max"} for c in "xyz"],
            "probe": [{"name": "corner", "point": [1.0, 1.0, 1.0]}],
        }
    )
    sol = solve(scene, order=1)
    lam = hydrostatic_stretch(NeoHookean.from_material(material), p)
    # brentq on a finite-difference stress: ~1e-8 relative
    np.testing.assert_allclose(sol.result.probes["corner"], [lam - 1] * 3, rtol=1e-6)
    np.testing.assert_allclose(sol.cell_data["J"], lam**3, rtol=1e-6)
    # a dead load (-p N on the reference surface) would give a visibly different stretch
    assert abs(lam - 1) > 0.03


def test_follower_pressure_with_amg_gmres_equals_direct():
    """The non-symmetric tangent (pressure load stiffness) through AMG-preconditioned GMRES."""
    scene = thick_cylinder_scene(A, B, 0.05 * E, (2, 6, 1), E, NU, law="neo-hookean", order=2)
    direct = solve(scene)
    scene = scene.with_options(fem=dataclasses.replace(FemOptions.of(scene), linear_solver="amg"))
    amg = solve(scene)
    assert amg.result.info["linear_solver"] == "amg" and amg.result.info["krylov_iterations"] > 0
    np.testing.assert_allclose(amg.u, direct.u, atol=1e-8 * np.abs(direct.u).max())
