"""Exponential stiffening of the spring element (``[spring] stiffening = "exponential"``).

References: the element energy under a stretch along a frame axis written out by hand;
central finite differences of the energy (forces) and of the forces (tangent) on irregular
Delaunay tets at a large deformation; the quadratic element's tangent at rest (unchanged);
and the Guccione P1 FEM under homogeneous stretches, which the stiffened Green-strain
element must reproduce exactly (module :mod:`springmodel.stiffening`).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import Delaunay

from springfem.errors import InputError, SceneError
from springfem.scene import Material, scene_from_dict
from springfem.volumetric import volumetric_energy
from springmodel.elements import build_spring_elements
from springmodel.hessian import SpringHessian
from springmodel.options import SpringOptions
from springmodel.spring_kernel import SpringKernel
from springmodel.springs.points import scatter
from springmodel.stiffening import StiffeningPart, deviatoric_energy, stiffening_modulus

GUCCIONE = {"C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0, "kappa": 100.0}
EXACT = dict(volume="axes", calibration="exact", coupling=True, torsion="shear")
#: The axial law ``k l0^2 E^2 / 2`` in the spring's Green strain ``E = (lambda^2 - 1) / 2``:
#: ``d^2/2 + b2 d^3/(3 l0) + b3 d^4/(4 l0^2)`` with ``b2 = 3/2, b3 = 1/2`` (eq. 2.36).
GREEN = dict(axial="cubic", axial_coefficients=(1.5, 0.5))


def guccione(kappa=100.0, volumetric="quadratic"):
    return Material(
        "guccione", 3 * 2.0, 0.49, parameters={**GUCCIONE, "kappa": kappa},
        volumetric=volumetric,
    )  # fmt: skip


def jittered(seed=5):
    """Delaunay tets of random points (irregular), slivers dropped, random fibre frames."""
    rng = np.random.default_rng(seed)
    X = rng.random((40, 3)) * np.array([2.0, 1.0, 1.5])
    tets = Delaunay(X).simplices
    V = np.linalg.det(X[tets[:, 1:]] - X[tets[:, :1]]) / 6.0
    tets = tets[np.abs(V) > 2e-3]
    q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    return X, tets, np.broadcast_to(q.T, (len(tets), 3, 3)).copy(), rng


def parts(X, tets, frames, opts, material):
    el = build_spring_elements(X, tets, frames, opts, material)
    C = stiffening_modulus(opts, material)
    return el, SpringKernel(el, opts), SpringHessian(el, opts), StiffeningPart(el, opts, C)


def total_energy(x, kernel, part):
    return kernel.energy(x) + part.energy(x)


def total_forces(x, kernel, part):
    return kernel.forces(x) + part.forces(x)


def test_energy_of_a_stretch_along_a_frame_axis_is_the_written_out_exponential():
    # one regular-ish tet, isotropic Guccione (b = 1): exact calibration gives k_l l_l^2 / V = C
    # and kappa on the axis-volume spring, so under F = diag(lam, 1, 1) in the frame
    # W = V C/2 (exp((lam - 1)^2) - 1) + V U(lam) for the linear axial law
    X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    tets = np.array([[0, 1, 2, 3]])
    mat = Material("guccione", 30.0, 0.49, parameters={"C": 10.0, "b_f": 1.0, "b_t": 1.0,
                                                       "b_fs": 1.0, "kappa": 100.0})  # fmt: skip
    opts = SpringOptions(**{**EXACT, "torsion": "energy"}, stiffening="exponential")
    el, kernel, _, part = parts(X, tets, np.eye(3)[None], opts, mat)
    V = 1 / 6
    for lam in (0.8, 1.1, 1.4):
        x = X * np.array([lam, 1.0, 1.0])
        U, _, _ = volumetric_energy(np.array([lam]), 100.0, "quadratic")
        expected = V * 10.0 / 2 * np.expm1((lam - 1) ** 2) + V * U[0]
        assert total_energy(x, kernel, part) == pytest.approx(expected, rel=1e-12)


def transverse():
    """A transversely isotropic material: the exact calibration puts non-zero constants on
    the Poisson-coupling springs (Guccione's are zero), which the stiffening wraps too."""
    return Material("transverse-linear", 10.0, 0.3, E_fiber=30.0, E_cross=10.0,
                    nu_fiber_cross=0.25, nu_cross=0.4, G_fiber=4.0)  # fmt: skip


CASES = {
    "guccione-linear-shear": (guccione, {"torsion": "shear"}),
    "guccione-green-shear": (guccione, {"torsion": "shear", **GREEN}),
    "transverse-energy": (transverse, {"torsion": "energy", "stiffening_modulus": 5.0}),
    "transverse-green-off": (transverse, {"torsion": "off", **GREEN, "stiffening_modulus": 5.0}),
}


def case_parts(name):
    X, tets, frames, rng = jittered()
    material, extra = CASES[name]
    opts = SpringOptions(**{**EXACT, **extra}, stiffening="exponential")
    return X, rng, opts, parts(X, tets, frames, opts, material())


def deformed(X, rng):
    A = np.array([[1.3, 0.2, 0.0], [0.0, 0.95, 0.1], [0.0, 0.0, 0.9]])
    return X @ A.T + 0.003 * rng.standard_normal(X.shape)  # 30 % stretch, 20 % shear


@pytest.mark.parametrize("name", list(CASES))
def test_compiled_pass_equals_the_numpy_reference(name):
    X, rng, opts, (el, _, _, part) = case_parts(name)
    x = deformed(X, rng)
    W_ref, g = deviatoric_energy(x, el, opts)
    W, s = part.scale(x)
    assert np.abs(W - W_ref).max() < 1e-13 * np.abs(W_ref).max()
    if "transverse" in name:
        assert np.abs(el.k_coupling).max() > 1e-3 * np.abs(el.k_axial * el.l0**2).max()
    f_ref = scatter(-(s - 1.0)[:, None, None] * g, el.tets, el.n_points)
    assert np.abs(part.forces(x) - f_ref).max() < 1e-12 * np.abs(f_ref).max()


@pytest.mark.parametrize("name", list(CASES))
def test_forces_are_the_energy_gradient_and_tangent_the_force_derivative(name):
    X, rng, opts, (el, kernel, hessian, part) = case_parts(name)
    x = deformed(X, rng)
    _, s = part.scale(x)
    assert s.max() > 1.5 and np.isfinite(s).all()  # into the exponential, not past the cap
    f = total_forces(x, kernel, part)
    h = 1e-6
    g = np.zeros_like(x)
    for i in range(x.shape[0]):
        for a in range(3):
            xp, xm = x.copy(), x.copy()
            xp[i, a] += h
            xm[i, a] -= h
            g[i, a] = -(total_energy(xp, kernel, part) - total_energy(xm, kernel, part)) / (2 * h)
    # central differences on O(1) coordinates: truncation ~h^2, roundoff ~1e-16 |W| / h
    assert np.abs(f - g).max() < 1e-6 * np.abs(f).max()
    K = (hessian.matrix(x) + part.stiffness(x)).toarray()
    assert np.abs(K - K.T).max() < 1e-12 * np.abs(K).max()
    Kfd = np.zeros_like(K)
    for j in range(x.size):
        xp, xm = x.ravel().copy(), x.ravel().copy()
        xp[j] += h
        xm[j] -= h
        df = total_forces(xp.reshape(-1, 3), kernel, part) - total_forces(
            xm.reshape(-1, 3), kernel, part
        )
        Kfd[:, j] = -df.ravel() / (2 * h)
    assert np.abs(K - Kfd).max() < 1e-6 * np.abs(K).max()


def test_small_strain_response_is_the_quadratic_element_and_large_strain_is_not():
    # the added force -(s - 1) grad W_q is O(u^3) against the quadratic element's O(u): their
    # ratio falls as u^2 (x 100 per decade of u); at strains of some 10 % the stiffening
    # dominates (random displacements of 0.01 on these ~0.1-0.3 tets)
    X, tets, frames, rng = jittered()
    opts = SpringOptions(**EXACT, stiffening="exponential")
    el, kernel, _, part = parts(X, tets, frames, opts, guccione())
    direction = rng.standard_normal(X.shape) / 10.0

    def ratio(size):
        x = X + size * direction
        return np.abs(part.forces(x)).max() / np.abs(kernel.forces(x)).max()

    assert ratio(1e-4) / ratio(1e-5) == pytest.approx(100.0, rel=0.01)
    assert ratio(1e-5) < 1e-6
    assert 1.0 < ratio(0.1) < np.inf


def test_model_tangent_is_the_derivative_of_its_forces(jittered_cube):
    # SpringModel wiring: kernel + stiffening (+ nodal volume) forces, energy and tangent,
    # and with a follower pressure (the springs' analytic tangent + the load's differences)
    from springmodel.model import SpringModel

    pressure = {"type": "pressure", "region": "z_max", "value": 0.5}  # a follower load
    for extra, load in (({}, None), ({"volume_average": "nodal", "nodal_fraction": 0.8}, None),
                        ({}, pressure), ({"volume_average": "nodal"}, pressure)):  # fmt: skip
        spring = {**EXACT, "axial": "green", "stiffening": "exponential", **extra}
        loads = [] if load is None else [load]
        model = SpringModel(stretch_scene("along", 1.2, spring, jittered_cube, loads))
        rng = np.random.default_rng(2)
        x = model.x0 * np.array([1.2, 0.93, 0.93]) + 0.01 * rng.standard_normal(model.x0.shape)
        K = model.stiffness(x).toarray()
        h = 1e-6
        cols = rng.choice(x.size, 40, replace=False)  # 40 columns of 192: every DOF kind
        K = K[:, cols]
        Kfd = np.zeros_like(K)
        for c, j in enumerate(cols):
            xp, xm = x.ravel().copy(), x.ravel().copy()
            xp[j] += h
            xm[j] -= h
            df = model.forces(xp.reshape(-1, 3), None) - model.forces(xm.reshape(-1, 3), None)
            Kfd[:, c] = -df.ravel() / (2 * h)
        assert np.abs(K - Kfd).max() < 1e-6 * np.abs(K).max()
        if load is not None:
            continue  # a follower load has no potential
        dx = 1e-6 * rng.standard_normal(x.shape)
        dE = model.energy(x + dx) - model.energy(x - dx)
        assert dE == pytest.approx(-2 * np.sum(model.forces(x, None) * dx), rel=1e-6)


@pytest.fixture(scope="module")
def jittered_cube(tmp_path_factory):
    """A unit cube of 3^3 boxes whose nodes are moved by up to 0.3 h (within their faces)."""
    import meshio

    from springfem.mesh import box_mesh

    mesh = box_mesh((1.0, 1.0, 1.0), (3, 3, 3))
    X = mesh.points.copy()
    rng = np.random.default_rng(11)
    inside = (X > 1e-9) & (X < 1 - 1e-9)  # a coordinate on a face stays on it
    X[inside] += rng.uniform(-0.1, 0.1, inside.sum())
    path = tmp_path_factory.mktemp("cube") / "jittered.vtu"
    meshio.write(path, meshio.Mesh(X, [("tetra", mesh.tets)]))
    return path


def stretch_scene(direction, stretch, spring, mesh_file, loads=()):
    """The tissue study's cube pulled along x (fibre along or across), on ``mesh_file``."""
    from studies.study_tissue import stretch_data

    data = stretch_data(direction, stretch, 1)
    data["load"] = list(loads)
    data["mesh"] = {"file": str(mesh_file)}
    data["material"]["volumetric"] = "quadratic"
    data["spring"] = spring
    return scene_from_dict(data)


@pytest.mark.parametrize("direction", ["along", "across"])
def test_green_stiffened_element_reproduces_guccione_under_a_homogeneous_stretch(
    direction, jittered_cube
):
    # Under F = diag(l1, l2, l3) in the fibre frame the axes stretch by l_i and stay
    # orthogonal: the Green-strain axial energy is V C/2 (b_f E_11^2 + b_t (E_22^2 + E_33^2)),
    # 2 W_q / (C V) is the law's Q and the element equals Guccione + penalty; the P1 FEM is exact
    # for the homogeneous solution, so both reactions agree to solver tolerance. The quadratic
    # (spec) element is 30-75 % off at 30 % stretch.
    from studies.solve import solve_scene

    spring = {**EXACT, "axial": "green", "volumetric": "quadratic"}  # cubic, (1.5, 0.5)

    def reaction(model, **extra):
        scene = stretch_scene(direction, 1.3, {**spring, **extra}, jittered_cube)
        return solve_scene(scene, model).result.reactions["x_max"][0]

    fem = reaction("fem")
    stiff = reaction("spring", stiffening="exponential")
    plain = reaction("spring")
    assert stiff == pytest.approx(fem, rel=1e-6)
    assert abs(plain / fem - 1) > 0.2


def test_scene_errors_name_the_key():
    base = {"name": "s", "mesh": {"generator": "box", "size": [1, 1, 1], "divisions": [1, 1, 1]},
            "material": {"law": "linear", "E": 1e4, "nu": 0.3}}  # fmt: skip
    with pytest.raises(SceneError, match=r"spring\.stiffening.*energy to exponentiate"):
        scene_from_dict({**base, "spring": {"stiffening": "exponential"}})  # cosine torsion
    with pytest.raises(SceneError, match=r"spring\.stiffening.*off, exponential|not one of"):
        scene_from_dict({**base, "spring": {"stiffening": "cubic"}})
    with pytest.raises(SceneError, match=r"axial_coefficients.*green"):
        scene_from_dict({**base, "spring": {"axial": "green", "axial_coefficients": [1, 1]}})
    green = scene_from_dict({**base, "spring": {"axial": "green"}})
    assert SpringOptions.of(green).axial_coefficients == (1.5, 0.5)
    with pytest.raises(SceneError, match=r"stiffening_modulus"):
        scene_from_dict({**base, "spring": {"stiffening_modulus": -1.0}})
    # the linear law has no C: the model says which key to give
    from springmodel.model import SpringModel

    scene = scene_from_dict({**base, "spring": {**EXACT, "stiffening": "exponential"}})
    with pytest.raises(InputError, match="needs stiffening_modulus for law 'linear'"):
        SpringModel(scene)
    ho = Material("holzapfel-ogden", 1.0, 0.49, parameters={"a_f": 18.472, "b_f": 16.026})
    assert stiffening_modulus(SpringOptions(**EXACT, stiffening="exponential"), ho) == (
        pytest.approx(18.472 / 16.026)
    )


@pytest.mark.parametrize(
    "name", [pytest.param("land-ventricle", marks=pytest.mark.slow), "land-ventricle-fibres"]
)
@pytest.mark.slow
def test_bundled_ventricles_run_to_full_load_where_quadratic_springs_stop(name):
    # Land problems 2 and 3 on a coarse gmsh mesh: the stiffened element carries the
    # 10 kPa (a converged static solve at load factor 1, the cavity inflated), the same
    # element with the spec's quadratic springs stops part way with its load factor named
    import tomllib
    from pathlib import Path

    from springfem.errors import SolverError
    from studies.solve import solve_scene

    path = Path(__file__).resolve().parents[2] / "studies" / "scenes" / f"{name}.toml"
    data = tomllib.loads(path.read_text())
    data["mesh"]["size"] = 6.0
    data["spring"] = {  # the stiffened exact element (the scenes now use the tissue element)
        "volume": "axes", "torsion": "shear", "calibration": "exact", "coupling": True,
        "axial": "green", "stiffening": "exponential", "volumetric": "log",
    }  # fmt: skip
    sol = solve_scene(scene_from_dict(data, path), "spring")
    assert sol.result.converged and sol.result.info.get("load_factor", 1.0) == 1.0
    cavity = sol.result.info["cavity"]
    assert cavity["final"] > 1.2 * cavity["initial"]
    quadratic = {k: v for k, v in data["spring"].items() if k not in ("axial", "stiffening")}
    with pytest.raises(SolverError, match="stopped at load factor 0") as err:
        solve_scene(scene_from_dict({**data, "spring": quadratic}, path), "spring")
    assert 0.0 < err.value.load_factor < 1.0


def test_stop_reason_names_the_largest_stiffening_factor():
    from springmodel.stop_reason import stop_reason

    X, rng, opts, (el, _, _, part) = case_parts("guccione-green-shear")
    x = deformed(X, rng)
    s_max = part.scale(x)[1].max()
    text = stop_reason(x, X, el, opts, part)
    assert f"stiffening factor up to {s_max:.3g}" in text
    past = stop_reason(X + 10.0 * (x - X), X, el, opts, part)  # strains of hundreds of %
    assert "past the stiffening's cap" in past
