"""The frame-rate verdict's machinery: errors against a reference motion, the settings that
fit a frame, the sentence."""

import json

import numpy as np
import pytest

from springfem.frames import ExplicitFrames, LoadHistory
from springfem.scene import scene_from_dict
from studies import models
from studies.realtime import Motion, frame_run, trajectory_error
from studies.verdict_frames import frame_verdict

T_END = 0.12


def beam(time=None, gravity=False):
    load = {"type": "traction", "region": "x_max", "value": [0, 0, -400.0]}
    if time:
        load["time"] = time
    loads = [load] + ([{"type": "gravity", "value": [0, 0, -9.81]}] if gravity else [])
    return scene_from_dict({
        "name": "beam",
        "mesh": {"generator": "box", "size": [0.1, 0.02, 0.02], "divisions": [5, 1, 1]},
        "material": {"law": "neo-hookean", "E": 1e5, "nu": 0.3, "density": 1000.0},
        "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
        "load": loads, "dynamics": {"t_end": T_END}})  # fmt: skip


def fine_reference(scene, t_end, frame_dt, scale):
    """Explicit P1-NH at a tenth of its critical step: the converged motion of that model."""
    system = models.get("P1-NH").system(scene)
    stepper = ExplicitFrames(system, frame_dt, safety=0.05)
    r = frame_run(stepper, scene, t_end, scale)
    return r.motion, "explicit P1-NH at 0.05 dt_crit"


@pytest.fixture(scope="module")
def scene():
    return beam(time={"ramp": [0, 0.03], "release": 0.08})


def test_the_same_model_converges_to_its_fine_run(scene):
    ref, _ = fine_reference(scene, T_END, 1 / 200, LoadHistory(scene))
    system = models.get("P1-NH").system(scene)
    errs = []
    for safety in (0.8, 0.2):
        r = frame_run(ExplicitFrames(system, 1 / 200, safety=safety), scene, T_END,
                      LoadHistory(scene))  # fmt: skip
        errs.append(trajectory_error(r.motion, ref))
    assert errs[0]["probe"] < 0.01
    # second order in the substep, across the ramp's kink and the release's jump: a step
    # four times shorter, an error about sixteen times smaller (first order would give 4)
    assert errs[1]["probe"] < errs[0]["probe"] / 8
    assert errs[1]["field"] < errs[0]["field"]


def test_a_load_history_of_two_time_functions_equals_one_when_they_agree():
    """Gravity always on and a traction with a constant table: the split history must step
    exactly as the single load factor 1."""
    split = beam(time={"table": [[0, 1], [1, 1]]}, gravity=True)
    single = beam(gravity=True)
    h_split, h_single = LoadHistory(split), LoadHistory(single)
    assert not h_split.single and h_single.single
    system = models.get("P1-NH").system(single)
    runs = [frame_run(ExplicitFrames(system, 1 / 200), sc, 0.05, h)
            for sc, h in ((split, h_split), (single, h_single))]  # fmt: skip
    assert np.allclose(runs[0].motion.probes, runs[1].motion.probes, rtol=1e-10, atol=1e-14)


def test_verdict_names_the_most_accurate_model_that_fits(scene):
    v = frame_verdict(scene, 200.0, names=["P1-NH", "P1"], budget=300, log=lambda s: None,
                      reference=fine_reference)  # fmt: skip
    t = v.table
    assert set(t.index) == {"P1-NH", "P1"}
    # linear P1 is off the finite-strain reference; P1-NH is the reference's own model
    assert t.loc["P1-NH", "probe error"] < t.loc["P1", "probe error"]
    if t.loc["P1-NH", "fits"]:
        assert v.pick == "P1-NH" and v.sentence.startswith("At 200 Hz")
    data = json.loads(v.to_json())
    assert set(data["models"]) == {"P1-NH", "P1"} and data["frame_rate"] == 200.0


def test_no_model_fits_a_frame_of_ten_microseconds(scene):
    def still(scene, t_end, frame_dt, scale):  # never compared: nothing fits
        n = scene.mesh.n_points
        return Motion(np.array([0.0, t_end]), np.zeros((2, 1, 3)), np.zeros((2, n, 3))), "-"

    v = frame_verdict(scene, 1e5, names=["P1-NH"], budget=60, log=lambda s: None,
                      reference=still)  # fmt: skip
    assert v.pick is None and not v.table.loc["P1-NH", "fits"]
    assert v.sentence.startswith("No model runs at 100000 Hz") and "faster" in v.sentence


def test_a_reference_past_the_budget_is_not_started(scene, monkeypatch):
    from studies import realtime

    monkeypatch.setattr(realtime, "reference_plan", lambda *a: ("reference: huge", 1e6))
    v = frame_verdict(scene, 200.0, names=["P1-NH"], budget=60, log=lambda s: None)
    assert v.sentence.startswith("No dynamic reference within the budget")
    assert "P1-NH" in v.sentence or "none" in v.sentence
    assert np.isnan(v.table.loc["P1-NH", "probe error"])
