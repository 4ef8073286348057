"""Active fibre tension ``T_a f0 (x) f0`` (docs/fem.rst#active-tension): the stress and the
tangent are derivatives of the energy-like term (central differences), the load factor
ramps it, and a block under active tension, alone or against a traction along the fibre,
takes the homogeneous state of the 1D (or 3D diagonal) equilibrium of the law, solved here
with scipy from the stretches alone, independently of the FEM.

A homogeneous deformation is exact in P1 and in Taylor–Hood P2/P1 on any mesh, so the
block is a jittered Delaunay box and the tolerances are those of the Newton stop
(``|R| <= 1e-10 |f|``), not of the discretisation.
"""

import numpy as np
import pytest
from scipy.optimize import brentq, fsolve
from scipy.spatial.transform import Rotation

from reference_fem import solve
from springfem.errors import SceneError
from springfem.materials.laws import Guccione, HolzapfelOgden
from springfem.mesh import box_mesh
from springfem.scene import scene_from_dict

GU = dict(C=2.0, b_f=8.0, b_t=2.0, b_fs=4.0)
HO = dict(a=1.0, b=2.0, a_f=2.0, b_f=3.0, a_s=1.5, b_s=2.5, a_fs=0.5, b_fs=1.5)
T_A = 10.0
RNG = np.random.default_rng(7)
FS = np.eye(3) + 0.25 * RNG.standard_normal((4, 3, 3))
FRAMES = Rotation.random(4, random_state=2).as_matrix()
LAWS = [
    Guccione(**GU, kappa=50.0, active_tension=60.0),
    Guccione(**GU, kappa=0.0, active_tension=60.0),
    HolzapfelOgden(**HO, kappa=30.0, volumetric="quadratic", active_tension=60.0),
]


def _fd(fun, F, h=1e-6):
    """Central differences of ``fun`` w.r.t. each ``F_kL``, stacked on the last two axes."""
    out = np.array(
        [(fun(F + h * np.eye(9)[i].reshape(3, 3)) - fun(F - h * np.eye(9)[i].reshape(3, 3)))
         / (2 * h) for i in range(9)]
    )  # fmt: skip
    return np.moveaxis(out.reshape((3, 3) + out.shape[1:]), (0, 1), (-2, -1))


@pytest.mark.parametrize("law", LAWS, ids=lambda law: law.name)
@pytest.mark.parametrize("i", range(len(FS)))
def test_active_stress_and_tangent_are_derivatives(law, i):
    F, R = FS[i], FRAMES[i]
    P, A = law.stress_tangent(F, R)
    # h = 1e-6: central differences are accurate to ~h^2 |d3W| + eps |W| / h ~ 1e-9 relative
    assert np.allclose(P, _fd(lambda G: law.energy(G, R), F), rtol=1e-7, atol=1e-7 * abs(P).max())
    assert np.allclose(A, _fd(lambda G: law.stress(G, R), F), rtol=1e-6, atol=1e-7 * abs(A).max())
    assert np.allclose(A, A.transpose(2, 3, 0, 1), atol=1e-12 * abs(A).max())


def test_active_part_is_the_fibre_stress_in_any_frame():
    # P - P_passive = T_a (F f0) (x) f0, with f0 the frame's first row
    F, R = FS, FRAMES
    law = Guccione(**GU, kappa=50.0, active_tension=60.0)
    passive = Guccione(**GU, kappa=50.0)
    f0 = R[:, 0]
    dP = 60.0 * np.einsum("eij,ej,eK->eiK", F, f0, f0)
    assert np.allclose(law.stress(F, R) - passive.stress(F, R), dP, atol=1e-11)
    dW = 30.0 * (np.einsum("eij,ej->ei", F, f0) ** 2).sum(axis=1) - 30.0
    assert np.allclose(law.energy(F, R) - passive.energy(F, R), dW, atol=1e-11)
    assert law.activated(0.25) == Guccione(**GU, kappa=50.0, active_tension=15.0)
    assert passive.activated(0.25) is passive


def _block(material: dict, traction: float, fem: dict, steps: int = 4):
    mesh = box_mesh((1.0, 1.0, 1.0), (3, 3, 3), "delaunay", jitter=0.3, seed=3)
    load = [{"type": "traction", "region": "x_max", "value": [traction, 0.0, 0.0]}]
    return scene_from_dict(
        {
            "mesh": mesh,
            "material": material,
            "axes": {"fiber": [1, 0, 0], "sheet": [0, 1, 0]},
            "boundary": [
                {"region": "x_min", "fix": ["x"]},
                {"region": "y_min", "fix": ["y"]},
                {"region": "z_min", "fix": ["z"]},
            ],
            "load": load if traction else [],
            "fem": {"load_steps": steps, **fem},
        }
    )


def _homogeneous_stretches(scene) -> tuple[np.ndarray, float]:
    """The stretches of the solve and how far its vertex field is from homogeneous."""
    sol = solve(scene)
    X = scene.mesh.points
    lams = 1.0 + np.linalg.lstsq(X, sol.u_vertices, rcond=None)[0].diagonal()
    off = np.abs(sol.u_vertices - X * (lams - 1.0)).max()
    return lams, off


def _guccione_d(lams):
    """``dW/dlambda_i`` of Guccione at ``F = diag(lams)`` (fibre along x)."""
    Bd = np.array([GU["b_f"], GU["b_t"], GU["b_t"]])
    E = 0.5 * (lams**2 - 1.0)
    return GU["C"] * np.exp((Bd * E**2).sum()) * Bd * E * lams


MIXED = {"formulation": "mixed", "order": 2}


@pytest.mark.parametrize("traction", [0.0, 5.0], ids=["alone", "counter-load"])
def test_incompressible_block_under_active_tension(traction):
    # J = 1, F = diag(l, l^-1/2, l^-1/2), P = dW/dl_i - p / l_i + T_a l delta_i1: lateral
    # faces free give p = m dW/dl_2 (m = l^-1/2); the fibre's nominal stress balances the
    # dead traction t: dW/dl_1 + T_a l - m / l dW/dl_2 = t.
    def axial(lam):
        m = lam**-0.5
        d = _guccione_d(np.array([lam, m, m]))
        return d[0] + T_A * lam - m / lam * d[1] - traction

    lam = brentq(axial, 0.3, 1.0, xtol=1e-15)
    m = float(lam**-0.5)
    mat = {"law": "guccione", **GU, "incompressible": True, "active_tension": T_A}
    lams, off = _homogeneous_stretches(_block(mat, traction, MIXED))
    # Newton stops at |R| <= 1e-10 |f|: stretches to ~1e-9
    assert lams == pytest.approx([lam, m, m], rel=1e-7)
    assert off < 1e-7
    assert lam < (0.9 if traction == 0 else 0.95)  # the fibres contract


@pytest.mark.parametrize("traction", [0.0, 5.0], ids=["alone", "counter-load"])
def test_nearly_incompressible_guccione_block_displacement_p1(traction):
    # U = kappa/2 ln^2 J, J U' = kappa ln J: P_ii = dW/dl_i + kappa ln J / l_i (+ T_a l_1)
    kappa = 200.0

    def eqs(x):
        lams = np.array([x[0], x[1], x[1]])
        d = _guccione_d(lams) + kappa * np.log(lams.prod()) / lams
        return [d[0] + T_A * x[0] - traction, d[1]]

    l1, l2 = fsolve(eqs, [0.9, 1.05], xtol=1e-13)
    mat = {"law": "guccione", **GU, "kappa": kappa, "active_tension": T_A}
    lams, off = _homogeneous_stretches(_block(mat, traction, {"order": 1}))
    assert lams == pytest.approx([l1, l2, l2], rel=1e-7)
    assert off < 1e-7


def _holzapfel_ogden_d(lams):
    """``dW/dlambda_i`` of Holzapfel–Ogden (with ``I1bar``) at ``F = diag(lams)``."""
    J = lams.prod()
    I1 = (lams**2).sum()
    I1b = J ** (-2.0 / 3.0) * I1
    dI1b = J ** (-2.0 / 3.0) * (2.0 * lams - 2.0 / 3.0 * I1 / lams)
    d = 0.5 * HO["a"] * np.exp(HO["b"] * (I1b - 3.0)) * dI1b
    for i, (a, b) in enumerate([(HO["a_f"], HO["b_f"]), (HO["a_s"], HO["b_s"])]):
        x = lams[i] ** 2 - 1.0
        if x > 0:  # fibre and sheet terms in tension only
            d[i] += a * x * np.exp(b * x**2) * 2.0 * lams[i]
    return d  # the shear term a_fs I8fs vanishes at diagonal F


@pytest.mark.parametrize("traction", [0.0, 5.0], ids=["alone", "counter-load"])
def test_nearly_incompressible_holzapfel_ogden_block_displacement_p1(traction):
    # diagonal F with the sheet along y (in tension when the fibre contracts): three stretches
    kappa = 100.0

    def eqs(lams):
        lams = np.asarray(lams)
        d = _holzapfel_ogden_d(lams) + kappa * np.log(lams.prod()) / lams
        d[0] += T_A * lams[0] - traction
        return d

    ref = fsolve(eqs, [0.8, 1.1, 1.1], xtol=1e-13)
    assert np.abs(eqs(ref)).max() < 1e-10
    mat = {"law": "holzapfel-ogden", **HO, "kappa": kappa, "active_tension": T_A}
    lams, off = _homogeneous_stretches(_block(mat, traction, {"order": 1}))
    assert lams == pytest.approx(ref, rel=1e-7)
    assert off < 1e-7


@pytest.mark.parametrize(
    "material, message",
    [
        ({"law": "guccione", **GU, "kappa": 50.0, "active_tension": -1.0}, "must not be neg"),
        ({"law": "guccione", **GU, "kappa": 50.0, "active_tension": float("inf")}, "finite"),
        ({"law": "guccione", **GU, "kappa": 50.0, "active_tension": "60"}, "a number"),
        ({"law": "neo-hookean", "E": 10.0, "nu": 0.3, "active_tension": 1.0}, "with fibres"),
        ({"law": "linear", "E": 10.0, "nu": 0.3, "active_tension": 1.0}, "with fibres"),
    ],
)
def test_active_tension_key_is_checked(material, message):
    with pytest.raises(SceneError, match=rf"material\.active_tension: .*{message}") as err:
        _block(material, 0.0, {"order": 1})
    assert "\n" not in str(err.value)
