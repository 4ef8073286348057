"""Loads as functions of time: parsing, evaluation, and one clear line for bad input.

The factors are checked against values worked out by hand from the definitions in
:mod:`springfem.scene.load_time` (piecewise linear, right-continuous at a jump).
"""

import numpy as np
import pytest

from springfem.errors import SceneError
from springfem.scene import DynamicsOptions, RayleighDamping, scene_from_dict
from springfem.scene.load_time import parse_time

BOX = {"generator": "box", "size": [1.0, 1.0, 1.0], "divisions": [1, 1, 1]}
MAT = {"law": "linear", "E": 1.0e3, "nu": 0.3}


def scene_with(time=None, **dynamics):
    load = {"type": "traction", "region": "x_max", "value": [1.0, 0.0, 0.0]}
    if time is not None:
        load["time"] = time
    fix = [{"region": "x_min", "fix": ["x", "y", "z"]}]
    data = {"mesh": BOX, "material": MAT, "boundary": fix, "load": [load]}
    if dynamics:
        data["dynamics"] = dynamics
    return scene_from_dict(data, path="s.toml")


def test_ramp_hold_release_and_their_product():
    ramp = parse_time({"ramp": [0.1, 0.3]})
    assert [ramp(t) for t in (0.0, 0.1, 0.2, 0.3, 5.0)] == pytest.approx([0, 0, 0.5, 1, 1])
    hold = parse_time({"hold": [0.1, 0.2]})
    assert [hold(t) for t in (0.05, 0.1, 0.15, 0.2)] == [0.0, 1.0, 1.0, 0.0]
    assert hold.left(0.1) == 0.0 and hold.left(0.2) == 1.0
    pull = parse_time({"ramp": [0.0, 0.05], "release": 0.2})
    t = np.array([0.0, 0.025, 0.05, 0.1, 0.1999, 0.2, 0.3])
    assert [pull(x) for x in t] == pytest.approx([0, 0.5, 1, 1, 1, 0, 0])
    assert pull.jumps() == [0.2] and pull.breakpoints() == [0.0, 0.05, 0.2]


def test_table_interpolates_linearly_and_holds_its_ends():
    g = parse_time({"table": [[0.0, 0.0], [1.0, 2.0], [1.0, -1.0], [3.0, 0.0]]})
    assert g(-1.0) == 0.0 and g(0.25) == 0.5 and g(4.0) == 0.0
    assert g.left(1.0) == 2.0 and g(1.0) == -1.0 and g(2.0) == pytest.approx(-0.5)
    assert g.jumps() == [1.0]


def test_a_load_carries_its_time_function_and_static_solves_ignore_it():
    s = scene_with({"ramp": [0.0, 1.0]})
    assert s.loads[0].factor(0.25) == 0.25 and scene_with().loads[0].factor(7.0) == 1.0
    from reference_fem import solve

    with_time = solve(s, order=1).u
    without = solve(scene_with(), order=1).u
    assert np.array_equal(with_time, without)  # the full load, as before


@pytest.mark.parametrize(
    "time, message",
    [
        ("ramp", "s.toml: load[0].time must be a table"),
        ({}, "s.toml: load[0].time.ramp: a time table needs ramp, hold, release or table"),
        ({"ramp": [0.3, 0.1]}, "s.toml: load[0].time.ramp: t1 is before t0: [0.3, 0.1]"),
        ({"hold": 0.2}, "s.toml: load[0].time.hold: must be [t0, t1] (seconds), got 0.2"),
        ({"release": "x"}, "s.toml: load[0].time.release: must be a number, got str"),
        ({"relase": 0.2}, "s.toml: load[0].time.relase: unknown key; did you mean 'release'?"),
        ({"table": [[0, 1], [0.5]]}, "s.toml: load[0].time.table: must be a list of [t, factor]"),
        ({"table": [[1, 1], [0.5, 0]]}, "s.toml: load[0].time.table: times must not decrease"),
        ({"table": [[0, 0]], "ramp": [0, 1]}, "s.toml: load[0].time.table: stands alone"),
    ],
)
def test_bad_time_tables_get_one_line_naming_the_load_and_key(time, message):
    with pytest.raises(SceneError) as exc:
        scene_with(time)
    text = str(exc.value)
    assert text.startswith(message) and "\n" not in text


def test_dynamics_section_damping_forms():
    o = DynamicsOptions.of(scene_with(None, damping={"mass": 0.5, "stiffness": 1e-3}))
    assert o.damping == RayleighDamping(0.5, 1e-3) and o.t_end == 1.0 and o.dt == 1.0 / 200
    o = DynamicsOptions.of(scene_with(None, damping={"ratio": 0.1, "frequencies": [2.0]}))
    assert o.damping.ratio_at(2.0) == pytest.approx(0.1)  # half from each term at f
    assert o.damping.mass / (4 * np.pi * 2.0) == pytest.approx(0.05)
    assert DynamicsOptions.of(scene_with()).damping.none


@pytest.mark.parametrize(
    "dynamics, message",
    [
        ({"damping": {"mass": 1.0, "frequencies": [1.0]}},
         "s.toml: dynamics.damping.frequencies: give mass and stiffness, or ratio and"),
        ({"damping": {"ratio": 0.1, "frequencies": [1.0, 2.0, 3.0]}},
         "s.toml: dynamics.damping.frequencies: must be [f] or [f1, f2] (Hz)"),
        ({"damping": {"mass": -1.0}}, "s.toml: dynamics.damping.mass: must not be negative"),
        ({"damping": {"ratio": 0.1}}, "s.toml: dynamics.damping.frequencies: missing"),
        ({"rho_inf": 1.5}, "s.toml: dynamics.rho_inf: must lie in [0, 1], got 1.5"),
        ({"t_end": 0.1, "dt": 0.2}, "s.toml: dynamics.dt: must not exceed t_end (0.1), got 0.2"),
        ({"integrator": "euler"}, "s.toml: dynamics.integrator: 'euler' is not one of"),
    ],
)  # fmt: skip
def test_bad_dynamics_get_one_line(dynamics, message):
    with pytest.raises(SceneError) as exc:
        scene_with(None, **dynamics)
    assert str(exc.value).startswith(message) and "\n" not in str(exc.value)
