"""The apex mesh-convergence table of the tissue study: Richardson extrapolation against
closed-form sequences (f = f0 + C h^p), and the published problem-2 values it cites."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from studies.metrics import observed_order
from studies.study_tissue.convergence import PUBLISHED, convergence_findings, richardson_frame


@pytest.mark.parametrize("p", [1.0, 2.0, 3.3])
def test_order_and_limit_of_a_power_law_on_uneven_meshes(p):
    h = np.array([3.5, 2.9, 2.1])  # uneven ratios, as gmsh gives
    got_p, f0, note = observed_order(h, -26.5 + 0.7 * h**p)
    assert note == ""
    assert got_p == pytest.approx(p, rel=1e-9)
    assert f0 == pytest.approx(-26.5, abs=1e-9)


def test_oscillating_values_have_no_order():
    p, f0, note = observed_order(np.array([4.0, 2.0, 1.0]), np.array([1.0, 1.2, 1.1]))
    assert math.isnan(p) and math.isnan(f0) and note == "oscillating"


def _frame(values_endo, values_epi, h):
    return pd.DataFrame({"scene": "land-ventricle", "h": h, "endo_apex_z": values_endo,
                         "epi_apex_z": values_epi})  # fmt: skip


def test_four_meshes_on_a_power_law_are_asymptotic_and_compared_to_the_published():
    h = np.array([3.5, 3.0, 2.7, 2.3])
    df = _frame(-26.53 + 0.4 * h**2, -28.18 + 0.3 * h**2, h)
    rich = richardson_frame(df).set_index("surface")
    assert rich.loc["endo", "order"] == pytest.approx(2.0, rel=1e-9)
    assert rich.loc["endo", "asymptotic"] == "yes"
    assert rich.loc["endo", "extrapolated"] == pytest.approx(-26.53, abs=1e-9)
    assert rich.loc["endo", "fit_order_2"] == pytest.approx(-26.53, abs=1e-9)
    assert rich.loc["epi", "extrapolated_minus_published"] == pytest.approx(
        -28.18 - PUBLISHED["land-ventricle"]["epi"], abs=1e-9)  # fmt: skip
    text = convergence_findings(richardson_frame(df))
    assert "-26.53 / -28.18 mm (endo / epi" in text[0] and "published -26.53" in text[0]


def test_a_changing_order_is_flagged_not_asymptotic():
    # the three coarse meshes follow h^1, the three fine ones h^3: the triples disagree
    h = np.array([3.5, 3.0, 2.7, 2.3])
    f = list(-27.0 + 0.2 * h[:3])
    f.append(f[2] - (f[1] - f[2]) * (h[2] ** 3 - h[3] ** 3) / (h[1] ** 3 - h[2] ** 3))
    f = np.array(f)
    assert observed_order(h[1:], f[1:])[0] == pytest.approx(3.0, rel=1e-9)
    rich = richardson_frame(_frame(f, f - 1.7, h)).set_index("surface")
    assert rich.loc["endo", "asymptotic"].startswith("no (coarser triple")


def test_the_published_values_are_the_ones_cited():
    # FEniCS-pulse, finsberg/pulse pull request 98: 26.5328 and 28.1790 mm (apex down)
    assert PUBLISHED["land-ventricle"] == {"endo": -26.5328, "epi": -28.1790}
