"""The frame-budget study on a tiny pull: its reference, its floor, its chart and table."""

import numpy as np
import pandas as pd
import pytest

from studies.cache import CaseCache
from studies.registry import StudyContext
from studies.study_frames import Settings, bundled_scenes, run


@pytest.fixture(scope="module")
def output(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("frames")
    s = Settings(scenes={"pull-release": {"mesh.divisions": [2, 2, 1], "dynamics.dt": 4e-3}},
                 rates=(100.0,), t_end=0.06, models=("P1-NH",), per_model=3)  # fmt: skip
    ctx = StudyContext("frame_budget", tmp / "out", quick=True, cache=CaseCache(tmp / "cache", "f"),
                       progress=False)  # fmt: skip
    return run(ctx, bundled_scenes(s), s)


def test_p1_converges_in_time_to_the_floor_of_its_mesh(output):
    df = pd.read_csv(output.tables[0].path.with_suffix(".csv"))
    errors = df[df["model"] == "P1-NH"]["probe error"].to_numpy()
    assert len(errors) == 3 and np.isfinite(errors).all()
    lo = output.headline["pull-release_100Hz_P1-NH_floor"]
    assert 0.01 < lo < 1.0  # P1 on two cells across is far from P2/P1: a real floor
    # every setting of P1-NH is within a few per mille of its time-converged run: on this
    # mesh the error against the P2 reference is the mesh's, not the time step's
    assert np.all(np.abs(errors - lo) < 5e-3 * max(lo, 1e-3) + 2e-3)


def test_chart_and_headline(output):
    assert output.figures and output.figures[0].path.stat().st_size > 10_000
    keys = [k for k in output.headline if k.startswith("pull-release_100Hz_P1-NH")]
    names = ("error_min", "floor", "ms_min")
    assert sorted(keys) == [f"pull-release_100Hz_P1-NH_{k}" for k in names]
