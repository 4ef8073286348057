"""The bundled dynamic scenes load, declare their run, and move as their loads say.

Each is run briefly (coarsened where it is a box) with the dynamic reference, and checked
against what its loads imply: the pull does work while it acts and none after its release,
gravity pulls the organ down, the energy balance closes (to the rule's error). Any scene
runs, a static one too (the cantilever, which has no [dynamics] section).
"""

import numpy as np
import pytest

from reference_fem.dynamics_implicit import run
from springfem.scene import DynamicsOptions, load_scene, scene_from_dict
from studies.scenes import SCENES, bundled_table

DYNAMIC = ("pull-release", "organ-settle", "ventricle-pulse")


@pytest.mark.parametrize("name", DYNAMIC)
def test_dynamic_scenes_declare_their_run(name):
    scene = load_scene(SCENES / f"{name}.toml")
    o = DynamicsOptions.of(scene)
    assert o.t_end > 0 and 0 < o.dt < o.t_end and not o.damping.none
    assert any(load.time is not None for load in scene.loads) or name == "organ-settle"


@pytest.mark.slow
def test_pull_release_pulls_then_lets_go():
    table = bundled_table("pull-release", {"mesh.divisions": [8, 8, 2]})  # the patch: 8 facets
    scene = scene_from_dict(table, path=SCENES / "pull-release.toml")
    r = run(scene, t_end=0.3, dt=2e-3)
    t, w, e = r.times, r.energies["external_work"], r.energies
    pulling, released = t <= 0.2, t >= 0.2
    assert w[pulling][-1] > 0 and np.ptp(w[released]) == 0.0  # no work once released
    z = r.probes["patch"][:, 2]
    assert z[pulling].max() > 0  # pulled up
    assert abs(z[-1]) < 0.5 * z[pulling].max()  # swung back down after the release
    total = e["kinetic"] + e["strain"] + e["dissipated"]
    assert np.abs(e["balance"]).max() < 0.02 * total.max()
    assert len(r.frames) == 21 and r.frames[0].shape == (scene.mesh.n_points, 3)


def test_any_scene_runs_a_static_one_too():
    table = bundled_table("cantilever", {"mesh.divisions": [10, 1, 1]})
    r = run(scene_from_dict(table), t_end=0.02, dt=0.01, order=2)
    assert r.steps == 2 and r.probes["tip"][-1, 2] < 0  # the traction pushes the tip down


@pytest.mark.slow
def test_organ_settles_down():
    scene = load_scene(SCENES / "organ-settle.toml")
    r = run(scene, t_end=0.05)
    assert r.info["formulation"] == "mixed"
    assert (np.diff(r.probes["bottom"][:, 2]) < 0).all()  # falling in the first 50 ms


@pytest.mark.slow
def test_ventricle_pulse_swells():
    scene = load_scene(SCENES / "ventricle-pulse.toml")
    r = run(scene, t_end=0.01)
    assert r.probes["endo_apex"][-1, 2] < -0.1  # the apex is pushed down
