"""The stability study's plug-in peers: the mass-spring network's critical step against an
eigenvalue solve of its own stiffness and mass, XPBD's step search against the ordering of
its two iterations, and the peers in every series they apply to."""

import numpy as np
import pytest
import scipy.linalg

from peers.plugin import XPBDModel
from peers.xpbd.step_search import measure_step, survives
from springfem.errors import SolverError
from studies import models
from studies.scenes import case_scene
from studies.study_stability import survival
from studies.study_stability.cases import VERSION, bar, critical_step_case, grids
from studies.study_stability.cases import Settings as StabilitySettings

#: The plug-in's own settings and its Jacobi variant's (what the study's step search runs).
_JACOBI = XPBDModel().with_settings(**XPBDModel.VARIANTS["xpbd-jacobi"])
XPBD = {"xpbd": XPBDModel()._settings, "xpbd-jacobi": _JACOBI._settings}


def measure_xpbd_step(scene, method: str, steps: int, bisections: int) -> dict:
    return measure_step(scene, XPBD[method], steps, bisections)


def _case(kind: str, **kw) -> dict:
    return bar(10, 1, ("dt",)).case("stability-test", VERSION, kind=kind, **kw)


def _fd_stiffness(system, x: np.ndarray, free: np.ndarray) -> np.ndarray:
    """``-d f_int / d x`` on the free DOFs by central differences of the internal forces
    (independent of the network's own tangent)."""
    h = 1e-7 * float(np.ptp(x))
    K = np.empty((free.size, free.size))
    for j, d in enumerate(free):
        e = np.zeros(x.size)
        e[d] = h
        fp = system.internal((x.ravel() + e).reshape(x.shape)).ravel()
        fm = system.internal((x.ravel() - e).reshape(x.shape)).ravel()
        K[:, j] = -(fp - fm)[free] / (2 * h)
    return 0.5 * (K + K.T)


def test_mass_spring_critical_step_is_two_over_its_highest_frequency():
    """Central differences on a linear(ised) system are stable iff ``omega_max dt < 2``:
    ``omega_max`` from a dense generalised eigen-solve of the network's finite-difference
    stiffness and lumped mass (free DOFs). The study's predicted step equals ``2/omega_max``
    to the eigen-solve's precision (FD error ~1e-7 relative), and the bisected step lies
    within the bisection's resolution (1.5/2^4) plus the finite-run margin of the explicit
    series' own test (0.85 to 1.15)."""
    case = _case("dt", method="mass-spring", steps=600, bisections=4)
    system = models.get("mass-spring").system(case_scene(case, 0.0))
    free = np.setdiff1d(np.arange(system.x0.size), system.fixed_dofs)
    K = _fd_stiffness(system, system.x0, free)
    M = np.repeat(system.masses, 3)[free]
    omega = float(np.sqrt(scipy.linalg.eigh(K, np.diag(M), eigvals_only=True).max()))
    r = critical_step_case(case)
    assert r["dt_pred"] == pytest.approx(2.0 / omega, rel=1e-4)
    assert 0.85 <= r["dt_measured"] * omega / 2.0 <= 1.15


def test_gauss_seidel_xpbd_survives_longer_substeps_than_jacobi():
    """Jacobi applies every correction from the same positions and averages them (docs/
    peers.rst: it blew up on the large-rotation cantilever where Gauss–Seidel did not), so
    its largest surviving substep is below Gauss–Seidel's; both are measured on the same
    bar with the same perturbation. At a small substep (a tenth of the bound) both survive:
    the search is not failing everything."""
    scene = case_scene(_case("dt", method="xpbd"), 0.0)
    gs = measure_xpbd_step(scene, "xpbd", steps=400, bisections=3)
    jac = measure_xpbd_step(scene, "xpbd-jacobi", steps=400, bisections=3)
    assert jac["ratio"] < gs["ratio"]
    v0 = np.zeros(scene.mesh.points.shape)
    v0[-1, 2] = 1e-6
    for m in ("xpbd", "xpbd-jacobi"):
        assert survives(scene, XPBD[m], 0.1 * gs["dt_pred"], 200, v0) is None


def test_xpbd_unstable_substep_is_caught_by_energy_growth_not_only_by_nan():
    """Well past its limit (4x the largest surviving substep), an undamped Gauss–Seidel run
    from a tiny perturbation grows its energy by orders of magnitude: the search reports a
    failure (energy, inversion or non-finite positions) at that step."""
    scene = case_scene(_case("dt", method="xpbd"), 0.0)
    gs = measure_xpbd_step(scene, "xpbd", steps=400, bisections=2)
    rng = np.random.default_rng(0)
    v0 = 1e-6 * rng.standard_normal(scene.mesh.points.shape)
    v0.reshape(-1)[scene.dirichlet()[0]] = 0.0
    assert survives(scene, XPBD["xpbd"], 4 * gs["dt_measured"], 400, v0) is not None


def test_peers_join_the_series_they_apply_to():
    """On the isotropic bar: the mass-spring network (a mechanical system) in the critical
    step and failure-map series, XPBD (no mechanical system) and its Jacobi variant in the
    critical-step search and the largest-load series, as the network."""
    q = StabilitySettings.quick()
    cases = grids([bar(10, 1, ("dt", "load", "map"))], q)
    got = {k: {c["method"] for c in v} for k, v in cases.items()}
    assert {"mass-spring", "xpbd", "xpbd-jacobi"} <= got["dt"]
    assert {"mass-spring", "xpbd", "xpbd-jacobi"} <= got["load"]
    assert "mass-spring" in got["map"] and "xpbd" not in got["map"]


def test_survival_table_takes_the_largest_ok_factor_and_the_first_failure():
    import pandas as pd

    dt = pd.DataFrame({"scene": ["a", "a"], "method": ["m", "x"], "dt_measured": [1.0, 2.0],
                       "ratio": [0.9, 1.4]})  # fmt: skip
    dl = pd.DataFrame({"scene": ["a"] * 3, "method": ["m"] * 3, "load_factor": [1, 10, 100],
                       "status": ["ok", "inverted", "ok"]})  # fmt: skip
    sv = survival({"dt": dt, "load": dl}).set_index("method")
    assert sv.loc["m", "max load factor"] == 100 and sv.loc["m", "first failing factor"] == 10
    assert np.isnan(sv.loc["x", "max load factor"]) and sv.loc["x", "largest step (s)"] == 2.0


def test_jacobi_run_to_rest_fails_where_its_substep_is_past_its_limit():
    """Two independent measurements agree: the step search (loads off, undamped) puts
    Jacobi's limit above a 1/1200 s substep (20 a 60 Hz frame) on the 10x1x1 bar and below
    it on the 20x2x2 bar (finer elements, higher omega_max); the run to rest at that substep
    under the bar's load (auto damping) then comes on the first and blows up on the second.
    The default 40 substeps (1/2400 s) are inside the limit on both."""
    from peers.xpbd import XPBD as Solver
    from peers.xpbd import XPBDSettings

    assert XPBD["xpbd-jacobi"].dt / XPBD["xpbd-jacobi"].substeps == pytest.approx(1 / 2400)
    h = 1 / 1200
    for (nx, ny), fits in (((10, 1), True), ((20, 2), False)):
        sc = bar(nx, ny, ("dt", "load"))
        limit = measure_xpbd_step(case_scene(sc.case("t", VERSION), 0.0), "xpbd-jacobi",
                                  steps=400, bisections=3)["dt_measured"]  # fmt: skip
        assert (h <= limit) == fits and 1 / 2400 <= limit
        settings = XPBDSettings(substeps=20, iteration="jacobi", max_frames=3_000)
        try:
            rests = Solver(case_scene(sc.case("t", VERSION), 1.0), settings).solve().converged
        except SolverError:  # positions no longer finite
            rests = False
        assert rests == fits


def test_a_case_the_budget_stops_is_a_row_not_a_lost_study():
    """A failure-map cell or a critical-step case whose solve meets the cap (the study's
    budget ran out: it runs with no time) is recorded as stopped, never raised."""
    from springfem.mechanics.limits import solve_limits
    from studies.study_stability.cases import failure_map_case

    sc = bar(10, 1, ("dt", "map"))
    cell = sc.case("t", VERSION, kind="map", method="P1-NH", factor=1.0, dt_factor=0.5,
                   steps=200)  # fmt: skip
    step = sc.case("t", VERSION, kind="dt", method="P1-NH", steps=200, bisections=3)
    with solve_limits(max_time=1e-9):
        got = failure_map_case(cell)
        dt = critical_step_case(step)
    assert got["status"] == "stopped" and "stopped" in got["message"], got
    assert np.isnan(dt["ratio"]) and "stopped" in dt["failure"], dt
    assert failure_map_case(cell)["status"] == "ok"  # uncapped, the same cell runs
