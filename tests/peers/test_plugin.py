"""XPBD and the mass-spring network through the model plug-in API: found by their entry
point, compared with P1 neo-Hookean by ``compare`` on a small cantilever, and with a one-line
error where they do not apply."""

from __future__ import annotations

import numpy as np
import pytest

from peers.plugin import models as peer_models
from springfem.errors import InputError, SolverError
from springfem.model_api import ModelPlugin, plugin_models
from springfem.scene import scene_from_dict
from studies import models
from studies.compare import compare_scene

SCENE = {
    "mesh": {"generator": "box", "size": [0.1, 0.02, 0.02], "divisions": [10, 2, 2]},
    "material": {"law": "neo-hookean", "E": 1.0e4, "nu": 0.3, "density": 1000.0},
    "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
    "load": [{"type": "gravity", "value": [0.0, 0.0, -0.981]}],
    "probe": [{"name": "tip", "point": [0.1, 0.01, 0.01]}],
}


def test_the_entry_point_registers_both_models():
    found = plugin_models()
    assert {"xpbd", "mass-spring"} <= set(found)
    assert all(isinstance(m, ModelPlugin) for m in peer_models())
    assert models.get("XPBD") in models.sync_plugins()
    assert {"xpbd", "mass-spring"} <= set(models.plugins())  # weighed by default


def test_compare_weighs_them_against_p1_neo_hookean():
    """Sag of a fifth of the length: XPBD's default rest state (40 substeps of a 60 Hz frame)
    is closer to P1 neo-Hookean's tip than the network's, and within 5 % of it (the energies
    agree to second order; the substep error at 10-20 substeps is of order 1 %:
    tests/peers/test_xpbd.py); the network is another material (Cauchy relations) and only
    has to sag the same way, within a factor 3."""
    scene = scene_from_dict(SCENE)
    cmp = compare_scene(scene, models=["P1-NH", "xpbd", "mass-spring"])
    tip = {m: cmp.solutions[m].result.probes["tip"][2] for m in ("P1-NH", "xpbd", "mass-spring")}
    assert abs(tip["xpbd"] - tip["P1-NH"]) < 0.05 * abs(tip["P1-NH"]), tip
    assert abs(tip["xpbd"] - tip["P1-NH"]) < abs(tip["mass-spring"] - tip["P1-NH"]), tip
    assert 1 / 3 < tip["mass-spring"] / tip["P1-NH"] < 3, tip
    assert cmp.solutions["xpbd"].result.info["frames"] > 0


def test_xpbd_has_no_explicit_form_and_refuses_anisotropic_laws():
    scene = scene_from_dict(SCENE)
    with pytest.raises(InputError, match="no explicit form"):
        models.system(models.get("xpbd"), scene)
    transverse = {"law": "transverse-linear", "E_fiber": 3e4, "E_cross": 1e4,
                  "nu_fiber_cross": 0.3, "nu_cross": 0.4, "G_fiber": 5e3}  # fmt: skip
    table = dict(SCENE, material=transverse)
    why = models.get("xpbd").applies(scene_from_dict(table))
    assert why is not None and why.startswith("model xpbd:")


def test_xpbd_without_rest_is_a_solver_error():
    """A run that does not come to rest is no static answer: a one-line SolverError."""
    from peers.plugin import XPBDModel

    with pytest.raises(SolverError, match=r"xpbd: no rest after 2 frames \(0\.03333 s\)"):
        XPBDModel(max_frames=2).solve(scene_from_dict(SCENE))


def test_xpbd_runs_frames_of_dynamics():
    xpbd = peer_models()[0]
    out = xpbd.run(scene_from_dict(SCENE), frames=3)
    assert out.result.status.startswith("end of run at t = 0.05 s")
    assert np.isfinite(out.u).all() and out.u[:, 2].min() < 0
