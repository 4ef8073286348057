"""Every registered model passes the conformance check (springfem.testing.check_model): rigid
motion gives no force, forces and tangent are finite differences of the energy and the
forces, the small-strain limit is linear P1's where the model claims it, and an undamped
explicit run conserves energy. On a jittered Delaunay box of 360 tets, neo-Hookean; a model
that does not take it (the tissue elements) on the same box with the Guccione law, and the
models that take both on that too (the tissue laws' own kernels and tangents)."""

from __future__ import annotations

import pytest

from springfem.api import models
from springfem.scene import scene_from_dict
from springfem.testing import check_model

BOX = {"generator": "box", "size": [0.06, 0.02, 0.02], "divisions": [6, 3, 3], "split": "delaunay"}
MATERIALS = {
    "neo-hookean": {"law": "neo-hookean", "E": 1.0e4, "nu": 0.3, "density": 1000.0},
    "guccione": {"law": "guccione", "C": 2000.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0,
                 "kappa": 5.0e4, "density": 1000.0},
    "linear": {"law": "linear", "E": 1.0e4, "nu": 0.3, "density": 1000.0},
}  # fmt: skip
#: What the plug-ins claim (springfem.testing.check_model): ``exact``, the tangent at rest is
#: linear P1's; ``approximate``, the stiffness is a Newton matrix, not the forces' derivative.
#: The spring and FEM models declare theirs (``claims``: the exact elements and P1 ``exact``,
#: P1-NH ``limit``, its solve under a tiny load through reference_fem's Newton).
CLAIMS = {
    "corotational": {"small_strain": "exact"},
    "corotational-warped": {"small_strain": "exact", "tangent": "approximate"},
}


def _scene(law: str):
    return scene_from_dict({
        "name": f"box-{law}", "mesh": BOX, "material": MATERIALS[law],
        "axes": {"fiber": [0.8, 0.6, 0.0], "sheet": [-0.6, 0.8, 0.0]},
        "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
        "load": [{"type": "traction", "region": "x_max", "value": [0.0, 0.0, -100.0]}],
    })  # fmt: skip


SCENES = {law: _scene(law) for law in MATERIALS}
#: Every registered model, from the public listing.
MODELS = models()


def _cases() -> list:
    """(model, law) pairs: neo-Hookean and Guccione where the model takes them, else linear."""
    out = []
    for name, model in MODELS.items():
        laws = [law for law in ("neo-hookean", "guccione") if model.applies(SCENES[law]) is None]
        for law in laws or ["linear"]:
            out.append(pytest.param(name, law, id=f"{name}-{law}"))
    return out


@pytest.mark.parametrize(("name", "law"), _cases())
def test_every_model_conforms(name, law):
    model = MODELS[name]
    report = check_model(model, SCENES[law], **CLAIMS.get(name, {}))
    if all(c.status == "skipped" for c in report.checks):
        pytest.skip(f"{name}: {report.checks[0].message}")
    claims = {**(getattr(model, "claims", None) or {}), **CLAIMS.get(name, {})}
    claimed = claims.get("small_strain")
    assert (report.status("small strain") == "passed") == bool(claimed), str(report)
