"""Frame stepping of an explicit form against the closed-form oscillator."""

import numpy as np
import pytest

from springfem.frames import ExplicitFrames, frames_settings
from springfem.mechanics.toy import Oscillator

OMEGA = 2.0  # the toy: stiffness 4, mass 1


def run(safety: float, frame_dt: float = 0.05, frames: int = 120, damping: float = 0.0):
    stepper = ExplicitFrames(Oscillator(), frame_dt, safety=safety, mass_damping=damping)
    x, v = stepper.start()
    xs = []
    for k in range(frames):
        stepper.frame(x, v, k * frame_dt, lambda t: 1.0)
        xs.append(x[3, 0])
    return stepper, np.arange(1, frames + 1) * frame_dt, np.array(xs)


def test_step_load_matches_the_closed_form():
    stepper, t, x = run(0.05)
    exact = 0.25 * (1 - np.cos(OMEGA * t))
    assert stepper.dt_crit == pytest.approx(2 / OMEGA)
    assert stepper.h <= 0.05 * stepper.dt_crit + 1e-15
    # Verlet's phase error: omega^3 h^2 t / 24 of an amplitude of 1/4
    assert np.abs(x - exact).max() < 1.2 * 0.25 * OMEGA**3 * stepper.h**2 * t[-1] / 24


def test_second_order_in_the_substep():
    errs = []
    for safety in (0.4, 0.2, 0.1):  # 2, 4 and 8 substeps a frame
        _, t, x = run(safety, frame_dt=0.8, frames=10)
        errs.append(np.abs(x - 0.25 * (1 - np.cos(OMEGA * t))).max())
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert (orders > 1.8).all(), orders


def test_mass_damping_matches_the_damped_closed_form():
    alpha = 0.6
    stepper, t, x = run(0.01, frame_dt=0.01, frames=600, damping=alpha)
    wd = np.sqrt(OMEGA**2 - alpha**2 / 4)
    decay = np.exp(-alpha * t / 2)
    exact = 0.25 * (1 - decay * (np.cos(wd * t) + alpha / (2 * wd) * np.sin(wd * t)))
    assert np.abs(x - exact).max() < 1.2 * 0.25 * OMEGA**3 * stepper.h**2 * t[-1] / 24 + 1e-6


def test_explicit_forms_are_tried_cheapest_first():
    class Plain:
        def system(self, scene):
            return Oscillator()

    safeties = [s["safety"] for s in frames_settings(Plain())]
    assert safeties == sorted(safeties, reverse=True)
