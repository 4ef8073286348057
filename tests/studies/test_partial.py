"""Partial results: a solve that stopped part way along its load, reported at that load.

References: a rigid translation (probe displacement = the translation, volume unchanged, to
round-off), and, for the spring ventricle, the equilibrium residual of the returned state
at the load factor reported, from the model's own forces (independent of the bookkeeping).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from springfem.errors import SolverError
from springfem.scene import scene_from_dict
from studies.compare import Comparison, comparison_table
from studies.partial import partial_solution
from studies.study_tissue import ventricle_frame

BOX = {
    "mesh": {"generator": "box", "size": [1.0, 1.0, 1.0], "divisions": [2, 2, 2]},
    "material": {"law": "linear", "E": 1.0e4, "nu": 0.3},
    "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
    "probe": [{"name": "tip", "point": [1.0, 0.5, 0.5]}],
}
SHIFT = np.array([0.1, -0.2, 0.3])


@pytest.fixture(scope="module")
def box():
    return scene_from_dict(BOX)


def _stopped(scene, load_factor=0.5):
    u = np.broadcast_to(SHIFT, (scene.mesh.n_points, 3)).copy()
    return SolverError("stopped", state=u, load_factor=load_factor)


def test_partial_solution_of_a_rigid_translation(box):
    """Probe = the translation exactly; volume change zero to round-off (1e-12)."""
    sol = partial_solution(box, "spring", _stopped(box), wall_time=2.0)
    r = sol.result
    assert r.status == "partial" and not r.converged and r.info["load_factor"] == 0.5
    assert np.allclose(r.probes["tip"], SHIFT, rtol=0, atol=1e-15)
    assert abs(r.volume["relative_change"]) < 1e-12
    assert r.wall_time == 2.0 and "cavity" not in r.info  # not a ventricle


def test_no_partial_without_a_state_or_a_load_factor(box):
    assert partial_solution(box, "spring", SolverError("singular")) is None
    u = np.zeros((box.mesh.n_points, 3))
    assert partial_solution(box, "fem", SolverError("diverged", state=u)) is None
    bad = SolverError("blew up", state=np.full_like(u, np.nan), load_factor=0.2)
    assert partial_solution(box, "spring", bad) is None


def test_comparison_table_reports_the_partial_row_at_its_load(box):
    """The partial row has its load factor and probes, and no error against the reference
    (which is at the full load); the finished model's load factor is 1."""
    ref = partial_solution(box, "fem", _stopped(box, 1.0))  # stands in for a full solve
    ref.result.status, ref.result.element = "converged", "P2"
    part = partial_solution(box, "spring", _stopped(box, 0.25))
    cmp = Comparison(box, pd.DataFrame(), {"P2": ref}, "P2", partial={"spring": part})
    table = comparison_table(cmp, ["spring", "P2"]).set_index("model")
    assert table.loc["spring", "status"] == "partial"
    assert table.loc["spring", "load factor"] == 0.25 and table.loc["P2", "load factor"] == 1.0
    column = next(c for c in table.columns if c.startswith("tip u"))
    assert table.loc["spring", column] == pytest.approx(SHIFT[np.argmax(np.abs(SHIFT))])
    assert math.isnan(table.loc["spring", "tip rel err"])


def test_ventricle_frame_gives_no_error_for_a_partial_row():
    """A partial spring row keeps its apex values and load factor; its rel_error is NaN
    (another load than the FEM's), the finished spring row's is the relative difference of
    the apex's downward motion from the FEM's (the report's convention: negative, it moves
    less)."""
    cases = [{"model": "fem"}, {"model": "spring", "variant": "exact"},
             {"model": "spring", "variant": "seed"}]  # fmt: skip
    cav = {"initial": 1.0, "final": 2.0}
    res = [
        {"endo_apex_z": -27.0, "epi_apex_z": -28.0, "cavity": cav, "wall_time": 1.0,
         "load_factor": 1.0, "error": ""},
        {"endo_apex_z": -18.0, "epi_apex_z": -21.0, "cavity": cav, "wall_time": 1.0,
         "load_factor": 0.35, "error": "stopped"},
        {"endo_apex_z": -22.0, "epi_apex_z": -24.0, "cavity": cav, "wall_time": 1.0,
         "load_factor": 1.0, "error": ""},
    ]  # fmt: skip
    df = ventricle_frame(cases, res)
    assert df.load_factor.tolist() == [1.0, 0.35, 1.0]
    assert math.isnan(df.rel_error.iloc[1])
    assert df.rel_error.iloc[2] == pytest.approx((5.0 - 10.0) / 10.0)  # motions 5 and 10 mm


@pytest.mark.slow
def test_spring_ventricle_stop_is_an_equilibrium_at_the_load_reached():
    """~8 s: the exact spring element with the spec's quadratic springs (the scene's
    stiffening switched off) on the coarse problem-3 ventricle stops part way; the
    error names the load, and the state is an equilibrium there (residual within the
    static tolerance of the full-load force, x 1.0001 for rounding)."""
    from springmodel.model import SpringModel, solve_spring
    from studies.overrides import load_scene_with

    quadratic = ["spring.axial=linear", "spring.torsion=energy", "spring.stiffening=off"]
    scene = load_scene_with(
        "studies/scenes/land-ventricle-fibres.toml", ["mesh.size=6", *quadratic]
    )
    with pytest.raises(SolverError) as e:
        solve_spring(scene)
    lf = e.value.load_factor
    assert lf is not None and 0.0 < lf < 1.0
    assert str(e.value).startswith("spring static solve did not converge: stopped at load")
    model = SpringModel(scene)
    x = model.x0 + np.asarray(e.value.state)
    f = model.forces(x, None, lf).reshape(-1)
    free = np.setdiff1d(np.arange(f.size), model.fixed_dofs)
    f_ref = np.linalg.norm(model.forces(model.x0, None, 1.0).reshape(-1)[free])
    assert np.linalg.norm(f[free]) <= model.options.tol * f_ref * 1.0001
    sol = partial_solution(scene, "spring", e.value)
    assert sol.result.info["cavity"]["final"] > sol.result.info["cavity"]["initial"]
