"""Static spring solves through the compiled tangent: the AMG path (which reuses the last
tangent's hierarchy across Newton iterations) reaches the same equilibrium as SuperLU (no
reuse, exact solves) on the bundled scenes, and both are equilibria of the force kernel."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from springfem.mechanics import static
from springmodel.model import SpringModel
from springmodel.options import SpringOptions
from studies.overrides import load_scene_with

SCENES = ["cantilever", "sag", "stretch-fiber"]


@pytest.mark.parametrize("name", SCENES)
def test_amg_with_reused_hierarchy_matches_direct(name):
    """Both solves stop at a relative residual of 1e-10 or at round-off (the slender
    cantilever stagnates near 3e-9); the relative displacement difference is then bounded by
    the relative residual times the conditioning of the equilibrium, and the 1e-8 bound
    (the issue's) fails for a wrong tangent or a stale preconditioner CG did not correct
    (Newton would stall or converge elsewhere)."""
    scene = load_scene_with(f"studies/scenes/{name}.toml", [])
    scene = scene.with_options(spring=replace(SpringOptions.of(scene), torsion="energy"))
    model = SpringModel(scene, parallel=False)
    ref = static(model, tol=1e-10, linear_solver="direct")
    amg = static(model, tol=1e-10, linear_solver="amg")
    assert ref.converged and amg.converged and "cg+amg" in amg.linear_solver
    u_ref, u_amg = ref.x - model.x0, amg.x - model.x0
    assert np.linalg.norm(u_amg - u_ref) <= 1e-8 * np.linalg.norm(u_ref)
    # an independent check of the equilibrium: the force kernel's free residual
    f = model.forces(amg.x, None).reshape(-1)
    free = np.setdiff1d(np.arange(f.size), model.fixed_dofs)
    # (1e-8: above the round-off stagnation level Newton reports, 3e-9 on the cantilever)
    assert np.linalg.norm(f[free]) <= 1e-8 * amg.reference_force
