"""Dynamic solves from the command line: time series, "end of run", FEM dynamics.

Independent references: before any elastic wave from the clamped ends reaches the centre
of the sag block, its centre falls freely, ``u_z = -g t^2 / 2`` (velocity Verlet is exact
for constant acceleration); the shear wave speed ``sqrt(mu / rho)`` ~ 1.3 m/s needs ~30 ms
for the 40 mm to the centre, the dilatational one (~4.2 m/s) ~9.5 ms, and the run ends at
~8.3 ms. A backward-Euler run with large steps relaxes to the static solution, which
the FEM's own Newton solve (another code path) gives.
"""

import json
from pathlib import Path

import numpy as np
import pytest

from studies.cli import main

G = 9.81
SAG = ["solve", "sag"]


def _result(out: Path) -> dict:
    return json.loads((out / "result.json").read_text())


def test_sag_explicit_series_opens_in_pyvista_and_falls_freely(tmp_path, capsys):
    pv = pytest.importorskip("pyvista")
    out = tmp_path / "sag"
    interval = 0.002
    argv = [*SAG, "--out", str(out), "--set", "spring.solver=explicit",
            "--set", "spring.integrator=verlet", "--set", "spring.t_end=0.008",
            "--set", f"output.interval={interval}", "--set", "output.animation=gif"]  # fmt: skip
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "end of run at t = " in printed and "converged" not in printed
    res = _result(out)
    assert res["converged"] is False and res["info"]["at_rest"] is False  # undamped, moving
    assert res["status"].startswith("end of run") and "still moving" in res["status"]
    t_end = res["info"]["end_time"]
    dt = res["info"]["dt"]
    assert t_end >= 0.008 and t_end - 0.008 < dt
    # free fall of the centre (Verlet is exact for constant acceleration; 1e-3 allows for
    # the waves from the clamps, which have not reached the centre at ~8 ms)
    uz = res["probes"]["center"][2]
    assert uz == pytest.approx(-0.5 * G * t_end**2, rel=1e-3)

    reader = pv.get_reader(str(out / "series" / "frame.pvd"))
    times = np.asarray(reader.time_values)
    # one frame per interval: the first step at or past each multiple of it; the last
    # step (the first past 8 ms) is the frame of 8 ms and the end state at once
    expected = [k * interval for k in range(int(np.floor(t_end / interval + 1e-9)) + 1)]
    assert len(times) == len(expected) == 5
    assert times[0] == 0.0 and times[-1] == pytest.approx(t_end, abs=1e-12)
    assert np.all(times[1:] - np.asarray(expected[1 : len(times)]) < dt + 1e-12)
    reader.set_active_time_value(times[-1])
    last = reader.read()[0]
    final = pv.read(str(out / "result.vtu"))
    np.testing.assert_allclose(last.point_data["displacement"], final.point_data["displacement"],
                               rtol=0, atol=1e-15)  # fmt: skip  # the same state, written twice
    reader.set_active_time_value(0.0)
    assert np.abs(reader.read()[0].point_data["displacement"]).max() == 0.0  # starts at rest

    import imageio.v2 as imageio

    gif = imageio.mimread(out / "series" / "animation.gif")
    assert len(gif) == len(times)


def test_dynamic_run_without_interval_says_end_of_run(tmp_path, capsys):
    out = tmp_path / "sag"
    argv = [*SAG, "--out", str(out), "--set", "spring.solver=explicit",
            "--set", "spring.steps=5", "--set", "mesh.divisions=[8, 4, 2]"]  # fmt: skip
    assert main(argv) == 0
    res = _result(out)
    assert res["converged"] is False and res["status"].startswith("end of run")
    assert not (out / "series").exists()


def test_fem_explicit_from_cli_falls_freely(tmp_path):
    out = tmp_path / "fem"
    argv = [*SAG, "--model", "fem", "--out", str(out), "--set", "fem.solver=explicit",
            "--set", "fem.t_end=0.008", "--set", "output.interval=0.004"]  # fmt: skip
    assert main(argv) == 0
    res = _result(out)
    t = res["info"]["end_time"]
    # symplectic Euler under constant acceleration: u_n = -g dt^2 n (n + 1) / 2 exactly
    n, dt = res["info"]["steps"], res["info"]["dt"]
    assert res["probes"]["center"][2] == pytest.approx(-0.5 * G * dt**2 * n * (n + 1), rel=1e-3)
    assert t == pytest.approx(n * dt) and res["status"].startswith("end of run")
    assert len(list((out / "series").glob("frame_*.vtu"))) == 3  # t = 0, 4 ms, ~8 ms


def test_fem_implicit_relaxes_to_the_static_solution(tmp_path):
    coarse = ["--set", "mesh.divisions=[8, 4, 2]"]
    static = tmp_path / "static"
    assert main([*SAG, "--model", "fem", "--out", str(static), *coarse]) == 0
    out = tmp_path / "implicit"
    argv = [*SAG, "--model", "fem", "--out", str(out), *coarse, "--set", "fem.solver=implicit",
            "--set", "fem.t_end=2.0", "--set", "fem.dt=0.1"]  # fmt: skip
    assert main(argv) == 0
    res, ref = _result(out), _result(static)
    assert res["info"]["at_rest"] is True
    # backward Euler with steps ~10x the sag's period damps it out: what is left after 20
    # steps is far below 1e-4 of the displacement (Newton tolerances are 1e-8 .. 1e-10)
    np.testing.assert_allclose(res["probes"]["center"], ref["probes"]["center"], rtol=1e-4,
                               atol=1e-4 * abs(ref["probes"]["center"][2]))  # fmt: skip


def test_fem_dynamic_needs_an_end_time(tmp_path, capsys):
    assert main([*SAG, "--model", "fem", "--set", "fem.solver=explicit"]) == 2
    assert "needs fem.t_end or fem.steps" in capsys.readouterr().err


def test_output_section_is_validated(capsys):
    assert main([*SAG, "--set", "output.animation=avi"]) == 2
    assert "output.animation" in capsys.readouterr().err


def test_fem_dynamics_are_p1_only(capsys):
    argv = [*SAG, "--model", "fem", "--order", "2", "--set", "fem.solver=explicit",
            "--set", "fem.steps=1"]  # fmt: skip
    assert main(argv) == 2
    assert "P1 only" in capsys.readouterr().err


def _mp4_argv(out):
    return [*SAG, "--out", str(out), "--set", "spring.solver=explicit",
            "--set", "spring.t_end=0.004", "--set", "output.interval=0.002",
            "--set", "output.animation=mp4", "--set", "mesh.divisions=[8, 4, 2]"]  # fmt: skip


def test_mp4_animation_has_one_frame_per_series_frame(tmp_path):
    import imageio_ffmpeg
    import pyvista as pv

    from studies.animation import WINDOW

    out = tmp_path / "sag"
    assert main(_mp4_argv(out)) == 0
    frames = pv.get_reader(str(out / "series" / "frame.pvd")).time_values
    video = out / "series" / "animation.mp4"
    # decoded by ffmpeg (not the writer's code path): the frame count and the frame size
    # (the pyvista window) show the video holds the series' frames
    reader = imageio_ffmpeg.read_frames(str(video))
    meta = next(reader)
    w, h = meta["size"]
    images = [np.frombuffer(b, np.uint8).reshape(h, w, 3) for b in reader]
    assert (w, h) == WINDOW
    assert len(images) == len(frames) >= 3
    # the first and last frames differ: the body moves (free fall), the video is no still
    assert np.abs(images[-1].astype(float) - images[0].astype(float)).max() > 0


def test_mp4_without_a_video_backend_warns_and_keeps_the_series(tmp_path, capsys, monkeypatch):
    import importlib.util

    real = importlib.util.find_spec
    hidden = {"imageio_ffmpeg", "av"}  # as on a machine without a video backend

    def find_spec(name, *args):
        return None if name in hidden else real(name, *args)

    monkeypatch.setattr(importlib.util, "find_spec", find_spec)
    out = tmp_path / "sag"
    assert main(_mp4_argv(out)) == 0
    err = [x for x in capsys.readouterr().err.splitlines() if x.startswith("warning:")]
    err = [x for x in err if "locks" not in x]  # the sag's nu = 0.45 warns of locking too
    assert len(err) == 1 and "mp4 needs the imageio-ffmpeg or av package" in err[0]
    assert (out / "series" / "frame.pvd").is_file() and (out / "result.json").is_file()
    assert not (out / "series" / "animation.mp4").exists()


def test_animation_frames_are_stamped_with_the_series_times(tmp_path):
    """The times come from the series' .pvd, as pyvista's own reader sees them."""
    import pyvista as pv

    from studies.animation import frame_times

    out = tmp_path / "sag"
    argv = [a if a != "output.animation=mp4" else "output.animation=gif" for a in _mp4_argv(out)]
    assert main(argv) == 0
    series = out / "series"
    frames = sorted(series.glob("frame_*.vtu"))
    expected = pv.get_reader(str(series / "frame.pvd")).time_values
    assert frame_times(frames) == pytest.approx(expected, rel=1e-15)
    assert (series / "animation.gif").stat().st_size > 0
