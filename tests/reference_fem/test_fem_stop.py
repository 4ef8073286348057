"""A FEM solve stopped part way (``--max-time`` cap, Ctrl-C, a Newton that gives up) hands
back its last converged state and load factor: the state is the one the solve reported
converged at that load (``on_step`` records each), and the stop comes within seconds of the
cap, inside a P2/P1 mixed tissue solve (Land's beam, 9.5k DOFs, tens of seconds in all).

The latency bound (the cap plus 5 s) is the cap's function, not a speed measurement."""

from __future__ import annotations

import _thread
import threading
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest

from reference_fem.newton import NewtonOptions, solve_nonlinear
from reference_fem.solver import make_problem
from springfem.errors import SolverError
from springfem.mechanics.limits import SolveStopped, solve_limits
from springfem.scene import scene_from_dict

SCENE = Path(__file__).resolve().parents[2] / "studies" / "scenes" / "land-beam.toml"


def beam(**fem):
    data = tomllib.loads(SCENE.read_text())
    data["fem"].update(fem)
    return make_problem(scene_from_dict(data, path=SCENE))


def run(problem, **opts):
    seen: dict[float, np.ndarray] = {}
    opts.setdefault("load_steps", 8)
    o = NewtonOptions(on_step=lambda lam, u: seen.__setitem__(lam, problem.state(u)), **opts)
    return seen, lambda: solve_nonlinear(problem, o)


def check_last_good(exc, seen):
    """The handed-back state is the last one reported converged, at its load factor."""
    lam = exc.load_factor
    if not seen:
        assert lam == 0.0 and np.all(np.asarray(exc.state) == 0.0)
        return
    assert lam == max(seen) and np.array_equal(exc.state, seen[lam])


def test_time_cap_stops_a_mixed_tissue_solve_within_seconds():
    problem = beam()
    seen, go = run(problem)
    cap = 3.0
    t0 = time.monotonic()
    with solve_limits(max_time=cap), pytest.raises(SolveStopped) as e:
        go()
    latency = time.monotonic() - t0 - cap
    assert latency < 5.0, f"stopped {latency:.2f} s after the cap"
    assert "--max-time cap of 3 s" in str(e.value)
    assert "last converged load factor" in str(e.value)
    check_last_good(e.value, seen)


@pytest.mark.skipif(
    threading.current_thread() is not threading.main_thread(),
    reason="signals reach the main thread only (a test runner may use another)",
)
def test_ctrl_c_stops_with_the_last_converged_state(python_sigint):
    """Ctrl-C (SIGINT's effect, raised in the main thread) once two load steps converged,
    from a timer thread started at the second step: the stop does not depend on how fast
    the machine is."""
    problem = beam()
    seen: dict[float, np.ndarray] = {}
    pressed: list[float] = []

    def on_step(lam, u):
        seen[lam] = problem.state(u)
        if len(seen) == 2 and not pressed:
            pressed.append(time.monotonic())
            threading.Timer(0.05, _thread.interrupt_main).start()

    opts = NewtonOptions(on_step=on_step, load_steps=8)
    with pytest.raises(SolveStopped, match=r"interrupted \(Ctrl-C\)") as e:
        solve_nonlinear(problem, opts)
    assert pressed and time.monotonic() - pressed[0] < 5.0
    check_last_good(e.value, seen)
    assert e.value.load_factor >= max(sorted(seen)[:2])


def test_newton_that_gives_up_reports_its_load_factor():
    """Two Newton iterations per step cannot converge this beam: the SolverError carries
    the last converged state and its load factor (0 here: no step converged)."""
    problem = beam()
    seen, go = run(problem, max_iter=2, max_cutbacks=1)
    with pytest.raises(SolverError) as e:
        go()
    assert e.value.load_factor is not None
    check_last_good(e.value, seen)


def test_solve_that_gives_up_keeps_the_load_factor():
    """:func:`reference_fem.solve` adds the scene to the message and keeps both fields."""
    from reference_fem import solve
    from springfem.scene import scene_from_dict

    scene = scene_from_dict(
        {
            "mesh": {"generator": "cook", "divisions": [4, 4, 1]},
            "material": {"law": "neo-hookean", "E": 240.565, "nu": 0.4999},
            "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
            "load": [{"type": "traction", "region": "x_max", "value": [0.0, 20.0, 0.0]}],
            "fem": {"max_iter": 1, "load_steps": 1},
        }
    )
    with pytest.raises(SolverError) as e:
        solve(scene)
    assert e.value.load_factor == 0.0 and e.value.state is not None
