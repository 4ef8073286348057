"""Numba's on-disk cache is shared by every checkout of the same sources on a machine.

Two copies of the kernel packages in two folders (a fresh clone, a second worktree): the
second finds the kernel the first compiled (numba's own locator filed it under a hash of the
first copy's absolute path, so the second compiled it again)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

from springfem._numba_cache import kernel_packages

SCRIPT = """
import numpy as np
from springfem.mesh import colouring
colouring.element_colouring(np.array([[0, 1, 2, 3], [1, 2, 3, 4]]), 5)
stats = colouring._compiled_colouring.stats
print(sum(stats.cache_hits.values()), sum(stats.cache_misses.values()))
"""


def _hits_misses(checkout: Path, xdg: Path) -> tuple[int, int]:
    env = {k: v for k, v in os.environ.items()
           if k not in ("NUMBA_CACHE_DIR", "NUMBA_CACHE_LOCATOR_CLASSES")}  # fmt: skip
    env.update(PYTHONPATH=str(checkout), XDG_CACHE_HOME=str(xdg))
    out = subprocess.run([sys.executable, "-c", SCRIPT], cwd=checkout, env=env,
                         capture_output=True, text=True, check=True, timeout=300)  # fmt: skip
    hits, misses = out.stdout.split()[-2:]
    return int(hits), int(misses)


def test_a_second_checkout_of_the_same_sources_reuses_the_compiled_kernels(tmp_path):
    for name in ("a", "b"):
        for folder in kernel_packages():
            shutil.copytree(folder, tmp_path / name / folder.name,
                            ignore=shutil.ignore_patterns("__pycache__"))  # fmt: skip
    xdg = tmp_path / "cache"
    assert _hits_misses(tmp_path / "a", xdg) == (0, 1)  # compiled
    assert _hits_misses(tmp_path / "b", xdg) == (1, 0)  # loaded: another folder, same sources
    filed = list((xdg / "springfem").glob("numba-*/packages/springfem/mesh/colouring*.nbi"))
    assert len(filed) == 1
