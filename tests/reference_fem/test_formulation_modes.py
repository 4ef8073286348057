"""No spurious modes: the near-zero eigenvalues of each formulation's tangent
(:func:`springfem.mechanics.modes.zero_modes`) on an irregular mesh (jittered Delaunay box).

A free body has exactly the six rigid-body modes, a clamped one none
(docs/volumetric.rst#counting-spurious-modes); checked at rest for plain P1, nodal-volume P1
(pure nodal averaging and the default share), nodal-strain P1 (pure node-based smoothing of
the strain and the default blend), Taylor–Hood P2/P1 and MINI, and at the final
load of a solved membrane.
"""

import numpy as np
import pytest

from reference_fem import solve
from reference_fem.solver import make_problem
from springfem.mechanics.modes import zero_modes
from springfem.mesh import box_mesh
from springfem.scene import scene_from_dict

NEO = {"law": "neo-hookean", "E": 1.0, "nu": 0.4999, "formulation": "uncoupled"}
GUCCIONE = {"law": "guccione", "C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0}
FORMULATIONS = {
    "P1": {"order": 1},
    "nodal-volume-f0": {"order": 1, "formulation": "nodal-volume", "stabilisation": 0.0},
    "nodal-volume": {"order": 1, "formulation": "nodal-volume"},
    "nodal-strain-a0": {"order": 1, "formulation": "nodal-strain", "strain_stabilisation": 0.0},
    "nodal-strain": {"order": 1, "formulation": "nodal-strain"},
    "mixed": {"order": 2, "formulation": "mixed"},
    "mini": {"order": 1, "formulation": "mini"},
}


def rest_tangent(material, fem, clamped: bool):
    scene = scene_from_dict(
        {
            "mesh": box_mesh((1.0, 0.8, 0.6), (3, 3, 2), split="delaunay", seed=2),
            "material": material,
            "axes": {"fiber": [1.0, 1.0, 0.3], "sheet": [-1.0, 1.0, 0.0]},
            "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}] if clamped else [],
            "fem": fem,
        }
    )
    p = make_problem(scene)
    K = p.residual_tangent(np.zeros(p.n_dofs))[1]
    K = K.toarray()
    return K[np.ix_(p.free, p.free)] if clamped else K


MATERIALS = {"neo-hookean": NEO, "guccione": {**GUCCIONE, "incompressible": True}}
CASES = [(f, m) for f in FORMULATIONS for m in MATERIALS if not (f == "P1" and m == "guccione")]


@pytest.mark.parametrize("formulation, material", CASES)
def test_free_body_has_exactly_the_rigid_modes(formulation, material):
    assert (
        zero_modes(rest_tangent(MATERIALS[material], FORMULATIONS[formulation], False)).count == 6
    )


@pytest.mark.parametrize("formulation, material", CASES)
def test_clamped_body_has_no_zero_mode(formulation, material):
    modes = zero_modes(rest_tangent(MATERIALS[material], FORMULATIONS[formulation], True))
    assert modes.count == 0
    if formulation not in ("mixed", "mini"):  # a saddle point is indefinite by construction
        assert modes.negative == 0


@pytest.mark.parametrize("formulation", ["nodal-volume", "nodal-strain", "mixed", "mini"])
def test_no_zero_mode_at_the_final_load(formulation):
    scene = scene_from_dict(
        {
            "mesh": {"generator": "cook", "divisions": [6, 6, 1], "thickness": 10.0},
            "material": {"law": "neo-hookean", "E": 240.565, "nu": 0.4999},
            "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
            "load": [{"type": "traction", "region": "x_max", "value": [0.0, 2.0, 0.0]}],
            "fem": {**FORMULATIONS[formulation], "load_steps": 2},
        }
    )
    sol = solve(scene)
    p = sol.problem
    K = p.residual_tangent(sol.u)[1].toarray()
    modes = zero_modes(K[np.ix_(p.free, p.free)])
    assert modes.count == 0
    if formulation == "nodal-volume":
        assert modes.negative == 0  # a stable equilibrium
