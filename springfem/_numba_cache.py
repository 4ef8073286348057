"""Numba's on-disk kernel cache, keyed by the project's sources.

Numba invalidates a cached kernel only when *its own* file changes; a kernel that inlines
helpers from another module (the models' kernel factories do) is reloaded stale after an
edit of that module, and then computes wrong forces without any error. Pointing numba at a
cache folder named by a hash of every source file of the core and of the packages that
register compiled kernels (entry-point group ``springfem.kernels``, :mod:`springfem.plugins`)
makes any edit start from a clean cache, while an unchanged checkout reuses its kernels.

Inside that folder numba would file each kernel under a hash of its source folder's absolute
path, so a fresh clone, a second worktree or a CI checkout elsewhere compiled everything
again (about 40 s of a quick report). The folder already names the exact sources, so
:class:`PackageRelativeLocator` files the kernels of the kernel packages under their path
*inside* the package instead (``springmodel/…``): any checkout of the same sources on the
machine reuses them. It is installed only together with the source-keyed folder.

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
from typing import Any

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
    locators = os.environ.get("NUMBA_CACHE_LOCATOR_CLASSES") or LOCATORS
    if "numba" in sys.modules:  # already configured from the environment: set it directly
        sys.modules["numba"].config.CACHE_DIR = folder
        sys.modules["numba"].config.CACHE_LOCATOR_CLASSES = locators
    else:  # numba reads it when first imported; importing numba here would slow start-up
        os.environ["NUMBA_CACHE_DIR"] = folder
        os.environ["NUMBA_CACHE_LOCATOR_CLASSES"] = locators
    return folder


#: Numba's locator classes (``NUMBA_CACHE_LOCATOR_CLASSES``): ours first, then numba's own
#: (by their names in ``numba.core.caching``) for every other cached function.
LOCATORS = ",".join(
    [f"{__name__}.PackageRelativeLocator", "UserProvidedCacheLocator", "InTreeCacheLocator",
     "UserWideCacheLocator", "IPythonCacheLocator", "ZipCacheLocator"]
)  # fmt: skip


def package_relative_subpath(py_file: str | os.PathLike, roots: list[Path]) -> str | None:
    """The cache subfolder of a source file below one of ``roots`` (package folders): its
    folder's path from the package's parent, or ``None`` outside them.

    Examples
    --------
    >>> package_relative_subpath("/a/b/springmodel/kernels.py", [Path("/a/b/springmodel")])
    'springmodel'
    >>> package_relative_subpath("/x/y.py", [Path("/a/b/springmodel")]) is None
    True
    """
    folder = Path(os.path.abspath(py_file)).parent
    for root in roots:
        if folder == root or root in folder.parents:
            return str(Path(root.name) / folder.relative_to(root))
    return None


def _locator_class() -> Any:
    """Numba's user-provided-folder locator, filing the kernel packages' functions by their
    path inside the package (module docstring)."""
    from numba.core import caching

    roots = [f.resolve() for f in kernel_packages()]

    class PackageRelativeLocator(caching.UserProvidedCacheLocator):
        def __init__(self, py_func: Any, py_file: str):
            super().__init__(py_func, py_file)
            sub = package_relative_subpath(py_file, roots)
            folder = os.path.dirname(self._cache_path)  # numba's CACHE_DIR
            self._cache_path = os.path.join(folder, "packages", str(sub))

        @classmethod
        def from_function(cls, py_func: Any, py_file: str) -> Any:
            if package_relative_subpath(py_file, roots) is None:
                return None  # not ours: numba's next locator
            return super().from_function(py_func, py_file)

    return PackageRelativeLocator


def __getattr__(name: str) -> Any:
    # numba imports the locator by name when it first caches a function; building the class
    # then keeps numba's import out of springfem's start-up
    if name == "PackageRelativeLocator":
        cls = _locator_class()
        globals()[name] = cls
        return cls
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
