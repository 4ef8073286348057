"""Time series: frames in a PVD that pyvista reads back, histories against closed forms."""

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from springfem.mechanics import explicit
from springfem.mesh import box_mesh
from springfem.scene import scene_from_dict
from springfem.series import SeriesWriter, pvd_text, reached_rest

pv = pytest.importorskip("pyvista")

MESH = box_mesh((0.02, 0.01, 0.01), (2, 1, 1))
N = MESH.n_points


def read_series(pvd):
    """(times, displacement arrays) of every dataset of a PVD, read with pyvista."""
    reader = pv.get_reader(str(pvd))
    times, fields = [], []
    for k, t in enumerate(reader.time_values):
        reader.set_active_time_point(k)
        block = reader.read()
        grid = block[0] if isinstance(block, pv.MultiBlock) else block
        times.append(t)
        fields.append(np.asarray(grid.point_data["displacement"]))
    return np.array(times), fields


def test_frames_and_histories_of_an_analytic_motion(tmp_path):
    """Rigid oscillation z = a sin(wt) plus a uniform stretch s(t) = e t along x."""
    a, w, e, dt = 1e-3, 2 * np.pi, 0.05, 0.01
    masses = np.full(N, 0.25)
    probe = lambda u: {"p": u[0].tolist()}  # noqa: E731 - node 0 sits at the origin
    writer = SeriesWriter(tmp_path, MESH, interval=0.1, history_interval=0.0, masses=masses,
                          probes=probe)  # fmt: skip
    X = MESH.points
    for k in range(1, 101):
        t = k * dt
        x = X.copy()
        x[:, 0] *= 1 + e * t
        x[:, 2] += a * np.sin(w * t)
        v = np.zeros_like(X)
        v[:, 0] = X[:, 0] * e
        v[:, 2] = a * w * np.cos(w * t)
        writer(k, t, x, v)
    s = writer.close()
    times, fields = read_series(s.pvd)
    # a frame every 0.1 s from 0 to 1 s; times written with 17 digits
    np.testing.assert_allclose(times, np.arange(11) * 0.1, atol=1e-12)
    for t, u in zip(times, fields, strict=True):
        exact = np.zeros_like(X)
        exact[:, 0] = X[:, 0] * e * t
        exact[:, 2] = a * np.sin(w * t)
        np.testing.assert_allclose(u, exact, atol=1e-15)  # float64 VTU: exact round trip
    h = s.history
    assert len(h) == 101  # every step (history_interval = 0) plus the initial state
    # the volume of the stretched box: (1 + e t) - 1, the translation does not change it
    np.testing.assert_allclose(h["volume_change"], e * h["t"], rtol=1e-12, atol=1e-15)
    ke = 0.5 * (masses.sum() * (a * w * np.cos(w * h["t"])) ** 2 + masses @ (X[:, 0] * e) ** 2)
    np.testing.assert_allclose(h["kinetic"], ke.where(h["t"] > 0, 0.0), rtol=1e-12)
    np.testing.assert_allclose(h["probe:p:uz"], a * np.sin(w * h["t"]), atol=1e-15)
    assert s.at_rest is False and "end of run at t = 1 s after 100 steps" in s.status_line()
    assert {p.name for p in s.files} == {"frame.pvd", "history.csv", "history.png"}


def test_the_pvd_is_valid_after_every_frame(tmp_path):
    """A run killed mid-way leaves a collection of the frames written so far."""
    writer = SeriesWriter(tmp_path, MESH, interval=0.1)
    for k in range(1, 26):
        writer(k, 0.01 * k, MESH.points, np.zeros((N, 3)))
        root = ET.parse(tmp_path / "frame.pvd").getroot()
        files = [d.get("file") for d in root.iter("DataSet")]
        assert files == [p.name for p in writer.frames]
        assert all((tmp_path / f).is_file() for f in files)
    assert len(writer.frames) == 3  # t = 0, 0.1, 0.2 (not yet closed at 0.25)


def test_pvd_quotes_file_names():
    assert 'file="a&amp;b.vtu"' in pvd_text([(0.5, "a&b.vtu")])


@pytest.mark.parametrize("decay, expected", [(0.0, False), (0.2, False), (3.0, True)])
def test_rest_is_a_quiet_tail_not_a_zero_crossing(decay, expected):
    """Damped oscillator kinetic energy exp(-2 c t) cos^2: at t in [9, 10] the peak is
    exp(-2 c 9): 1 (c=0), 0.03 (c=0.2), 4e-24 (c=3) against the 1e-6 threshold."""
    t = np.linspace(0, 10, 2001)
    assert reached_rest(np.exp(-2 * decay * t) * np.cos(5 * t) ** 2) is expected


def _sag_model():
    import tomllib
    from pathlib import Path

    from springmodel.model import SpringModel

    root = Path(__file__).resolve().parents[2]
    data = tomllib.loads((root / "studies" / "scenes" / "sag.toml").read_text())
    data["mesh"]["divisions"] = [4, 2, 1]  # 48 tets
    scene = scene_from_dict(data)
    return scene, SpringModel(scene)


def test_explicit_spring_solve_of_sag_writes_a_series(tmp_path):
    """The core explicit solver drives the writer; pyvista reads the series back and its
    last frame is the solver's final state."""
    scene, model = _sag_model()
    writer = SeriesWriter(tmp_path, scene.mesh, interval=0.01, masses=model.masses,
                          potential=model.energy, probes=scene.probe_displacements)  # fmt: skip
    traj = explicit(model, t_end=0.05, callback=writer)
    s = writer.close()
    times, fields = read_series(s.pvd)
    assert times[0] == 0 and times[-1] == pytest.approx(s.end_time, rel=1e-15)
    # a frame at the first step at or after each multiple of the interval, the end included
    assert s.end_time == pytest.approx(traj.steps * traj.dt, rel=1e-12) and s.end_time >= 0.05
    k = np.arange(len(times))
    assert len(times) == 6
    assert np.all((times >= 0.01 * k - 1e-12) & (times < 0.01 * k + traj.dt))
    np.testing.assert_allclose(fields[-1], traj.x - model.x0, atol=1e-15)
    assert s.history["probe:center:uz"].min() < 0  # it sags (gravity along -z)
    assert s.at_rest is False  # undamped: still moving at the end
    assert "still moving" in s.status_line()


@pytest.mark.parametrize("integrator, order", [("symplectic-euler", 1), ("verlet", 2)])
def test_energy_history_has_the_integrators_order(tmp_path, integrator, order):
    """The total-energy wobble of the written history shrinks as dt^order: symplectic Euler's
    end-of-step velocity is half a step off the positions (first order), velocity Verlet's
    is synchronised (second order). Two step sizes; 0.2 allows for the pre-asymptotic part."""
    scene, model = _sag_model()
    dts, wobble = [], []
    for f in (1, 2):
        w = SeriesWriter(tmp_path / str(f), scene.mesh, interval=0.01, history_interval=0,
                         masses=model.masses, potential=model.energy)  # fmt: skip
        traj = explicit(model, dt_safety=0.5 / f, t_end=0.05, callback=w, integrator=integrator)
        h = w.close(plot=False).history
        dts.append(traj.dt)
        wobble.append(np.ptp(h["total"]) / np.ptp(h["potential"]))
    rate = np.polyfit(np.log(dts), np.log(wobble), 1)[0]
    assert rate == pytest.approx(order, abs=0.2)
