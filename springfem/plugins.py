"""What the packages built on the core register with it, found without the core naming them.

A package registers through entry points in its distribution's metadata
(``pyproject.toml``), so the core never imports or names its clients:

``springfem.sections``
    ``name = "module:parser"``: the parser of a scene's model section ``[name]``
    (:func:`springfem.scene.register_section` registers one directly, too);
``springfem.kernels``
    ``name = "package"``: a package whose sources the compiled kernels depend on (their
    on-disk cache is keyed by a hash of them, :mod:`springfem._numba_cache`);
``springfem.scenes``
    ``name = "package:folder"``: a folder of named scene files inside a package, that
    :func:`springfem.scene.load_scene` finds by name (``load_scene("cantilever")``);
    found without importing the package;
``springfem.laws``
    ``name = "module:Class"``: a material law (a :class:`~springfem.materials.laws.base.
    TissueLaw` subclass) added to the law table (:mod:`springfem.materials.laws`);
``springfem.models``
    ``name = "module:attribute"``: a model plug-in (or a list of them, or a function
    returning either) that the comparisons and studies weigh (:mod:`springfem.model_api`,
    docs/plugins.rst).

Examples
--------
>>> "reference_fem" in entry_points("springfem.kernels")
True
"""

from __future__ import annotations

import importlib
import importlib.metadata
import importlib.util
from functools import cache
from pathlib import Path
from typing import Any


@cache
def entry_points(group: str) -> dict[str, str]:
    """The entry points of ``group``: name -> ``"module:attribute"`` (or ``"module"``).

    Parameters
    ----------
    group
        The entry-point group.

    Returns
    -------
    dict
    """
    return {ep.name: ep.value for ep in importlib.metadata.entry_points(group=group)}


def load(value: str) -> Any:
    """The object an entry point's value names (the module is imported).

    Parameters
    ----------
    value
        ``"module:attribute"`` or ``"module"``.

    Returns
    -------
    object
    """
    module, _, attr = value.partition(":")
    obj: Any = importlib.import_module(module)
    for part in attr.split(".") if attr else ():
        obj = getattr(obj, part)
    return obj


def package_folder(name: str) -> Path | None:
    """The source folder of package ``name``, found without importing it.

    Parameters
    ----------
    name
        A top-level package name.

    Returns
    -------
    Path or None
        ``None`` if it is not installed.
    """
    spec = importlib.util.find_spec(name)
    if spec is None or not spec.submodule_search_locations:
        return None
    return Path(next(iter(spec.submodule_search_locations)))


def scene_folders() -> list[Path]:
    """The folders of named scene files the installed packages register.

    Returns
    -------
    list of Path
    """
    out = []
    for _, value in sorted(entry_points("springfem.scenes").items()):
        package, _, sub = value.partition(":")
        folder = package_folder(package)
        if folder is not None and (folder / sub).is_dir():
            out.append(folder / sub)
    return out
