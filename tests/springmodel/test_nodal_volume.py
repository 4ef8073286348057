"""The nodal-averaged volume term (``volume_average = "nodal"``, Bonet & Burton 1998).

References: central finite differences of the energy (forces) and of the forces (tangent),
the per-tet energy ``sum_e V_e0 U(J)`` written out from :mod:`springfem.volumetric` under a
uniform dilation, and exact invariants (rigid motions; piecewise-affine isochoric shears).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import Delaunay

from springfem.mesh import box_mesh
from springfem.scene import scene_from_dict
from springfem.volumetric import volumetric_energy
from springmodel.nodal_volume import NodalVolume, tet_volumes_and_gradients

KINDS = ("quadratic", "log", "simo-taylor")


def jittered_mesh(seed: int = 3):
    """Delaunay tets of random points (irregular, not a cube split), slivers dropped."""
    rng = np.random.default_rng(seed)
    X = rng.random((45, 3)) * np.array([2.0, 1.0, 1.5])
    tets = Delaunay(X).simplices
    V = np.linalg.det(X[tets[:, 1:]] - X[tets[:, :1]]) / 6.0
    keep = np.abs(V) > 2e-3
    return X, tets[keep], rng


def large_deformation(X, rng):
    """A smooth non-affine map (bending, 30% stretch) plus a random rotation and jitter."""
    x = X.copy()
    x[:, 0] *= 1.3
    x[:, 2] += 0.3 * np.sin(1.5 * X[:, 0]) + 0.1 * X[:, 1] ** 2
    q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    return x @ q.T + 0.02 * rng.standard_normal(X.shape)


def fd_forces(term, x, h=1e-6):
    g = np.zeros_like(x)
    for i in range(x.shape[0]):
        for a in range(3):
            xp, xm = x.copy(), x.copy()
            xp[i, a] += h
            xm[i, a] -= h
            g[i, a] = -(term.energy(xp) - term.energy(xm)) / (2 * h)
    return g


def fd_tangent(fn, x, h=1e-6):
    n = x.size
    K = np.zeros((n, n))
    for j in range(n):
        xp, xm = x.ravel().copy(), x.ravel().copy()
        xp[j] += h
        xm[j] -= h
        K[:, j] = -(fn(xp.reshape(-1, 3)) - fn(xm.reshape(-1, 3))).ravel() / (2 * h)
    return K


@pytest.mark.parametrize("kind", KINDS)
def test_forces_are_the_energy_gradient_and_tangent_the_force_derivative(kind):
    X, tets, rng = jittered_mesh()
    kappa = rng.uniform(1.0, 3.0, len(tets))  # heterogeneous: the nodal average matters
    term = NodalVolume(X, tets, kappa, kind)
    x = large_deformation(X, rng)
    J = term.ratios(x)
    assert J.min() > 0.5 and np.abs(J - 1).max() > 0.1  # a large deformation, J > 0
    f = term.forces(x)
    # central differences, h = 1e-6 on O(1) coordinates: truncation ~h^2, roundoff
    # ~1e-16 |W| / h ~ 1e-10 relative; 1e-7 leaves a margin of 1000
    assert np.abs(f - fd_forces(term, x)).max() < 1e-7 * np.abs(f).max()
    K = term.tangent(x).toarray()
    assert np.abs(K - K.T).max() < 1e-12 * np.abs(K).max()  # the Hessian of an energy
    assert np.abs(K - fd_tangent(term.forces, x)).max() < 1e-7 * np.abs(K).max()


def test_tangent_couples_the_node_patch():
    """``g_a g_a^T`` couples nodes that share no element but share a neighbour."""
    X, tets, _ = jittered_mesh()
    term = NodalVolume(X, tets, np.ones(len(tets)))
    K = term.tangent(X * 1.01)
    A = np.zeros((len(X), len(X)), bool)
    for t in tets:
        A[np.ix_(t, t)] = True
    nodes = (abs(K).tocoo().row // 3, abs(K).tocoo().col // 3)
    patch = np.zeros_like(A)
    patch[nodes] = True
    assert patch.sum() > A.sum()  # wider than the element pattern ...
    assert not (patch & ~((A.astype(int) @ A.astype(int)) > 0)).any()  # ... within 2 rings


@pytest.mark.parametrize("kind", KINDS)
def test_uniform_dilation_gives_the_per_tet_energy(kind):
    X, tets, rng = jittered_mesh(5)
    kappa = rng.uniform(1.0, 3.0, len(tets))
    term = NodalVolume(X, tets, kappa, kind)
    s = 1.07
    x = s * X + np.array([0.3, -0.2, 0.1])
    assert np.allclose(term.ratios(x)[np.unique(tets)], s**3, rtol=1e-13, atol=0)
    V0 = np.abs(np.linalg.det(X[tets[:, 1:]] - X[tets[:, :1]])) / 6.0
    per_tet = float(np.sum(V0 * volumetric_energy(np.full(len(tets), s**3), kappa, kind)[0]))
    assert term.energy(x) == pytest.approx(per_tet, rel=1e-12)  # sums of the same terms


def test_rigid_motion_gives_no_force_and_unit_ratios():
    X, tets, rng = jittered_mesh(7)
    term = NodalVolume(X, tets, np.full(len(tets), 1.0e3), "log")
    q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    q *= np.sign(np.linalg.det(q))
    x = X @ q.T + np.array([1.0, 2.0, -3.0])
    assert np.abs(term.ratios(x) - 1.0).max() < 1e-12
    # U'(J) ~ kappa * 1e-13 and dV ~ 0.1: forces at roundoff of kappa
    assert np.abs(term.forces(x)).max() < 1e-9


def test_isochoric_non_affine_shear_keeps_nodal_ratios_one():
    """A zig-zag shear ``x += phi(z)``, affine on each layer of cells: every tet keeps its
    volume (``det(I + s e_x (x) e_z) = 1``), so every ``J_a = 1`` and nothing pushes back."""
    mesh = box_mesh((1.0, 1.0, 3.0), (2, 2, 3))
    X = mesh.points
    phi = np.interp(X[:, 2], [0.0, 1.0, 2.0, 3.0], [0.0, 0.4, -0.3, 0.2])
    x = X.copy()
    x[:, 0] += phi
    V0, _ = tet_volumes_and_gradients(X, mesh.tets)
    V, _ = tet_volumes_and_gradients(x, mesh.tets)
    assert np.abs(V / V0 - 1).max() < 1e-13  # the per-tet ratio is one (independent check)
    term = NodalVolume(X, mesh.tets, np.full(mesh.n_tets, 1.0e3), "quadratic")
    assert np.abs(term.ratios(x) - 1.0).max() < 1e-13
    assert abs(term.energy(x)) < 1e-20 and np.abs(term.forces(x)).max() < 1e-10


def nodal_scene(follower: bool) -> dict:
    """A small clamped block of the incompressible Land material under a pressure."""
    return {
        "name": "nodal-block",
        "mesh": {"generator": "box", "size": [4.0, 1.0, 1.0], "divisions": [4, 2, 2]},
        "material": {"law": "guccione", "C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0,
                     "incompressible": True},
        "axes": {"fiber": [1.0, 0.0, 0.0], "sheet": [0.0, 1.0, 0.0]},
        "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
        "load": [{"type": "pressure" if follower else "traction", "region": "z_min",
                  "value": 0.004 if follower else [0.0, 0.0, 0.004]}],
        "spring": {"volume": "axes", "torsion": "energy", "calibration": "exact",
                   "coupling": True, "volume_average": "nodal"},
    }  # fmt: skip


@pytest.mark.parametrize("follower, fraction", [(False, 1.0), (True, 1.0), (True, 0.5)])
def test_model_tangent_matches_fd_of_its_forces(follower, fraction):
    from springmodel.model import SpringModel

    d = nodal_scene(follower)
    d["spring"]["nodal_fraction"] = fraction
    model = SpringModel(scene_from_dict(d))
    assert model.nodal is not None and model._hessian is not None  # follower or not
    rng = np.random.default_rng(0)
    x = model.x0 + 0.05 * rng.standard_normal(model.x0.shape)
    K = model.stiffness(x).toarray()
    Kfd = fd_tangent(lambda y: model.forces(y, None), x, h=1e-5)
    # the follower path adds the load's coloured central differences (relative error ~1e-9,
    # see fd_jacobian.default_step) to the springs' and the nodal term's analytic tangents:
    # a missing load tangent or a wrong colouring would give errors far above 1e-6
    assert np.abs(K - Kfd).max() < 1e-6 * np.abs(K).max()


def test_model_dilation_energy_is_the_element_models_for_every_fraction():
    """Under a uniform dilation every ``J_a = J_e``: moving ``kappa`` between the tets and
    the nodes changes nothing, and equals the per-tet (``element``) model's energy."""
    from springmodel.model import SpringModel

    d = nodal_scene(False)
    x = None
    energies = []
    for average, fraction in (("element", 1.0), ("nodal", 0.0), ("nodal", 0.5), ("nodal", 1.0)):
        d["spring"].update(volume_average=average, nodal_fraction=fraction)
        model = SpringModel(scene_from_dict(d))
        x = 1.02 * model.x0 if x is None else x
        energies.append(model.energy(x, scale=0.0))
    assert energies[0] > 0  # the volume energy dominates: kappa = 1000 mu
    assert np.allclose(energies, energies[0], rtol=1e-12, atol=0)


def test_option_needs_the_axis_volume():
    from springfem.errors import SceneError
    from springmodel.options import SpringOptions

    d = nodal_scene(False)
    d["spring"] = {"volume_average": "nodal"}
    with pytest.raises(SceneError, match="volume_average"):
        SpringOptions.of(scene_from_dict(d))
    assert SpringOptions().volume_average == "element"  # default unchanged


def test_stop_reason_reads_the_nodal_ratios():
    """A uniform dilation by 1.1: every nodal ratio is 1.331 (= 1.1^3) in the message."""
    from springmodel.model import SpringModel
    from springmodel.stop_reason import stop_reason

    model = SpringModel(scene_from_dict(nodal_scene(False)))
    text = stop_reason(1.1 * model.x0, model.x0, model.elements, model.options)
    assert "nodal volume ratio 1.33 to 1.33" in text and "nodal pressures" in text
