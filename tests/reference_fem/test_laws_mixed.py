"""Mixed u–p (Taylor–Hood P2/P1) formulation and the tissue scene keys.

A homogeneous state is exact in P2 displacement / P1 pressure, so the incompressible
uniaxial stretch must match the incompressible closed form to the Newton tolerance; with a
finite ``kappa`` the perturbed Lagrangian ``-p (J-1) - p^2/(2 kappa)`` eliminates to the
quadratic penalty ``kappa/2 (J-1)^2``, so it must match the displacement formulation with
``volumetric = "quadratic"``.
"""

import numpy as np
import pytest

from reference_fem import solve
from reference_fem.solver import make_problem
from springfem.errors import InputError, SceneError
from springfem.scene import scene_from_dict

GU = dict(C=2.0, b_f=8.0, b_t=2.0, b_fs=4.0)


def _cube(material: dict, traction: float, fem: dict, axis: int = 0, divisions=(1, 1, 1)):
    value = [0.0, 0.0, 0.0]
    value[axis] = traction
    return scene_from_dict(
        {
            "mesh": {"generator": "box", "size": [1, 1, 1], "divisions": list(divisions)},
            "material": material,
            "axes": {"fiber": [1, 0, 0], "sheet": [0, 1, 0]},
            "boundary": [
                {"region": "x_min", "fix": ["x"]},
                {"region": "y_min", "fix": ["y"]},
                {"region": "z_min", "fix": ["z"]},
            ],
            "load": [{"type": "traction", "region": f"{'xyz'[axis]}_max", "value": value}],
            "probe": [{"name": "corner", "point": [1, 1, 1]}],
            "fem": {"load_steps": 2, **fem},
        }
    )


def _stretches(scene) -> np.ndarray:
    return 1.0 + np.array(solve(scene).result.probes["corner"])


MIXED = {"formulation": "mixed", "order": 2}


@pytest.mark.parametrize("stretch", [1.2, 0.9])
def test_incompressible_uniaxial_along_fibre_is_the_closed_form(stretch):
    # F = diag(l, l^-1/2, l^-1/2); dW/dl_i = C e^Q B_ii E_ii l_i; P = dW/dl_1 - l_2/l_1 dW/dl_2
    lat = stretch**-0.5
    lams = np.array([stretch, lat, lat])
    Bd = np.array([GU["b_f"], GU["b_t"], GU["b_t"]])
    E = 0.5 * (lams**2 - 1)
    d = GU["C"] * np.exp((Bd * E**2).sum()) * Bd * E * lams
    P = d[0] - lat / stretch * d[1]
    scene = _cube({"law": "guccione", **GU, "incompressible": True}, P, MIXED)
    # Newton stops at |R| <= 1e-10 |f|: stretches to ~1e-9
    assert _stretches(scene) == pytest.approx(lams, rel=1e-7)


def test_mixed_with_kappa_equals_quadratic_penalty():
    kappa = 30.0
    mat = {"law": "guccione", **GU, "kappa": kappa, "volumetric": "quadratic"}
    mixed = _stretches(_cube(mat, 3.0, MIXED, axis=1))
    penalty = _stretches(_cube(mat, 3.0, {"order": 2}, axis=1))
    assert abs(mixed.prod() - 1) > 1e-2  # compressible enough to tell the two apart
    assert mixed == pytest.approx(penalty, rel=1e-8)


@pytest.mark.parametrize("law", ["guccione", "holzapfel-ogden"])
def test_mixed_tangent_is_the_derivative_of_the_residual(law):
    params = (
        GU
        if law == "guccione"
        else dict(a=1.0, b=2.0, a_f=2.0, b_f=3.0, a_s=1.5, b_s=2.5, a_fs=0.5, b_fs=1.5)
    )
    scene = _cube({"law": law, **params, "incompressible": True}, 0.5, MIXED, divisions=(2, 1, 1))
    pr = make_problem(scene)
    rng = np.random.default_rng(2)
    x = np.zeros(pr.n_dofs)
    x[: pr.nu] = 0.05 * rng.standard_normal(pr.nu)
    x[pr.nu :] = 0.05 * rng.standard_normal(pr.n_p)
    _, K, _, _ = pr.residual_tangent(x, 1.0)
    v = rng.standard_normal(pr.n_dofs)
    h = 1e-6
    fd = (pr.residual(x + h * v)[0] - pr.residual(x - h * v)[0]) / (2 * h)
    # central differences: O(h^2) truncation plus ~eps |R| / h round-off, ~1e-9 relative
    assert np.abs(fd - K @ v).max() <= 1e-7 * np.abs(K @ v).max()


def test_errors():
    inc = {"law": "guccione", **GU, "incompressible": True}
    with pytest.raises(InputError, match="mixed"):
        solve(_cube(inc, 0.1, {}))
    with pytest.raises(InputError, match="order 2"):
        solve(_cube(inc, 0.1, {"formulation": "mixed", "order": 1}))
    linear = {"law": "linear", "E": 1.0, "nu": 0.3}
    with pytest.raises(InputError, match="hyperelastic law"):
        solve(_cube(linear, 0.1, MIXED))
    with pytest.raises(InputError, match="use law guccione"):
        solve(_cube(inc, 0.1, MIXED), law="neo-hookean")
    with pytest.raises(SceneError, match="material.b_t: missing"):
        _cube({"law": "guccione", "C": 1.0, "b_f": 1.0, "b_fs": 1.0, "kappa": 1.0}, 0.1, {})
    with pytest.raises(SceneError, match="either kappa or incompressible"):
        _cube({**inc, "kappa": 1.0}, 0.1, {})
    with pytest.raises(SceneError, match="material.kappa: missing"):
        _cube(
            {
                "law": "holzapfel-ogden",
                "a": 1.0,
                "b": 1.0,
                "a_f": 1.0,
                "b_f": 1.0,
                "a_s": 1.0,
                "b_s": 1.0,
                "a_fs": 1.0,
                "b_fs": 1.0,
            },
            0.1,
            {},
        )
    with pytest.raises(SceneError, match="formulation"):
        _cube(inc, 0.1, {"formulation": "u-p"})


def test_doctest():
    import doctest

    import reference_fem.mixed

    assert doctest.testmod(reference_fem.mixed).failed == 0


NH = {"law": "neo-hookean", "E": 10.0, "nu": 0.49}


def test_mixed_uncoupled_neo_hookean_is_the_quadratic_penalty_law():
    """Eliminating p leaves kappa/2 (J-1)^2: the displacement formulation with it."""
    law = {**NH, "formulation": "uncoupled", "volumetric": "quadratic"}
    mixed = _stretches(_cube(law, 2.0, MIXED))
    displacement = _stretches(_cube(law, 2.0, {"order": 2}))
    assert mixed == pytest.approx(displacement, rel=1e-8)  # Newton tolerance


def test_mixed_coupled_neo_hookean_uniaxial_is_the_closed_form():
    """``mu/2 (I1 - 3) - mu ln J + lam/2 (J - 1)^2`` under uniaxial traction ``t``."""
    from scipy.optimize import fsolve

    E, nu, t = NH["E"], NH["nu"], 2.0
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))

    def stationary(s):
        l1, l2 = s
        J = l1 * l2**2
        dWdJ = -mu / J + lam * (J - 1)
        return [mu * l1 + dWdJ * l2**2 - t, 2 * mu * l2 + dWdJ * 2 * l1 * l2]

    l1, l2 = fsolve(stationary, [1.1, 0.95], xtol=1e-12)
    assert _stretches(_cube(NH, t, MIXED)) == pytest.approx([l1, l2, l2], rel=1e-8)
    assert make_problem(_cube(NH, t, MIXED)).law_name == "neo-hookean/coupled/mixed-P2P1"
