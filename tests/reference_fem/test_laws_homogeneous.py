"""Tissue laws in the FEM: homogeneous deformations against stresses derived from W by hand.

Uniaxial stretch along and across the fibre (rollers on the three ``min`` faces, the
nominal stress of the closed form as a dead traction on a ``max`` face, lateral faces
free): P1 is exact for the homogeneous state, so the stretches equal the closed form's,
whose lateral stretches come from the traction-free condition (scipy). Simple shear in the fs and sn
planes: ``P_01 = dW/dgamma`` of ``W(gamma)`` written by hand, against the summed nodal
forces of the homogeneous field on a P2 mesh.
"""

import numpy as np
import pytest
from scipy.optimize import brentq, fsolve

from reference_fem import solve
from reference_fem.problem import FemProblem
from springfem.regions import resolve_region
from springfem.scene import scene_from_dict

GU = dict(C=2.0, b_f=8.0, b_t=2.0, b_fs=4.0)
HO = dict(a=1.0, b=2.0, a_f=2.0, b_f=3.0, a_s=1.5, b_s=2.5, a_fs=0.5, b_fs=1.5)
#: Newton stops at |R| <= 1e-10 |f|; the hand closed forms are solved to ~1e-12.
TOL = 1e-7


def _stretches(material: dict, axis: int, traction: float) -> np.ndarray:
    """Principal stretches of the unit cube under a uniform dead traction along ``axis``
    (rollers on the three ``min`` faces), read at the corner (1, 1, 1)."""
    comp = "xyz"[axis]
    value = [0.0, 0.0, 0.0]
    value[axis] = traction
    scene = scene_from_dict(
        {
            "mesh": {"generator": "box", "size": [1, 1, 1], "divisions": [1, 1, 1]},
            "material": material,
            "axes": {"fiber": [1, 0, 0], "sheet": [0, 1, 0]},
            "boundary": [
                {"region": "x_min", "fix": ["x"]},
                {"region": "y_min", "fix": ["y"]},
                {"region": "z_min", "fix": ["z"]},
            ],
            "load": [{"type": "traction", "region": f"{comp}_max", "value": value}],
            "probe": [{"name": "corner", "point": [1, 1, 1]}],
            "fem": {"load_steps": 4},
        }
    )
    return 1.0 + np.array(solve(scene, order=1).result.probes["corner"])


# -- Guccione, hand-derived: for F = diag(l), E_ii = (l_i^2 - 1)/2, Q = sum_i B_ii E_ii^2,
#    dW/dl_i = C e^Q B_ii E_ii l_i; log penalty U = kappa/2 ln^2 J adds kappa ln J / l_i.
def _guccione_principal(lams, kappa):
    lams = np.asarray(lams, dtype=float)
    Bd = np.array([GU["b_f"], GU["b_t"], GU["b_t"]])
    E = 0.5 * (lams**2 - 1.0)
    Q = float((Bd * E**2).sum())
    return GU["C"] * np.exp(Q) * Bd * E * lams + kappa * np.log(lams.prod()) / lams


@pytest.mark.parametrize("stretch", [1.15, 0.9])
def test_guccione_uniaxial_along_fibre(stretch):
    kappa = 200.0
    mat = {"law": "guccione", **GU, "kappa": kappa}
    lat = brentq(lambda m: _guccione_principal([stretch, m, m], kappa)[1], 0.5, 1.5, xtol=1e-14)
    P = _guccione_principal([stretch, lat, lat], kappa)[0]
    assert _stretches(mat, 0, P) == pytest.approx([stretch, lat, lat], rel=TOL)


def test_guccione_uniaxial_across_fibre():
    kappa, stretch = 200.0, 1.2
    mat = {"law": "guccione", **GU, "kappa": kappa}
    f = _guccione_principal

    def lateral(m):
        return [f([m[0], stretch, m[1]], kappa)[0], f([m[0], stretch, m[1]], kappa)[2]]

    m1, m2 = fsolve(lateral, [0.95, 0.9], xtol=1e-13)
    P = f([m1, stretch, m2], kappa)[1]
    assert _stretches(mat, 1, P) == pytest.approx([m1, stretch, m2], rel=TOL)
    assert m1 > m2  # the stiff fibre resists the lateral contraction


def test_guccione_penalty_approaches_incompressible_within_C_over_kappa():
    """Penalty vs the incompressible closed form ``l_lat = l^(-1/2)``,
    ``P = dW/dl_1 - (l_2 / l_1) dW/dl_2``, Lagrange multiplier ``p = l_2 dW/dl_2``."""
    stretch = 1.15
    lat = stretch**-0.5
    d = _guccione_principal([stretch, lat, lat], 0.0)
    P_inc, p = d[0] - lat / stretch * d[1], lat * d[1]
    for kappa in (1e3, 1e4):
        lams = _stretches({"law": "guccione", **GU, "kappa": kappa}, 0, P_inc)
        # first order in 1/kappa: ln J = -p / kappa. The penalty's pressure differs from p by
        # O(D / kappa) (D ~ C b_f e^Q ~ 30, so 3% at kappa = 1e3): 20% covers it
        assert abs(lams.prod() - 1.0) == pytest.approx(abs(p) / kappa, rel=0.2)
        # and every stretch moves by less than the volume change
        assert np.abs(lams - [stretch, lat, lat]).max() <= abs(p) / kappa


# -- Holzapfel–Ogden, hand-derived for F = diag(l): I1bar = J^(-2/3) sum l_i^2,
#    dI1bar/dl_i = J^(-2/3) (2 l_i - 2/3 I1 / l_i); fibre/sheet terms psi(l_i^2 - 1) in
#    tension with psi' = a x e^{b x^2}, d/dl_i = 2 l_i psi'; quadratic U adds kappa (J-1) J/l_i.
def _ho_principal(lams, kappa):
    lams = np.asarray(lams, dtype=float)
    J = lams.prod()
    I1 = (lams**2).sum()
    I1b = J ** (-2 / 3) * I1
    d = 0.5 * HO["a"] * np.exp(HO["b"] * (I1b - 3)) * J ** (-2 / 3) * (2 * lams - 2 / 3 * I1 / lams)
    for i, (a, b) in enumerate([(HO["a_f"], HO["b_f"]), (HO["a_s"], HO["b_s"])]):
        x = lams[i] ** 2 - 1.0
        if x > 0:
            d[i] += 2 * lams[i] * a * x * np.exp(b * x**2)
    return d + kappa * (J - 1.0) * J / lams


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_holzapfel_ogden_uniaxial(axis):
    kappa, stretch = 100.0, 1.15
    mat = {"law": "holzapfel-ogden", **HO, "kappa": kappa, "volumetric": "quadratic"}
    others = [i for i in range(3) if i != axis]

    def lams(m):
        out = np.full(3, stretch)
        out[others] = m
        return out

    m = fsolve(lambda m: _ho_principal(lams(m), kappa)[others], [0.93, 0.93], xtol=1e-13)
    P = _ho_principal(lams(m), kappa)[axis]
    assert _stretches(mat, axis, P) == pytest.approx(lams(m), rel=TOL)


# -- simple shear, J = 1: u_i = gamma X_j with (i, j) = (f, s) or (s, n).
def _shear_force(material: dict, i: int, j: int, gamma: float) -> float:
    box = {"generator": "box", "size": [1, 1, 1], "divisions": [2, 2, 2]}
    scene = scene_from_dict({"mesh": box, "material": material})  # default axes: x, y, z
    problem = FemProblem(scene, order=2)
    H = np.zeros((3, 3))
    H[i, j] = gamma
    u = problem.space.node_coordinates @ H.T
    fi, _ = problem.internal_force(u.ravel())
    face = problem.space.region_nodes(resolve_region(scene.mesh, f"{'xyz'[j]}_max").nodes)
    return float(fi.reshape(-1, 3)[face, i].sum())  # = P_ij * area(face), area 1


@pytest.mark.parametrize("plane", ["fs", "sn"])
def test_guccione_simple_shear(plane):
    g = 0.3
    i, j = (0, 1) if plane == "fs" else (1, 2)
    # fs: E_fs = g/2, E_ss = g^2/2 -> Q = b_fs g^2/2 + b_t g^4/4
    # sn: E_sn = g/2, E_nn = g^2/2 -> Q = b_t g^2/2 + b_t g^4/4;  P_ij = dW/dg = C/2 e^Q Q'
    b = GU["b_fs"] if plane == "fs" else GU["b_t"]
    Q = b * g**2 / 2 + GU["b_t"] * g**4 / 4
    P = 0.5 * GU["C"] * np.exp(Q) * (b * g + GU["b_t"] * g**3)
    mat = {"law": "guccione", **GU, "kappa": 50.0}
    assert _shear_force(mat, i, j, g) == pytest.approx(P, rel=1e-12)


@pytest.mark.parametrize("plane", ["fs", "sn"])
def test_holzapfel_ogden_simple_shear(plane):
    g = 0.3
    i, j = (0, 1) if plane == "fs" else (1, 2)
    a, b = HO["a"], HO["b"]
    # I1bar = 3 + g^2; fs: I4s = 1 + g^2, I8 = g, I4f = 1; sn: I4n unused, I4s = 1, I8 = 0
    P = a * g * np.exp(b * g**2)
    if plane == "fs":
        P += 2 * HO["a_s"] * g**3 * np.exp(HO["b_s"] * g**4)
        P += HO["a_fs"] * g * np.exp(HO["b_fs"] * g**2)
    mat = {"law": "holzapfel-ogden", **HO, "kappa": 50.0}
    assert _shear_force(mat, i, j, g) == pytest.approx(P, rel=1e-12)


@pytest.mark.parametrize("law", ["guccione", "holzapfel-ogden"])
@pytest.mark.parametrize("order", [1, 2])
def test_assembled_tangent_is_the_derivative_of_the_residual(law, order):
    """Random per-element frames (``[axes] type = "cells"`` would give the same): the
    element frames reach the assembly, and the global tangent is consistent (so Newton
    converges quadratically)."""
    from scipy.spatial.transform import Rotation

    params = GU if law == "guccione" else HO
    box = {"generator": "box", "size": [1, 1, 1], "divisions": [2, 1, 1]}
    scene = scene_from_dict({"mesh": box, "material": {"law": law, **params, "kappa": 20.0}})
    scene.frames = Rotation.random(scene.mesh.n_tets, random_state=4).as_matrix()
    problem = FemProblem(scene, order=order)
    rng = np.random.default_rng(6)
    # a 10% expansion plus noise keeps every fibre and sheet in tension: the
    # Holzapfel–Ogden tangent jumps where I4 = 1, which a difference must not straddle
    X = problem.space.node_coordinates
    u = (0.1 * X).ravel() + 0.02 * rng.standard_normal(problem.n_dofs)
    _, K = problem.internal_force(u, tangent=True)
    v = rng.standard_normal(problem.n_dofs)
    h = 1e-6
    fd = (problem.internal_force(u + h * v)[0] - problem.internal_force(u - h * v)[0]) / (2 * h)
    # central differences: O(h^2) truncation plus ~eps |f| / h round-off, ~1e-9 relative
    assert np.abs(fd - K @ v).max() <= 1e-7 * np.abs(K @ v).max()
    # and the frames matter: the same field with the global axes gives other forces
    iso = FemProblem(
        scene_from_dict({"mesh": box, "material": {"law": law, **params, "kappa": 20.0}}),
        order=order,
    )
    assert np.abs(iso.internal_force(u)[0] - problem.internal_force(u)[0]).max() > 1e-3
