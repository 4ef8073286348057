"""Study ``accuracy`` on tiny variants of the bundled scenes: properties with stated
tolerances.

The study runs with tiny settings (cantilever 10x1x1, stretches 2x2x2, sag 4x2x1) and
only the cantilever gets a pyvista error-field figure, so the whole study runs in seconds.
"""

import json

import numpy as np
import pandas as pd
import pytest

from springfem.scene import scene_from_dict
from studies import analytic, models
from studies import study_accuracy as sa
from studies.cache import CaseCache
from studies.metrics import timoshenko_tip_deflection
from studies.registry import StudyContext
from studies.scenes import StudyScene, bundled_table

TINY = {
    "cantilever": (10, 1, 1),
    "stretch-fiber": (2, 2, 2),
    "stretch-cross": (2, 2, 2),
    "sag": (4, 2, 1),
}

EXTRA = {"cantilever-unstructured": (10, 2, 2), "cantilever-elongated": (5, 1, 1)}
EXTRA_NAMES = tuple(EXTRA)


@pytest.fixture(scope="module")
def output(tmp_path_factory):
    root = tmp_path_factory.mktemp("acc")
    ctx = StudyContext("accuracy", root / "accuracy", True, CaseCache(root, "a"), False)
    settings = sa.Settings(divisions=TINY, figure_scenes=("cantilever",), extra=EXTRA)
    out = sa.run(ctx, sa.bundled_scenes(settings), settings)
    errors = pd.read_csv(ctx.out / "accuracy_errors.csv").set_index("scene")
    probes = pd.read_csv(ctx.out / "accuracy_probes.csv").set_index("scene")
    return out, errors, probes


def test_outputs(output):
    out, errors, probes = output
    assert list(errors.index) == list(sa.SCENES) + list(EXTRA)
    assert len(out.figures) == 2  # bar chart + one error field
    for f in out.figures:
        assert f.path.read_bytes()[:4] == b"\x89PNG"
    n = len(sa.SCENES) + len(EXTRA)
    # model + total per scene, discretisation on two, exact model/total and the specification's vs
    # P1-NH on every scene, the exact vs P1-NH on the isotropic ones (4 of 6)
    peers = models.plugins()
    assert {"corotational", "xpbd", "mass-spring"} <= set(peers)
    prefixes = tuple(p.replace("-", "_") + "_" for p in peers)
    own = {k: v for k, v in out.headline.items() if not k.startswith(prefixes)}
    assert len(own) == 2 * n + len(sa.DISCRETISATION_HEADLINE) + 2 * n + 2 * (n - 2)
    # the plug-in models (docs/plugins.rst, docs/peers.rst): against the reference on every
    # scene whose law they take, against P1-NH on the isotropic ones (4 of 6); co-rotational
    # P1 takes every law, XPBD and the network only the isotropic ones
    isotropic = n - 2
    per_peer = {"corotational": n + isotropic, "xpbd": 2 * isotropic, "mass-spring": 2 * isotropic}
    for peer, count in per_peer.items():
        keys = [k for k in out.headline if k.startswith(peer.replace("-", "_") + "_")]
        assert len(keys) == count, (peer, keys)
    assert all(np.isfinite(v) for v in out.headline.values())
    json.dumps(out.headline)
    assert len(out.findings) == 7 + len(peers)  # one sentence per plug-in
    assert out.findings[7].startswith("corotational (a plug-in model)")


def test_xpbd_is_p1_at_small_strain(output):
    """XPBD's constraints linearise to the scene's linear elasticity on P1 tets
    (docs/peers.rst#xpbd), so at these strains its total error is the same-mesh P1's
    discretisation error, up to its O(h^2) substep bias (1-2 % of P1-NH at 40 substeps)."""
    _, errors, _ = output
    for name in ("cantilever", "cantilever-elongated"):
        p1 = errors.at[name, "discretisation err L2"]
        xpbd = errors.at[name, "xpbd total err L2"]
        assert abs(xpbd - p1) < 0.05 * p1, (name, xpbd, p1)


def test_corotational_is_p1_at_small_strain(output):
    """At these strains (<= 1 %) co-rotational P1 is linear P1 on the same mesh to O(strain):
    its total error is the same-mesh P1's discretisation error to 2 % of it (the linear-law
    scenes: sag's same-mesh P1 is neo-Hookean at nu = 0.45)."""
    _, errors, _ = output
    for name in errors.index.drop("sag"):
        p1 = errors.at[name, "discretisation err L2"]
        corot = errors.at[name, "corotational total err L2"]
        assert abs(corot - p1) < 0.02 * max(p1, 1e-2), name


def test_p1_is_exact_for_uniaxial_stretch(output):
    """Uniform strain lies in the P1 space: P1 = P2 = sigma L / E up to round-off."""
    _, errors, probes = output
    for name in ("stretch-fiber", "stretch-cross"):
        assert errors.at[name, "discretisation err L2"] < 1e-9
        assert abs(probes.at[name, "ref / analytic − 1"]) < 1e-9
        assert probes.at[name, "analytic (m)"] == pytest.approx(1e-4, rel=1e-12)


#: Strain of the stretch scenes (sigma / E = 1 %). The study solves the spring model with
#: its nonlinear kinematics at this strain; its linearisation (the D_k FEM, equal to it to
#: 1e-6 at small load: test_compare.py) differs by O(strain) (measured 1.0 % over the field):
#: numbers of the linear D_k FEM hold for the study's to 2 x strain.
STRAIN = 0.01


@pytest.mark.parametrize("name", ["stretch-fiber", "stretch-cross"])
def test_spring_stretch_errors(output, dk_reference, name):
    """The study's spring numbers on the 2x2x2 cubes against the D_k FEM (the spring
    model's own small-strain answer) and P1 on the same mesh: probe error from sigma L / E
    and L2 model error, to 2 x strain."""
    import reference_fem

    _, errors, probes = output
    dk_p1_displacement, _ = dk_reference
    scene = scene_from_dict(bundled_table(name, {"mesh.divisions": list(TINY[name])}))
    u_dk = dk_p1_displacement(scene)
    u_p1 = reference_fem.solve(scene, order=1).u_vertices
    analytic = probes.at[name, "analytic (m)"]
    probe_dk = scene.probe_displacements(u_dk)["corner"][0] / analytic - 1
    err_dk = np.linalg.norm(u_dk - u_p1) / np.linalg.norm(u_p1)
    assert probes.at[name, "spring / analytic − 1"] == pytest.approx(probe_dk, abs=2 * STRAIN)
    assert errors.at[name, "model err L2"] == pytest.approx(err_dk, abs=2 * STRAIN)
    # with P1 exact, model error and total error coincide
    assert errors.at[name, "model err L2"] == pytest.approx(
        errors.at[name, "total err L2"], rel=1e-8
    )
    # the calibration contracts too much laterally
    # (docs/theory.rst#the-radial-tensor-and-box-meshes): the sign, not a size
    assert probes.at[name, "lateral spring / ref − 1"] > 0


def test_cantilever_analytic_is_timoshenko(output):
    _, _, probes = output
    bar = StudyScene.bundled("cantilever", {"mesh.divisions": [10, 1, 1]}, analytic="timoshenko")
    probe, comp, value, source = analytic.reference(bar, bar.build())
    expected = -timoshenko_tip_deflection(0.1 * 0.01 * 0.01, 0.1, 0.01, 0.01, 1.0e4, 0.3)
    assert (probe, comp, source) == ("tip", 2, "Timoshenko")
    assert value == pytest.approx(expected, rel=1e-12)
    assert probes.at["cantilever", "analytic (m)"] == pytest.approx(expected, rel=1e-12)


def test_cantilever_coarse_mesh_errors(output):
    """On the 10x1x1 mesh P1 is far too stiff in bending (tip -78 % measured) and the spring
    model is softer than P1 (+23 % measured); P2 is within 3 % of Timoshenko."""
    _, errors, probes = output
    c = probes.loc["cantilever"]
    assert c["P1 / ref − 1"] < -0.5
    assert c["spring (m)"] / c["P1 (m)"] - 1 > 0.1
    assert abs(c["ref / analytic − 1"]) < 0.03
    assert errors.at["cantilever", "discretisation err L2"] > 0.5


def test_sag_uses_neo_hookean_reference(output):
    """Sag is large-strain (neo-Hookean law) at nu = 0.45: the reference is the verdict's,
    P2/P1 mixed of the neo-Hookean law (displacement P2 locks), and the same-mesh P1 is
    P1-NH."""
    _, errors, _ = output
    assert errors.at["sag", "reference"] == "fem-P2-mixed"
    assert errors.at["sag", "same-mesh P1"] == "P1-NH"
    assert errors.at["sag", "max strain (ref)"] > 0.05
    assert np.isfinite(errors.at["sag", "total err L2"])


def _max_strain(errors, name):
    return errors.at[name, "max strain (ref)"]


@pytest.mark.parametrize("name", ["cantilever", *EXTRA])
def test_exact_element_matches_p1_on_any_mesh(output, name):
    """The exact element's small-strain stiffness is the P1 element's on any tet
    (docs/theory.rst#the-exact-element-is-the-p1-element), so on the regular, unstructured and
    elongated cantilever meshes its error against
    P1 neo-Hookean (both at finite strain) is of higher order in the strain: below the
    reference's max Green-Lagrange strain. Against linear P1 the geometric nonlinearity of
    the finite-strain spring model remains: O(rotation), below sqrt(2 max strain) (a rotation
    theta has Green-Lagrange strain theta^2 / 2). The specification's element misses by more than 5
    %."""
    _, errors, _ = output
    strain = _max_strain(errors, name)
    assert errors.at[name, "exact model nh err L2"] < strain
    assert errors.at[name, "exact model err L2"] < np.sqrt(2 * strain)
    assert errors.at[name, "model err L2"] > 0.05


@pytest.mark.parametrize("name", ["stretch-fiber", "stretch-cross"])
def test_exact_coupling_fixes_the_stretches(output, name):
    """Exact element + Poisson coupling on the transversely isotropic stretches: P1 is exact
    (uniform strain), and the spring model solved at finite strain differs from it at
    O(strain) = 1 %; the specification's element's lateral contraction error is gone."""
    _, errors, probes = output
    assert errors.at[name, "exact model err L2"] < STRAIN
    assert errors.at[name, "model err L2"] > 5 * STRAIN
    assert abs(probes.at[name, "exact / ref − 1"]) < STRAIN


def test_unstructured_mesh_is_delaunay_of_the_box(output):
    """The jittered Delaunay mesh fills the cantilever's box exactly (its faces stay planar)."""
    scene = next(s for s in sa.bundled_scenes(sa.Settings()) if s.label == EXTRA_NAMES[0])
    assert scene.table["mesh"]["split"] == "delaunay"
    m = scene.with_sets({"mesh.divisions": [10, 2, 2]}).build().mesh
    assert m.volumes().sum() == pytest.approx(1e-5, rel=1e-12)
    assert (m.volumes() > 0).all()
    lo, hi = m.bounding_box()
    np.testing.assert_allclose(hi - lo, [0.1, 0.01, 0.01], rtol=1e-14)
