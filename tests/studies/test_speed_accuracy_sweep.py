"""The plug-ins' sweeps in the speed-accuracy study: XPBD's substeps x iterations as points
of their own, checked against P1 neo-Hookean Newton on the same stocky block (computed here
from the points' fields, not by the study's tables), and one static point for a model
without a sweep."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from peers.plugin import XPBDModel
from springfem.errors import InputError
from studies import models
from studies.cache import case_key
from studies.scenes import StudyScene
from studies.study_speed_accuracy import SAME, measure, points_frame, report_findings
from studies.study_speed_accuracy import cases as sa

#: A stocky neo-Hookean block sagging under gravity: XPBD comes to rest in tens of frames.
BLOCK = StudyScene(
    "block",
    {
        "mesh": {"generator": "box", "size": [0.02, 0.02, 0.02], "divisions": [3, 3, 3]},
        "material": {"law": "neo-hookean", "E": 1.0e4, "nu": 0.3, "density": 1000.0},
        "boundary": [{"region": "z_min", "fix": ["x", "y", "z"]}],
        "load": [{"type": "gravity", "value": [0.0, 3.0, -3.0]}],
        "probe": [{"name": "top", "point": [0.01, 0.01, 0.02]}],
    },
)


def xpbd_points(q: sa.Settings, scene: StudyScene = BLOCK) -> list[dict]:
    return [c for c in sa.points(scene, scene.build(), [1], q) if c["model"] == "xpbd"]


def test_each_sweep_setting_is_its_own_case_and_method():
    """Full: XPBD's six substeps x iterations settings, six cases with six cache keys and
    method names; quick: the first two; the settings reach the plug-in (its label)."""
    full = xpbd_points(sa.Settings.full())
    own = [c["setting"]["model"] for c in full]
    assert own == [dict(s) for s in XPBDModel.SWEEP] and len(own) == 6
    assert len({case_key(c) for c in full}) == 6
    names = [sa.method_name(c["model"], c["solution"], c["setting"]) for c in full]
    assert names[:2] == ["xpbd 40x2 static", "xpbd 80x2 static"] and len(set(names)) == 6
    assert [c["setting"] for c in xpbd_points(sa.Settings.quick())] == [
        {"model": {"substeps": 40, "iterations": 2}},
        {"model": {"substeps": 80, "iterations": 2}},
    ]
    m = sa.with_settings(models.get("xpbd"), {"substeps": 10, "iterations": 4})
    assert m.settings["substeps"] == 10 and "10 substeps x 4" in m.label
    assert models.get("xpbd").settings["substeps"] == 40  # the registry's is unchanged


def test_a_model_without_a_sweep_has_one_static_point_per_level():
    """The mass-spring network has no ``sweep``: one static point (no model settings) on
    each level, and asking it for settings of its own is an input error."""
    pts = [c for c in sa.points(BLOCK, BLOCK.build(), [1, 2], sa.Settings.full())
           if c["model"] == "mass-spring" and c["solution"] == "static"]  # fmt: skip
    assert [(c["factor"], c["setting"]) for c in pts] == [(1, {}), (2, {})]
    assert not hasattr(models.get("mass-spring"), "sweep")
    with pytest.raises(InputError, match="no settings of its own"):
        sa.with_settings(models.get("mass-spring"), {"damping": 1.0})


@pytest.fixture(scope="module")
def block_sweep():
    """The substep series (10, 20, 40, 80 at 2 iterations) and P1-NH static on the block."""
    q = sa.Settings(sweep=None)
    cases = [c for c in xpbd_points(q) if c["setting"]["model"]["iterations"] == 2]
    cases.append(sa.point_case(BLOCK, "P1-NH", "static", 1, {}))
    return cases, [sa.point_work(c) for c in cases]


def test_xpbd_error_against_p1_neo_hookean_falls_with_the_substeps(block_sweep):
    """XPBD's rest state approaches the P1 neo-Hookean Newton answer on the same mesh as the
    substeps grow, at about the h² of docs/peers.rst#xpbd-bias (fitted rate above 1.5), and
    the table's same-mesh column is that error."""
    cases, results = block_sweep
    assert all(r["status"] == "ok" for r in results), [r.get("message") for r in results]
    u_nh = np.asarray(results[-1]["u"])
    err = {
        c["setting"]["model"]["substeps"]: np.linalg.norm(np.asarray(r["u"]) - u_nh)
        / np.linalg.norm(u_nh)
        for c, r in zip(cases[:-1], results[:-1], strict=True)
    }
    n = sorted(err)
    assert n == [10, 20, 40, 80]
    assert all(err[a] > err[b] for a, b in zip(n, n[1:], strict=False)), err
    rate = -np.polyfit(np.log(n), np.log([err[k] for k in n]), 1)[0]
    assert rate > 1.5, (rate, err)
    df = points_frame(BLOCK, cases, results, results[-1], measure(BLOCK, results[-1]))
    got = df.set_index("method")[SAME]
    for k in n:
        assert got[f"xpbd {k}x2 static"] == pytest.approx(err[k], rel=1e-9)
    # the findings report the same rate, as a headline key
    _, headline, _ = report_findings(df, None, measure(BLOCK, results[-1]), "3x3x3", "block",
                                     cases=cases)  # fmt: skip
    assert headline["rate_xpbd_substeps_3x3x3"] == pytest.approx(rate, abs=1e-3)


def test_figure_shows_every_model_with_its_front(block_sweep, tmp_path):
    """One legend entry for XPBD's sweep beside P1-NH's, each model's own front drawn."""
    from studies.cache import CaseCache
    from studies.registry import StudyContext
    from studies.study_speed_accuracy.figures import pareto_figure

    cases, results = block_sweep
    df = points_frame(BLOCK, cases, results, results[-1], measure(BLOCK, results[-1]))
    df = pd.concat([df, df.assign(method="P1 static", seconds=df["seconds"] / 2)])
    ctx = StudyContext("speed_accuracy", tmp_path, True, CaseCache(tmp_path, "s"), False)
    fig = pareto_figure(ctx, df, SAME, "P1-NH", "front.", "block")
    assert fig.path.is_file() and "each model's own front" in fig.caption


def test_sweep_entries_after_the_first_stop_at_sweep_levels():
    """Full settings on levels 1, 2, 4: the whole sweep on 1 and 2, the first (default)
    setting alone on 4."""
    pts = [c for c in sa.points(BLOCK, BLOCK.build(), [1, 2, 4], sa.Settings.full())
           if c["model"] == "xpbd"]  # fmt: skip
    by_level = {k: [c["setting"]["model"] for c in pts if c["factor"] == k] for k in (1, 2, 4)}
    assert len(by_level[1]) == len(by_level[2]) == 6
    assert by_level[4] == [{"substeps": 40, "iterations": 2}]


def test_xpbd_stops_at_the_time_cap():
    """A run that never rests (``rest_tol = 0``) stops at the cap of ``solve_limits`` (a
    study's budget, ``--max-time``) instead of running its frames out."""
    import time

    from springfem.mechanics.limits import SolveStopped, solve_limits

    model = XPBDModel(rest_tol=0.0, max_frames=20_000)  # uncapped: ~25 s, then a SolverError
    scene = BLOCK.build()
    t0 = time.monotonic()
    with solve_limits(max_time=0.5), pytest.raises(SolveStopped, match="frames to rest"):
        model.solve(scene)
    assert time.monotonic() - t0 < 10.0
