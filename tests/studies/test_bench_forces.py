"""``springfem bench forces --models``: the bytes each pass moves per tet, against a count by
hand of what its kernel reads and writes, and the table's rows (no timing is asserted)."""

from __future__ import annotations

import pytest

from studies.bench_forces import bench_forces, csv, markdown
from studies.cli import main


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    folder = tmp_path_factory.mktemp("organ")
    return bench_forces((300,), ["P1-NH", "xpbd", "mass-spring"], repeats=1, folder=folder)


def test_bytes_per_tet_are_the_kernels_arrays_counted_by_hand(result):
    """P1-NH's blocked kernel reads 9 shape-gradient entries and the volume (f64) and four
    int32 node indices per element, in blocks of 16 (the last one padded); XPBD's sweep four
    int64 indices, 9 gradient entries, two compliances, and reads and writes two
    multipliers; per node, the force passes read the positions and write the forces (48 B),
    XPBD reads and writes the positions and reads the inverse masses (72 B)."""
    rows = {r["model"]: r for r in result["rows"]}
    m, n = rows["P1-NH"]["tets"], rows["P1-NH"]["nodes"]
    padded = -(-m // 16) * 16 / m
    assert rows["P1-NH"]["bytes_per_tet"] == pytest.approx((10 * 8 + 4 * 4) * padded + 48 * n / m)
    assert rows["xpbd"]["bytes_per_tet"] == pytest.approx(
        4 * 8 + 9 * 8 + 2 * 8 + 4 * 8 + 72 * n / m
    )
    assert rows["xpbd"]["pass"] == "one iteration" and rows["P1-NH"]["pass"] == "force pass"
    edges_per_tet = rows["mass-spring"]["bytes_per_tet"] - 48 * n / m
    assert 1.0 < edges_per_tet / 32 < 2.0  # (2 int64 ends + rest length + k) per edge


def test_table_rows_and_floor(result):
    for r in result["rows"]:
        copy = result["bandwidth_copy"][r["tets"]]
        assert r["floor_tets_per_s"] == pytest.approx(copy / r["bytes_per_tet"])
        assert r["of_floor"] == pytest.approx(r["tets_per_s"] / r["floor_tets_per_s"])
    text = markdown(result)
    assert text.count("\n| 3") == 3 and "of floor" in text
    assert csv(result).count("\n") == 3


def test_sizes_are_checked():
    assert main(["bench", "forces", "--models", "all", "--sizes", "10"]) == 2
