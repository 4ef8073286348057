"""The study registry: ``@study("name", Settings, scenes)`` and what a study returns.

A study is one function ``run(ctx, scenes, settings) -> StudyOutput`` of a context (where
it writes, its case cache), a list of :class:`~studies.scenes.StudyScene` and its settings,
registered with :func:`study`. ``settings`` is an instance of the study's frozen settings
dataclass (grid sizes, load factors, levels), with two presets, ``Settings.full()`` and
``Settings.quick()``; ``scenes(settings)`` gives the bundled scenes the report runs it on.
``springfem study NAME --scene FILE`` runs the same function on the user's scene, unless
the study says why it cannot (``user_scenes``). A test runs a study on a small grid by
passing its own settings and scenes.

Examples
--------
>>> from dataclasses import dataclass
>>> from studies.scenes import StudyScene
>>> @dataclass(frozen=True)
... class Tiny:
...     n: int = 1
...     @classmethod
...     def full(cls): return cls(4)
...     @classmethod
...     def quick(cls): return cls(2)
>>> def bundled(settings):
...     return [StudyScene.bundled("cantilever", {"mesh.divisions": [settings.n, 1, 1]})]
>>> @study("doctest-example", Tiny, bundled, register=False)
... def run(ctx, scenes, settings):
...     return StudyOutput(ctx.name, "example", headline={"tets": scenes[0].build().mesh.n_tets})
>>> spec = run.study
>>> spec.settings_for(quick=True), spec.scenes(spec.settings_for(quick=True))[0].label
(Tiny(n=2), 'cantilever')
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from springfem.errors import InputError

from .cache import CaseCache
from .scenes import StudyScene


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

    def table(self, df, stem: str, caption: str) -> Table:
        """Write ``df`` as ``<stem>.csv`` and ``<stem>.md`` here (:mod:`studies.tables`)."""
        from .tables import write_table

        return Table(write_table(df, self.path(stem)), caption)

    def figure(self, fig, filename: str, caption: str) -> Figure:
        """Save the matplotlib figure ``fig`` here as PNG (and close it)."""
        from .tables import save_figure

        return Figure(save_figure(fig, self.path(filename)), caption)


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
    """A registered study.

    Attributes
    ----------
    name
        Its name.
    run
        ``run(ctx, scenes, settings) -> StudyOutput``.
    settings
        Its settings dataclass (``full()``, ``quick()``).
    scenes
        ``scenes(settings)``: the bundled scenes of the report.
    source
        The study's source (a package folder or a module): part of its cache keys.
    user_scenes
        ``None`` when it runs on a user's scene (``--scene``), else why not.
    serial
        Its cases are timings measured alone: they run in this process even when the
        others run on workers.
    """

    name: str
    run: Callable[[StudyContext, list[StudyScene], Any], StudyOutput]
    settings: type
    scenes: Callable[[Any], list[StudyScene]]
    source: Path
    user_scenes: str | None = None
    serial: bool = False

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


def study(
    name: str,
    settings: type,
    scenes: Callable[[Any], list[StudyScene]],
    register: bool = True,
    user_scenes: str | None = None,
    serial: bool = False,
) -> Callable:
    """Register ``run(ctx, scenes, settings)`` as the study ``name``.

    Parameters
    ----------
    name
        The study's name (``springfem study NAME``; dashes and underscores are the same).
    settings
        Its settings dataclass, with classmethods ``full()`` and ``quick()``.
    scenes
        ``scenes(settings)``: the bundled scenes it runs on in the report.
    register
        Add it to :data:`REGISTRY` (``False``: only attach the :class:`Study`).
    user_scenes
        ``None`` if it runs on a user's scene, else the reason it cannot (one line).
    serial
        Run its cases in this process whatever the workers (timings measured alone).

    Returns
    -------
    callable
        A decorator returning the function unchanged, with a ``study`` attribute.
    """

    def decorate(fn: Callable) -> Callable:
        source = Path(inspect.getfile(fn))
        source = source.parent if source.name == "__init__.py" else source
        spec = Study(name, fn, settings, scenes, source, user_scenes, serial)
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
