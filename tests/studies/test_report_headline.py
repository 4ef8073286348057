"""The quick report's headline numbers: against independent references, and as a regression.

The quick report runs once in CI: ``.ci/run`` writes it into ``reports/quick/`` and then runs
the test suite, whose ``written`` cases check those files (they skip when no quick report
has been written; set ``SPRINGFEM_QUICK_REPORT`` to check another folder). The ``fresh``
case (``-m slow``) runs the quick report itself into a temporary folder.

Two checks:

- every headline with an independent reference (analytic value, an invariant between two
  code paths, linear stability theory) is compared with it, tolerance and reason stated in
  :data:`REFERENCES`;
- every other headline is compared with the committed ``reports/headline-quick.json`` (a
  regression check only: that file is written by the same code). The timing-derived keys
  in :data:`TIMING_KEYS` are only checked for being finite.

After an intentional change of a model, regenerate the committed file with
``springfem report --quick --out reports/quick && cp reports/quick/headline-quick.json
reports/`` and say why in the commit.
"""

import json
import math
import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
COMMITTED = ROOT / "reports" / "headline-quick.json"
WRITTEN = Path(os.environ.get("SPRINGFEM_QUICK_REPORT", ROOT / "reports" / "quick"))

#: Timing-derived headlines (fitted cost slopes): noisy on a shared machine, finite only.
TIMING_KEYS = {
    # costs per explicit step
    "dynamics": {
        "land-beam_P1_step_us",
        *(
            f"land-beam_{m}_cost_ratio"
            for m in ("spring-exact", "spring-stiffened", "spring-tissue")
        ),
        "land-beam-nh_P1-NH_step_us",
        *(
            f"land-beam-nh_{m}_cost_ratio"
            for m in ("spring-exact", "corotational", "mass-spring", "xpbd", "vbd", "pd", "pd-nh")
        ),
    },
    # the cheapest method within the tolerance is picked by its solve time
    "locking": {
        f"cheapest_error_{scene}_nu{nu}"
        for scene in ("cook-membrane", "land-beam")
        for nu in ("0.3", "0.49", "0.4999")
    },
    # the cheapest frame of each model (its errors are not timings: they are checked)
    "frame_budget": {
        f"pull-release_{rate}Hz_{m}_ms_min" for rate in (60, 1000) for m in ("P1-NH", "xpbd", "vbd")
    },
    "scaling": {
        "slope_static_P1",
        "slope_static_P1-NH",
        "slope_static_spring",
        "slope_step_fem",
        "slope_step_spring",
    },
}

# Relative tolerance of the regression check: the quick studies are deterministic apart
# from solver stopping points (Newton tolerances 1e-8, dynamic relaxation 1e-6..1e-8), which
# move errors of order 1e-2 by far less than 2 %; a model regression moves them by more.
REL_TOL = 0.02
ABS_TOL = 1e-6
#: Headlines rounded to 4 decimals by the studies are exact to half a unit of the 4th.
ROUNDING = 5e-5


def _same(study: str, key: str):
    return lambda h: h[study][key]


#: ``(study, key) -> (reference(headline) -> value, abs tolerance, reason)``.
REFERENCES = {
    ("anisotropy", "ratio_analytic"): (
        lambda h: 30e3 / 10e3,
        1e-12,
        "E_fiber / E_cross of the stretch-fiber material",
    ),
    ("anisotropy", "ratio_P1"): (
        lambda h: 3.0,
        ROUNDING,
        "P1 is exact for a homogeneous field (patch test)",
    ),
    ("anisotropy", "max_rel_error_P1"): (
        lambda h: 0.0,
        ROUNDING,
        "P1 reproduces the off-axis formula exactly",
    ),
    ("anisotropy", "ratio_spring-exact"): (
        lambda h: 30e3 / 10e3,
        3.0 * (0.01 + 0.03),
        "exact element + coupling = P1 at small strain; each modulus is off by at most its "
        "applied strain (1 % along, 3 % across the fibers) from the finite-strain kinematics",
    ),
    ("anisotropy", "max_rel_error_spring-exact"): (
        lambda h: 0.0,
        0.03,
        "at most the largest applied strain (3 %, across the fibers): finite-strain kinematics",
    ),
    ("volume_drift", "cube_compressed_analytic_dV"): (
        lambda h: (1 - 2 * 0.49) * 0.1,
        1e-12,
        "(1 - 2 nu) sigma / E, nu = 0.49, sigma = 0.1 E",
    ),
    ("volume_drift", "cube_compressed_static_dV_P1-NH"): (
        lambda h: (1 - 2 * 0.49) * 0.1,
        0.1 * 0.002,
        "small-strain value; finite-strain terms are of relative order eps = 0.1",
    ),
    ("volume_drift", "cube_compressed_ramp_dV_spring-exact"): (
        lambda h: (1 - 2 * 0.49) * 0.1,
        0.1 * 0.002,
        "the axis-volume spring's J is the true volume ratio and its small-strain element is "
        "P1's: the material's small-strain value; finite-strain terms of relative order 0.1",
    ),
    ("anisotropy", "ratio_P2"): (
        lambda h: 3.0,
        ROUNDING,
        "P2 is exact for a homogeneous field (patch test)",
    ),
    ("anisotropy", "max_rel_error_P2"): (
        lambda h: 0.0,
        ROUNDING,
        "P2 reproduces the off-axis formula exactly",
    ),
    ("volume_drift", "cube_pulled_analytic_dV"): (
        lambda h: (1 - 2 * 0.49) * 0.1,
        1e-12,
        "(1 - 2 nu) sigma / E, nu = 0.49, sigma = 0.1 E (in tension)",
    ),
    ("volume_drift", "cube_pulled_static_dV_P1-NH"): (
        lambda h: (1 - 2 * 0.49) * 0.1,
        0.1 * 0.002,
        "small-strain value; finite-strain terms are of relative order eps = 0.1",
    ),
    ("volume_drift", "cube_pulled_ramp_dV_spring-exact"): (
        lambda h: (1 - 2 * 0.49) * 0.1,
        0.1 * 0.002,
        "the axis-volume spring's J is the true volume ratio and its small-strain element is "
        "P1's: the material's small-strain value; finite-strain terms of relative order 0.1",
    ),
    ("speed_accuracy", "tip_error_spring-exact_static_20x2x2"): (
        _same("speed_accuracy", "tip_error_P1_static_20x2x2"),
        2 * ROUNDING + 4e-3,
        "the exact element's small-strain stiffness is P1's "
        "(docs/theory.rst#the-exact-element-is-the-p1-element); its finite-strain "
        "kinematics move the tip by O(tip rotation w/L = 4e-3, Timoshenko)",
    ),
    ("convergence", "tip_err_finest_spring-exact"): (
        _same("convergence", "tip_err_finest_P1"),
        4e-3,
        "the exact element's small-strain stiffness is P1's "
        "(docs/theory.rst#the-exact-element-is-the-p1-element); its finite-strain "
        "kinematics move the tip by O(tip rotation w/L = 4e-3, Timoshenko)",
    ),
    ("convergence", "rate_l2_spring-exact"): (
        _same("convergence", "rate_l2_P1"),
        0.01,
        "same errors as P1 up to O(4e-3) relative on each level: the fitted slope moves by "
        "well under 0.01",
    ),
    ("stability", "locking_tip_ratio_spring-exact"): (
        _same("stability", "locking_tip_ratio_P1"),
        2e-3,
        "the exact element is P1's element at small strain "
        "(docs/theory.rst#the-exact-element-is-the-p1-element), so it locks like P1; "
        "3-decimal rounding and O(w/L) finite-strain kinematics",
    ),
    ("convergence", "ref_over_timoshenko"): (
        lambda h: 1.0,
        0.02,
        "P2 vs Timoshenko beam theory, which ignores the 3D clamping (~1 %)",
    ),
    ("speed_accuracy", "tip_error_P1-NH_explicit_20x2x2"): (
        _same("speed_accuracy", "tip_error_P1_static_20x2x2"),
        2 * ROUNDING + 1e-4,
        "explicit neo-Hookean P1 relaxes to the static P1 answer (small load, tol 1e-6)",
    ),
}
for _scene in ("stretch_fiber", "stretch_cross"):
    # P1 is exact on the uniaxial stretches, so model error == total error (round-off)
    REFERENCES[("accuracy", f"total_l2_{_scene}")] = (
        _same("accuracy", f"model_l2_{_scene}"),
        1e-8,
        "P1 = P2 = exact on a uniform stretch",
    )
for _scene in ("cantilever", "cantilever_unstructured", "cantilever_elongated"):
    # the exact element's small-strain stiffness is the P1 element's on any tet
    # (docs/theory.rst#the-exact-element-is-the-p1-element);
    # solved at finite strain like P1 neo-Hookean, they differ at third order in the strain
    # (max Green-Lagrange strain 6e-4 .. 3e-3 at this load): relative L2 below 1e-4
    REFERENCES[("accuracy", f"exact_model_nh_l2_{_scene}")] = (
        lambda h: 0.0,
        1e-4,
        "exact element = P1 element at small strain; vs P1-NH only higher-order terms remain",
    )
for _scene in ("stretch_fiber", "stretch_cross"):
    REFERENCES[("accuracy", f"exact_total_l2_{_scene}")] = (
        _same("accuracy", f"exact_model_l2_{_scene}"),
        1e-8,
        "P1 = P2 = exact on a uniform stretch",
    )
for _method in ("spring-energy", "spring-cosine", "P1", "P1-NH", "spring-exact", "mass-spring"):
    REFERENCES[("stability", f"dt_ratio_{_method}")] = (
        lambda h: 1.0,
        0.1,
        "symplectic Euler is stable iff omega_max dt < 2; bisection resolution 1.5/2^4",
    )
for _scene, _key in (  # not the cantilever: its two solves differ by 3.5e-4 (not understood)
    ("sag", "sag"),
    ("stretch-fiber", "stretch_fiber"),
    ("stretch-cross", "stretch_cross"),
):
    # two code paths, same model and mesh: the ablation's full spring model against its own
    # P1 solve, and compare_scene's spring vs same-mesh P1 (headline rounded to 4 decimals;
    # solver tolerances 1e-8)
    REFERENCES[("ablation", f"full_error_{_scene}")] = (
        _same("accuracy", f"model_l2_{_key}"),
        ROUNDING + 1e-6,
        "accuracy's model error",
    )
for _scene, _key, _variant, _acc in (
    # the exact element in two code paths (the ablation's own solves against its P1 with the
    # scene's law; accuracy's compare_scene): same model, mesh and reference; solver
    # tolerances 1e-8
    ("cantilever", "cantilever", "exact", "exact_model"),
    ("cantilever-unstructured", "cantilever_unstructured", "exact", "exact_model"),
    ("cantilever-elongated", "cantilever_elongated", "exact", "exact_model"),
    ("sag", "sag", "exact", "exact_model_nh"),  # the sag's P1 is neo-Hookean
    ("stretch-fiber", "stretch_fiber", "exact_coupling", "exact_model"),
    ("stretch-cross", "stretch_cross", "exact_coupling", "exact_model"),
):
    REFERENCES[("ablation", f"{_variant}_error_{_scene}")] = (
        _same("accuracy", f"{_acc}_l2_{_key}"),
        1e-6,
        "accuracy's exact-element model error (same solve, other code path)",
    )


def _load(path: Path) -> dict:
    return json.loads(path.read_text())


@pytest.fixture(scope="module", params=["written", pytest.param("fresh", marks=pytest.mark.slow)])
def quick_headline(request, tmp_path_factory):
    if request.param == "written":
        path = WRITTEN / "headline-quick.json"
        if not path.is_file():
            pytest.skip(f"no quick report in {WRITTEN} (springfem report --quick writes it)")
        return _load(path), WRITTEN
    from studies.runner import run_report

    out = tmp_path_factory.mktemp("quick-report")
    outputs = run_report(out, quick=True)
    return {o.name: o.headline for o in outputs}, out


def test_committed_headline_exists():
    assert COMMITTED.is_file(), "run the quick report and commit reports/headline-quick.json"


def test_timing_keys_exist():
    """The exempt keys are real headline keys (a renamed key must not escape the check)."""
    committed = _load(COMMITTED)
    for study, keys in TIMING_KEYS.items():
        assert keys <= set(committed[study]), keys - set(committed[study])
    for study, key in REFERENCES:
        assert key in committed[study], (study, key)


def test_report_files(quick_headline):
    _, root = quick_headline
    assert (root / "REPORT.md").is_file()
    for png in root.glob("*/*.png"):
        assert png.stat().st_size > 10_000, png  # a real picture


def test_headline_numbers_match_independent_references(quick_headline):
    headline, _ = quick_headline
    failures = []
    for (study, key), (reference, tol, reason) in REFERENCES.items():
        got, ref = headline[study][key], reference(headline)
        if not abs(got - ref) <= tol:
            failures.append(f"{study}.{key} = {got:.6g}, reference {ref:.6g} ± {tol:g} ({reason})")
    assert not failures, "\n".join(failures)


def _none_if_nan(value):
    return None if isinstance(value, float) and math.isnan(value) else value


def test_headline_numbers_match_committed(quick_headline):
    headline, _ = quick_headline
    committed = _load(COMMITTED)
    assert set(committed) == set(headline)
    failures = []
    for study, values in committed.items():
        assert set(values) == set(headline[study]), study
        for key, ref in values.items():
            got = _none_if_nan(headline[study][key])  # a fresh run's NaN is JSON's null
            where = f"{study}.{key}"
            if got is None or ref is None:
                if got != ref:
                    failures.append(f"{where}: {got} != {ref}")
            elif key in TIMING_KEYS.get(study, ()):
                if not math.isfinite(got):
                    failures.append(f"{where}: not finite ({got})")
            elif not math.isclose(got, ref, rel_tol=REL_TOL, abs_tol=ABS_TOL):
                failures.append(f"{where}: {got:.6g} vs committed {ref:.6g}")
    assert not failures, "\n".join(failures)
