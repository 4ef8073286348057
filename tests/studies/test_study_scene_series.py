"""``springfem study NAME --scene FILE`` for stability, volume-drift, speed-accuracy and
anisotropy, on a non-box body: a coarse unstructured gmsh mesh (180 tets)
of a hexagonal prism along x, 0.04 m long, circumradius 8 mm, written to ``tmp_path``. (Its
side faces are parallel to x, so uniaxial stress along x is a homogeneous state of the
faceted body, which a faceted cylinder's is not.)
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from studies.cli import main

MATERIAL = """
[material]
law = "linear"
E = 1.0e4
nu = 0.3
density = 1000.0
"""

TRANSVERSE = """
[material]
law = "transverse-linear"
E_fiber = 3.0e4
E_cross = 1.0e4
nu_fiber_cross = 0.3
nu_cross = 0.4
G_fiber = 5.0e3
[axes]
fiber = [0.8660254037844387, 0.5, 0.0]
sheet = [-0.5, 0.8660254037844387, 0.0]
"""

#: Clamped at x = 0, end traction along -z (bending).
CLAMPED = """
[[boundary]]
region = "x_min"
fix = ["x", "y", "z"]
[[load]]
type = "traction"
region = "x_max"
value = [0.0, 0.0, {tz}]
"""

#: Uniaxial stress along x: x_min slides in y, z; its centre and one corner remove rigid motion.
UNIAXIAL = """
[[boundary]]
region = "x_min"
fix = ["x"]
[[boundary]]
region = {{ point = [0.0, 0.0, 0.0] }}
fix = ["y", "z"]
[[boundary]]
region = {{ point = [0.0, 0.008, 0.0] }}
fix = ["z"]
[[load]]
type = "traction"
region = "x_max"
value = [{sx}, 0.0, 0.0]
"""

R, L = 0.008, 0.04


@pytest.fixture(scope="module")
def mesh_dir(tmp_path_factory):
    gmsh = pytest.importorskip("gmsh")
    d = tmp_path_factory.mktemp("cyl")
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("prism")
        occ = gmsh.model.occ
        corners = [occ.addPoint(0, R * math.cos(k * math.pi / 3), R * math.sin(k * math.pi / 3))
                   for k in range(6)]  # fmt: skip
        loop = occ.addCurveLoop([occ.addLine(corners[k], corners[(k + 1) % 6]) for k in range(6)])
        occ.extrude([(2, occ.addPlaneSurface([loop]))], L, 0, 0)
        occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMin", 0.008)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.008)
        gmsh.model.addPhysicalGroup(3, [t for _, t in gmsh.model.getEntities(3)], name="body")
        gmsh.model.mesh.generate(3)
        gmsh.write(str(d / "cyl.msh"))
    finally:
        gmsh.finalize()
    return d


def write_scene(d, name: str, material: str, rest: str) -> str:
    path = d / f"{name}.toml"
    path.write_text(f'name = "{name}"\n[mesh]\nfile = "cyl.msh"\n{material}{rest}')
    return str(path)


def run(study: str, scene: str, out) -> None:
    assert main(["study", study, "--quick", "--scene", scene, "--out", str(out)]) == 0


@pytest.mark.slow
def test_stability_on_a_prism(mesh_dir, tmp_path):
    """Linear stability theory and linearity, on the user's mesh: symplectic Euler is stable
    iff omega_max dt < 2, so the measured step of every gradient-consistent method is
    2/omega_max within the bisection's resolution (1.5 / 2^4 < 0.1); at 1.1 dt_crit every
    damped run blows up (the damping omega_max/200 moves the bound by 0.5 %); the linear FEM's
    largest displacement is linear in the load factor."""
    scene = write_scene(mesh_dir, "cyl-bend", MATERIAL, CLAMPED.format(tz=-1.0))
    run("stability", scene, tmp_path)
    dt = pd.read_csv(tmp_path / "stability" / "critical_dt.csv").set_index("method")["ratio"]
    for m in ("spring-energy", "spring-exact", "P1", "P1-NH"):
        assert dt[m] == pytest.approx(1.0, abs=0.1), m
    load = pd.read_csv(tmp_path / "stability" / "max_load.csv")
    assert (load[load.load_factor == 1].status == "ok").all()
    lin = load[load.method == "P1"].set_index("load_factor")["u/size"]
    assert lin[100] == pytest.approx(100 * lin[1], rel=1e-6)  # the linear solve's tolerance
    fmap = pd.read_csv(tmp_path / "stability" / "failure_map.csv")
    above = fmap[(fmap.dt_factor == 1.1) & fmap.method.isin(["spring-energy", "spring-exact"])]
    assert len(above) and (above.status == "blew up").all()
    below = fmap[(fmap.dt_factor == 0.5) & (fmap.load_factor == 1)]
    assert (below.status == "ok").all()


def run_direct(study: str, scene: str, out, settings=None):
    """The study's registered function on the user's scene (the path of ``springfem study
    NAME --quick --scene FILE`` past the runner), with the quick preset by default."""
    import importlib

    from studies.cache import CaseCache
    from studies.registry import StudyContext
    from studies.scenes import StudyScene

    spec = importlib.import_module(f"studies.study_{study}").run.study
    ctx = StudyContext(spec.name, out / spec.name, True, CaseCache(out / ".cache", spec.name))
    ctx.progress = False
    settings = settings or spec.settings_for(quick=True)
    return spec.run(ctx, [StudyScene.from_file(scene)], settings)


@pytest.mark.slow
def test_volume_drift_on_a_prism_in_uniaxial_stress(mesh_dir, tmp_path):
    """Uniaxial stress sigma along the prism (BCs remove only rigid motion): P1 holds the
    homogeneous field exactly (patch test), so its volume change is the analytic
    (1 - 2 nu) sigma / E = 4e-4 up to the O(eps^2) = 1e-6 of measuring it on the deformed
    mesh (1 % tolerance); the exact axis-volume element is P1's element at small strain,
    finite-strain terms O(eps) = 0.1 %."""
    sigma, E, nu = 10.0, 1.0e4, 0.3
    scene = write_scene(mesh_dir, "cyl-pull", MATERIAL, UNIAXIAL.format(sx=sigma))
    from studies.study_volume_drift import Settings

    short = Settings(periods=2.0, ramp_periods=2.0, records=10, loads=(0.5, 1.0))
    out = run_direct("volume_drift", scene, tmp_path, short)
    s = pd.read_csv(tmp_path / "volume_drift" / "static_drift.csv")
    assert (s.status == "ok").all()
    s = s[s.load == 1.0].set_index("model")
    analytic = (1 - 2 * nu) * sigma / E
    for m in ("P1", "P1-NH", "fem", "spring-exact"):
        assert s.at[m, "dV"] == pytest.approx(analytic, rel=0.01), m
    d = pd.read_csv(tmp_path / "volume_drift" / "final_drift.csv")
    step = d[d.run == "step"].set_index("model")
    assert set(step.index) == {"spring-volume-off", "spring-volume-on", "spring-lms-spec",
                               "spring-lms-abs", "spring-volume-nnls", "spring-exact"}  # fmt: skip
    assert np.isfinite(step.loc[step.status == "ok", "dV/V0"]).all()
    assert set(d.run) == {"step", "ramp", "static"}  # every series runs on a user's scene
    # no closed form on a user's scene: its headline drift is the element drift
    assert out.headline["cyl_pull_static_element_drift_P1-NH"] == pytest.approx(
        abs(s.at["P1-NH", "element_drift"]), abs=5e-5
    )


@pytest.mark.slow
def test_speed_accuracy_on_a_refined_prism(mesh_dir, tmp_path):
    """Level 2 is the mesh file refined uniformly (8x the tets); the reference point (P2 on
    the finest level) has error 0; P1's error falls under refinement and P2 beats P1 on the
    same mesh (convergence); the exact spring element's error is P1's up to O(rotation) —
    the end rotation of this load is below 0.01 rad (its small-strain element is P1's)."""
    from studies import study_speed_accuracy
    from studies.cache import CaseCache
    from studies.registry import StudyContext
    from studies.scenes import StudyScene

    scene = write_scene(mesh_dir, "cyl-bend", MATERIAL, CLAMPED.format(tz=-1.0))
    ctx = StudyContext("speed_accuracy", tmp_path / "sa", True, CaseCache(tmp_path, "s"), False)
    study_speed_accuracy.run(
        ctx, [StudyScene.from_file(scene)], study_speed_accuracy.Settings.quick()
    )
    df = pd.read_csv(tmp_path / "sa" / "points.csv")
    d = df[df["setting"].isna()].set_index(["method", "factor"])  # static points
    err = "L2 err (level-1 vertices)"
    assert d.at[("P2 static", 2), err] == 0.0
    assert d.at[("P1 static", 2), "tets"] == 8 * d.at[("P1 static", 1), "tets"]
    assert d.at[("P1 static", 2), err] < d.at[("P1 static", 1), err]
    assert d.at[("P2 static", 1), err] < d.at[("P1 static", 1), err]
    for k in (1, 2):
        e = d.at[("spring-exact static", k), err]
        assert e == pytest.approx(d.at[("P1 static", k), err], abs=0.01)
    assert (df.status == "ok").all()
    assert df.pareto.any()


def test_anisotropy_on_a_transversely_isotropic_prism(mesh_dir, tmp_path):
    """The exact element with Poisson coupling equals the transversely isotropic P1 element
    at small strain on any tet: at strains ~1e-6 its fibre and cross-fibre errors against
    P1 vanish (1e-4: finite-strain terms and the Newton tolerance), while the seed
    calibration misses; the split adds in quadrature to the L2 error."""
    scene = write_scene(mesh_dir, "tcyl", TRANSVERSE, CLAMPED.format(tz=-0.01))
    out = run_direct("anisotropy", scene, tmp_path)
    df = pd.read_csv(tmp_path / "anisotropy" / "fibre_split.csv")
    d = df.set_index(["model", "against"])
    exact = d.loc[("spring-exact", "P1")]
    assert exact["fibre err (displ.)"] < 1e-4 and exact["cross err (displ.)"] < 1e-4
    assert d.loc[("spring-analytic", "P1"), "L2 err"] > 0.01
    split = np.hypot(df["fibre err (displ.)"], df["cross err (displ.)"])
    np.testing.assert_allclose(split, df["L2 err"], rtol=1e-10)
    assert out.headline["fibre_err_spring-exact_vs_P1"] == pytest.approx(
        exact["fibre err (displ.)"]
    )
    assert not (tmp_path / "anisotropy" / "modulus.csv").exists()  # no closed form here


def test_anisotropy_refuses_an_isotropic_scene(mesh_dir, tmp_path):
    from springfem.errors import InputError

    scene = write_scene(mesh_dir, "cyl-bend", MATERIAL, CLAMPED.format(tz=-1.0))
    with pytest.raises(InputError) as exc:
        run_direct("anisotropy", scene, tmp_path)
    msg = str(exc.value)
    assert "scene cyl-bend has isotropic material (law linear): anisotropy needs" in msg
    assert "\n" not in msg
    no_axes = TRANSVERSE.split("[axes]")[0]
    scene = write_scene(mesh_dir, "t-no-axes", no_axes, CLAMPED.format(tz=-1.0))
    with pytest.raises(InputError, match="scene t-no-axes has no \\[axes\\] section"):
        run_direct("anisotropy", scene, tmp_path)
