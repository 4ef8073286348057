"""The study registry: ``@study("name", Settings)`` and what a study returns.

A study is a function ``run(ctx, settings) -> StudyOutput`` registered with
:func:`study`. ``settings`` is an instance of the study's frozen settings dataclass (grid
sizes, meshes, loads), which has two presets, ``Settings.full()`` and ``Settings.quick()``;
a test runs a study on a small grid by passing its own instance.

Examples
--------
>>> from dataclasses import dataclass
>>> @dataclass(frozen=True)
... class Tiny:
...     n: int = 1
...     @classmethod
...     def full(cls): return cls(4)
...     @classmethod
...     def quick(cls): return cls(2)
>>> @study("doctest-example", Tiny, register=False)
... def run(ctx, settings):
...     return StudyOutput(ctx.name, "example", headline={"n": settings.n})
>>> run.study.settings_for(quick=True)
Tiny(n=2)
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from springfem.errors import InputError

from .cache import CaseCache


@dataclass
class StudyContext:
    """Where a study writes, which preset it runs, and its case cache.

    Parameters
    ----------
    name
        The study's registered name (also the folder it writes to).
    out
        The folder of its tables and figures.
    quick
        Whether the run is the quick preset (only changes wording of the findings).
    cache
        The case cache (see :mod:`studies.cache`).
    progress
        Show a progress bar.
    """

    name: str
    out: Path
    quick: bool
    cache: CaseCache
    progress: bool = True

    def path(self, filename: str) -> Path:
        """``out / filename``, creating ``out``.

        Parameters
        ----------
        filename
            A file name inside the study's folder.

        Returns
        -------
        Path
            The path (its folder exists).
        """
        self.out.mkdir(parents=True, exist_ok=True)
        return self.out / filename


@dataclass
class Figure:
    """A PNG written by a study, with its caption."""

    path: Path
    caption: str


@dataclass
class Table:
    """A Markdown table written by a study (a CSV sits beside it), with its caption."""

    path: Path
    caption: str


@dataclass
class StudyOutput:
    """What a study found: a title, findings, tables, figures and headline numbers."""

    name: str
    title: str
    findings: list[str] = field(default_factory=list)
    tables: list[Table] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)
    headline: dict[str, float] = field(default_factory=dict)
    seconds: float = 0.0


@dataclass(frozen=True)
class Study:
    """A registered study: its name, run function, settings type and source file."""

    name: str
    run: Callable[[StudyContext, Any], StudyOutput]
    settings: type
    source: Path

    def settings_for(self, quick: bool) -> Any:
        """The preset settings: ``settings.quick()`` or ``settings.full()``.

        Parameters
        ----------
        quick
            The quick preset (coarse meshes, fewer points).

        Returns
        -------
        object
            An instance of :attr:`settings`.
        """
        return self.settings.quick() if quick else self.settings.full()


#: Registered studies in registration (= report) order.
REGISTRY: dict[str, Study] = {}


def study(name: str, settings: type, register: bool = True) -> Callable:
    """Register ``run(ctx, settings)`` as the study ``name``.

    Parameters
    ----------
    name
        The study's name (``springfem study NAME``; dashes and underscores are the same).
    settings
        Its settings dataclass, with classmethods ``full()`` and ``quick()``.
    register
        Add it to :data:`REGISTRY` (``False``: only attach the :class:`Study`).

    Returns
    -------
    callable
        A decorator returning the function unchanged, with a ``study`` attribute.
    """

    def decorate(fn: Callable) -> Callable:
        spec = Study(name, fn, settings, Path(inspect.getfile(fn)))
        if register:
            if name in REGISTRY and REGISTRY[name].run is not fn:
                raise ValueError(f"study {name!r} is registered twice")
            REGISTRY[name] = spec
        fn.study = spec
        return fn

    return decorate


def get_study(name: str) -> Study:
    """The registered study ``name`` (dashes or underscores).

    Parameters
    ----------
    name
        A study name such as ``volume-drift``.

    Returns
    -------
    Study
        Its registry entry.

    Raises
    ------
    InputError
        If no study has that name (the message lists the valid ones).
    """
    key = name.replace("-", "_")
    if key not in REGISTRY:
        valid = ", ".join(s.replace("_", "-") for s in REGISTRY)
        raise InputError(f"unknown study {name!r}; valid studies: {valid}")
    return REGISTRY[key]


def scene_settings(spec: Study, table: dict, path: str, quick: bool) -> Any:
    """The settings that run study ``spec`` on one user scene (``study NAME --scene FILE``).

    A study supports it with a classmethod ``Settings.for_scene(table, path, quick)``; one
    that cannot run on an arbitrary scene says why in ``Settings.NO_SCENE``.

    Parameters
    ----------
    spec
        The study.
    table
        The scene table (``--set`` overrides applied).
    path
        The scene file (anchors relative mesh paths).
    quick
        The quick preset (fewer levels or points).

    Returns
    -------
    object
        An instance of the study's settings.

    Raises
    ------
    InputError
        If the study cannot run on a given scene, or not on this one (the message says why).
    """
    make = getattr(spec.settings, "for_scene", None)
    if make is None:
        why = getattr(spec.settings, "NO_SCENE", "it runs only on its own scenes")
        raise InputError(f"study {spec.name.replace('_', '-')} cannot run on --scene: {why}")
    return make(table, path, quick)


def mesh_digest(table: dict, path: str | None) -> str:
    """SHA-256 of the mesh file a scene table names ('' for a generated mesh).

    Cases keyed by a scene table then change when the mesh file changes.

    Parameters
    ----------
    table
        The scene table.
    path
        The scene file (relative mesh paths are relative to its folder).

    Returns
    -------
    str
        The hex digest, or ``""``.
    """
    import hashlib

    mesh = table.get("mesh", {})
    if not isinstance(mesh, dict) or "file" not in mesh:
        return ""
    f = Path(mesh["file"])
    if not f.is_absolute() and path is not None:
        f = Path(path).parent / f
    try:
        return hashlib.sha256(f.read_bytes()).hexdigest()
    except OSError:
        return ""  # the scene validation names the missing file
