"""Regression test of the report's headline numbers.

Runs the quick report (all eight studies, coarse meshes) into a fresh folder, so nothing
is reused from a cache, and compares every accuracy headline with the committed values in
``reports/headline-quick.json`` within a stated tolerance. Timing-derived numbers (costs,
speeds, fitted cost slopes) are noisy on a shared machine and are only checked for being
finite. After an intentional change of a model, regenerate the committed file with
``springfem report --quick --out reports/quick && cp reports/quick/headline-quick.json
reports/`` and say why in the commit.
"""

import json
import math
from pathlib import Path

import pytest

from studies.runner import run_report

ROOT = Path(__file__).resolve().parents[2]
COMMITTED = ROOT / "reports" / "headline-quick.json"
TIMING_WORDS = ("slope", "time", "cost", "speed", "per_step", "tets_per_s", "seconds", "ms")

# Relative tolerance for accuracy numbers: the quick studies are deterministic apart from
# solver stopping points (Newton tolerances 1e-8, dynamic relaxation 1e-6..1e-8), which
# move errors of order 1e-2 by far less than 2 %; a model regression moves them by more.
REL_TOL = 0.02
ABS_TOL = 1e-6


@pytest.fixture(scope="module")
def quick_headline(tmp_path_factory):
    out = tmp_path_factory.mktemp("quick-report")
    outputs = run_report(out, quick=True)
    assert (out / "REPORT.md").is_file()
    for o in outputs:
        for fig in o.figures:
            assert Path(fig.path).stat().st_size > 10_000, fig.path  # a real picture
    return {o.name: o.headline for o in outputs}


def test_committed_headline_exists():
    assert COMMITTED.is_file(), "run the quick report and commit reports/headline-quick.json"


def test_headline_numbers_match_committed(quick_headline):
    committed = json.loads(COMMITTED.read_text())
    assert set(committed) == set(quick_headline)
    failures = []
    for study, values in committed.items():
        for key, ref in values.items():
            got = quick_headline[study].get(key)
            where = f"{study}.{key}"
            if got is None or ref is None:
                if got != ref:
                    failures.append(f"{where}: {got} != {ref}")
                continue
            if any(w in key for w in TIMING_WORDS):
                if not math.isfinite(got):
                    failures.append(f"{where}: not finite ({got})")
                continue
            if not math.isclose(got, ref, rel_tol=REL_TOL, abs_tol=ABS_TOL):
                failures.append(f"{where}: {got:.6g} vs committed {ref:.6g}")
    assert not failures, "\n".join(failures)
