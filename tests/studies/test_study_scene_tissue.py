"""The volume-drift study on an incompressible tissue scene (the Land beam, Guccione,
``formulation = "mixed"``): P1 cannot be Taylor–Hood, so the registry's P1 solves the
displacement formulation with the spring model's penalty (``reference_fem.fitting.tissue_scene``)
instead of stopping with "needs order 2".

Independent reference: the mixed P2/P1 solve enforces ``int q (J - 1) dX = 0`` for every P1
pressure ``q``; ``q = 1`` makes the whole-body volume change zero up to the Newton tolerance.
"""

from __future__ import annotations

import pandas as pd
import pytest

from studies.cache import CaseCache
from studies.registry import StudyContext
from studies.scenes import StudyScene
from studies.study_volume_drift import Settings, run


@pytest.mark.slow
def test_volume_drift_on_the_land_beam(tmp_path):
    scene = StudyScene.from_file("studies/scenes/land-beam.toml", {"mesh.divisions": [6, 1, 1]})
    ctx = StudyContext("volume_drift", tmp_path, True, CaseCache(tmp_path, "vd"), False)
    s = Settings(periods=1.0, ramp_periods=1.0, records=5, loads=(1.0,))  # short runs
    run(ctx, [scene], s)
    table = pd.read_csv(tmp_path / "static_drift.csv")
    table = table[table.load == 1.0].set_index("model")
    assert "P1-NH" not in table.index  # neo-Hookean is not the scene's law
    assert table.loc["P1", "status"] == "ok"
    assert table.loc["P1", "law"] == "guccione/log"  # displacement formulation, penalty
    assert table.loc["fem", "law"] == "guccione/mixed-P2P1"
    # the mixed solve's own constraint (q = 1): zero volume change to the Newton tolerance
    assert abs(table.loc["fem", "dV (P2 volume)"]) < 1e-6
