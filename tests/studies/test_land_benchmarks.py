"""The Land benchmark level runner (studies.land_benchmarks): its extrapolation recovers a
known limit and order, rows merge per problem, a stopped level shows where it stopped, and
the cited published values are the ones in the manual."""

from __future__ import annotations

import doctest
import math

import pytest

import studies.land_benchmarks as lb
from springfem.ellipsoid import wall_volume


def _tets(h):
    """The tet count whose mean-volume regular tet has the edge ``h`` (the runner's h)."""
    return 6.0 * math.sqrt(2.0) * wall_volume() / h**3


def _row(problem, h, **values):
    return {"problem": problem, "size": h, "axis_size": None, "tets": _tets(h), "dofs": 30,
            "wall": 1.0, "iterations": 5, "load_steps": 2, "cutbacks": 0, "error": "",
            **values}  # fmt: skip


def test_extrapolation_recovers_the_limit_of_a_known_sequence():
    # f = f0 + C h^p with p = 1.5: the three finest levels give p and f0 to round-off
    rows = [_row("2", h, endo=-26.5 + 0.3 * h**1.5, epi=-28.2 + 0.1 * h**1.5)
            for h in (4.0, 3.0, 2.0, 1.5)]  # fmt: skip
    ext = lb.extrapolate(rows)["2"]
    assert ext["endo"]["order"] == pytest.approx(1.5, abs=1e-9)
    assert ext["epi"]["extrapolated"] == pytest.approx(-28.2, abs=1e-9)
    assert ext["endo"]["asymptotic"] and ext["endo"]["order_coarser"] == pytest.approx(1.5)
    assert "(p = 1.5, coarser 1.5)" in lb.markdown(rows) and "-26.53" in lb.markdown(rows)
    # a sequence whose order changes between the triples is flagged
    rows[0]["endo"] += 0.5
    assert not lb.extrapolate(rows)["2"]["endo"]["asymptotic"]


def test_rows_merge_per_problem_and_a_stopped_level_is_shown(tmp_path):
    lb.merge_row(_row("1", 1.0, tip=4.0), tmp_path)
    lb.merge_row(_row("1", 1.0, tip=4.1), tmp_path)  # the same level again: replaced
    lb.merge_row({"problem": "3", "size": 2.0, "axis_size": 0.5, "error": "Newton failed",
                  "wall": 9.0, "load_factor": 0.47}, tmp_path)  # fmt: skip
    rows = lb.load_rows(tmp_path)
    assert [r["problem"] for r in rows] == ["1", "3"] and rows[0]["tip"] == 4.1
    table = lb.markdown(rows)
    assert "stopped at load 0.47" in table and "4.14-4.20" in table
    assert lb.extrapolate(rows)["1"]["tip"]["note"] == "fewer than 3 levels"


def test_published_values_are_the_cited_ones():
    assert lb.PULSE["2"] == {"endo": -26.5328, "epi": -28.1790}
    assert lb.PULSE["3"] == {"endo": -12.00, "epi": -15.22}
    assert lb.PAPER_RANGE["1"]["tip"] == (4.14, 4.20)


def test_doctests():
    assert doctest.testmod(lb).failed == 0
