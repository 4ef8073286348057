"""The source folders of the plug-in models' packages, for the code fingerprints.

The studies' case cache (:mod:`studies.runner`) and the sweeps (:mod:`studies.sweep`) key
every case by the code that computed it; a plug-in model (:mod:`springfem.model_api`) lives
outside ``springfem`` and ``studies``, so its package's folder joins the fingerprint.
"""

from __future__ import annotations

from pathlib import Path

from .models import sync_plugins


def plugin_sources() -> list[Path]:
    """The source folders of the plug-in models' packages (part of the studies' and
    sweeps' code fingerprints, so that editing a plug-in recomputes its cases).

    Returns
    -------
    list of Path
    """
    import importlib

    from springfem.model_api import plugin_module

    folders = set()
    for m in sync_plugins():
        name = plugin_module(m)
        if name in ("springfem", "studies"):
            continue  # in every fingerprint already
        src = getattr(importlib.import_module(name), "__file__", None)
        if src:
            path = Path(src).parent if Path(src).name == "__init__.py" else Path(src)
            folders.add(path)
    return sorted(folders)
