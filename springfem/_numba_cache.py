"""Numba's on-disk kernel cache, keyed by the project's sources.

Numba invalidates a cached kernel only when *its own* file changes; a kernel that inlines
helpers from another module (the models' kernel factories do) is reloaded stale after an
edit of that module, and then computes wrong forces without any error. Pointing numba at a
cache folder named by a hash of every source file of the core and of the packages that
register compiled kernels (entry-point group ``springfem.kernels``, :mod:`springfem.plugins`)
makes any edit start from a clean cache, while an unchanged checkout reuses its kernels.

Examples
--------
>>> h = source_hash(kernel_packages())
>>> len(h), h == source_hash(kernel_packages())  # stable for a checkout
(16, True)
"""

from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path

from .plugins import entry_points, package_folder


def kernel_packages() -> list[Path]:
    """The source folders of the core and of the packages that register compiled kernels.

    Returns
    -------
    list of Path
    """
    folders = [Path(__file__).resolve().parent]
    for name in sorted(entry_points("springfem.kernels").values()):
        folder = package_folder(name)
        if folder is not None:
            folders.append(folder.resolve())
    return folders


def source_hash(folders: list[Path]) -> str:
    """Hash of the Python sources below ``folders``.

    Parameters
    ----------
    folders
        Package folders.

    Returns
    -------
    str
        16 hex digits.
    """
    h = hashlib.sha256()
    for root in folders:
        for f in sorted(root.rglob("*.py")):
            h.update(f"{root.name}/{f.relative_to(root)}".encode())
            h.update(f.read_bytes())
    return h.hexdigest()[:16]


def use_source_keyed_numba_cache() -> str | None:
    """Point numba's cache at ``<cache>/springfem/numba-<source hash>`` (once per process).

    A ``NUMBA_CACHE_DIR`` set by the user is kept as it is.

    Returns
    -------
    str or None
        The cache folder in use, or ``None`` when the user chose one.
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return None
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "springfem"
    folder = str(base / f"numba-{source_hash(kernel_packages())}")
    if "numba" in sys.modules:  # already configured from the environment: set it directly
        sys.modules["numba"].config.CACHE_DIR = folder
    else:  # numba reads it when first imported; importing numba here would slow start-up
        os.environ["NUMBA_CACHE_DIR"] = folder
    return folder
