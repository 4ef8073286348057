"""``study volume-drift --scene`` on an incompressible tissue scene (the Land beam, Guccione,
``formulation = "mixed"``): P1 cannot be Taylor–Hood, so the studies' P1 solves the
displacement formulation with the spring model's penalty (``compare_models.model_scene``)
instead of stopping with "needs order 2".

Independent reference: the mixed P2/P1 solve enforces ``int q (J - 1) dX = 0`` for every P1
pressure ``q``; ``q = 1`` makes the whole-body volume change zero up to the Newton tolerance.
"""

from __future__ import annotations

import pandas as pd

from studies.cli import main


def test_volume_drift_on_the_land_beam(tmp_path):
    argv = ["study", "volume-drift", "--quick", "--scene", "studies/scenes/land-beam.toml",
            "--set", "mesh.divisions=[6, 1, 1]", "--out", str(tmp_path)]  # fmt: skip
    assert main(argv) == 0
    table = pd.read_csv(tmp_path / "volume_drift" / "scene_static_drift.csv").set_index("method")
    assert table.loc["fem-p1", "status"] == "ok"
    assert table.loc["fem-p1", "law"] == "guccione/log"  # displacement formulation, penalty
    assert table.loc["fem-scene", "law"] == "guccione/mixed-P2P1"
    # the mixed solve's own constraint (q = 1): zero volume change to the Newton tolerance
    assert abs(table.loc["fem-scene", "dV (P2 volume)"]) < 1e-6
