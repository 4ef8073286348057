"""Run registered studies (``springfem study NAME``) and the report (``springfem report``).

A study is a function ``run(ctx, scenes, settings) -> StudyOutput`` registered with
:func:`studies.registry.study`; importing its module registers it. It runs on its bundled
scenes or on the scenes it is given (a user's, ``--scene``). Each study writes CSV +
Markdown tables and PNG figures into ``<out>/<name>/`` and caches every finished case
(see :mod:`studies.cache`), so an interrupted report resumes where it stopped.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from springfem.files import atomic_write_text, folder_lock, remove_stale_temp_files
from springfem.files import jsonable as _jsonable

from .budget import Budget, skipped_finding, skipped_table
from .cache import CaseCache, source_fingerprint
from .html import static_markdown, write_index, write_output
from .registry import REGISTRY, StudyContext, StudyOutput, get_study
from .scenes import StudyScene

# Importing a study module registers it; the import order is the report's order.
# isort: off
from . import study_convergence  # noqa: F401, E402
from . import study_accuracy  # noqa: F401, E402
from . import study_volume_drift  # noqa: F401, E402
from . import study_anisotropy  # noqa: F401, E402
from . import study_stability  # noqa: F401, E402
from . import study_speed_accuracy  # noqa: F401, E402
from . import study_scaling  # noqa: F401, E402
from . import study_ablation  # noqa: F401, E402
from . import study_tissue  # noqa: F401, E402
from . import study_locking  # noqa: F401, E402
from . import study_frames  # noqa: F401, E402
from . import study_dynamics  # noqa: F401, E402
# isort: on


def run_study(
    name: str,
    out: str | Path = "reports",
    quick: bool = False,
    progress: bool = True,
    settings: object | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    scenes: list[StudyScene] | None = None,
    command: str | None = None,
    budget: Budget | None = None,
) -> StudyOutput:
    """Run one study and write its tables, figures and ``headline.json`` under ``out/<name>``.

    Parameters
    ----------
    name
        A registered study name (dashes or underscores).
    out
        The report folder; the case cache is ``out/.cache``.
    quick
        Use the quick preset (when ``settings`` is not given) and say so in the findings.
    progress
        Show a progress bar.
    settings
        The study's settings (default: its ``quick()`` or ``full()`` preset).
    workers, scheduler
        Run the cases on a local Dask cluster of ``workers`` processes or on the cluster of
        ``scheduler`` (default: in-process); see :mod:`studies.executor`.
    scenes
        The scenes (default: the study's bundled scenes for ``settings``).
    command
        The command that regenerates the run (for the HTML page; default the bundled
        study's).
    budget
        The whole study's time and the cap of each case (:class:`~studies.budget.Budget`;
        default none): the cases that do not fit are skipped and listed in
        ``skipped.csv`` and a finding.

    Returns
    -------
    StudyOutput
        Findings, tables, figures, headline numbers and the wall time.
    """
    spec = get_study(name)
    root = Path(out)
    import reference_fem
    import springfem
    import springmodel

    from .plugin_sources import plugin_sources

    here = Path(__file__).parent
    code = source_fingerprint(
        Path(springfem.__file__).parent,  # the core's solvers, meshes and loads shape results
        Path(springmodel.__file__).parent,
        Path(reference_fem.__file__).parent,
        spec.source,
        # the models, comparisons and metrics every study uses (a study module: its own)
        *sorted(f for f in here.glob("*.py") if not f.name.startswith("study_")),
        here / "scenes",
        *plugin_sources(),  # the plug-in models' packages (springfem.model_api)
    )
    if spec.serial and scheduler is None:
        workers = None  # its cases are timings, measured alone
    budget = budget if budget is not None else Budget()
    budget.start = time.monotonic()
    cache = CaseCache(root / ".cache", spec.name, code, workers, scheduler, budget,
                      quiet=not progress)  # fmt: skip
    ctx = StudyContext(spec.name, root / spec.name, quick, cache, progress)
    remove_stale_temp_files(ctx.out)  # tables/figures of a run killed mid-write
    t0 = time.perf_counter()
    settings = settings if settings is not None else spec.settings_for(quick)
    with folder_lock(root / ".cache" / spec.name, "study"):  # one writer per case folder
        try:
            result = spec.run(ctx, scenes if scenes is not None else spec.scenes(settings),
                              settings)  # fmt: skip
        finally:
            cache.print_warnings()  # each distinct line once, after the progress bars
    result.seconds = time.perf_counter() - t0
    if cache.skipped:
        result.tables.append(skipped_table(ctx, cache.skipped))
        result.findings.append(skipped_finding(cache.skipped, budget))
    atomic_write_text(
        ctx.path("headline.json"), json.dumps(_jsonable(result.headline), indent=2, sort_keys=True)
    )
    flag = " --quick" if quick else ""
    write_output(ctx.out, result, command or f"springfem study {spec.name.replace('_', '-')}{flag}")
    return result


def default_out(out: str | None, quick: bool) -> Path:
    """The report folder: ``out`` if given, else ``reports/`` (``reports/quick/`` for quick).

    Parameters
    ----------
    out
        The ``--out`` option (``None``: the default folder).
    quick
        The ``--quick`` flag.

    Returns
    -------
    Path

    Examples
    --------
    >>> default_out(None, quick=True).as_posix()
    'reports/quick'
    >>> default_out("elsewhere", quick=True).as_posix()
    'elsewhere'
    """
    return Path(out) if out else Path("reports") / ("quick" if quick else "")


def _rel(path: Path, root: Path) -> str:
    try:
        return str(Path(path).resolve().relative_to(root.resolve()))
    except ValueError:
        return str(path)


def write_report(outputs: list[StudyOutput], root: Path, quick: bool) -> Path:
    """Assemble ``REPORT.md`` and the headline JSON from the studies' outputs.

    Parameters
    ----------
    outputs
        The studies' outputs, in report order.
    root
        The report folder (tables and figures are linked relative to it).
    quick
        The quick preset (names the regenerating command and ``headline-quick.json``).

    Returns
    -------
    Path
        The path of ``REPORT.md``.
    """
    flag = " --quick" if quick else ""
    lines = [
        "# springfem report: the spring model against FEM on the same meshes",
        "",
        f"Generated by `springfem report{flag}` on one 2-core machine; every table and figure "
        "below names the command that regenerates it. Times are medians of repeated runs "
        "where stated, and speeds are compared as ratios measured in one run.",
        "",
        "## Summary of findings",
        "",
    ]
    for o in outputs:
        for f in o.findings[:3]:
            lines.append(f"- **{o.title}**: {f}")
    for o in outputs:
        lines += [
            "",
            f"## {o.title}",
            "",
            f"Regenerate: `springfem study {o.name.replace('_', '-')}{flag}` ({o.seconds:.0f} s).",
            "",
        ]
        for f in o.findings:
            lines.append(f"- {f}")
        for t in o.tables:
            lines += ["", f"**Table.** {t.caption} (`{_rel(t.path, root)}`, CSV beside it)", ""]
            lines.append(Path(t.path).read_text().rstrip())
        for fig in o.figures:
            lines += ["", f"![{o.name}]({_rel(fig.path, root)})", "", f"*Figure.* {fig.caption}"]
    lines += static_markdown(root)  # e.g. the scale benchmark's, when reports/scale/ holds it
    path = root / "REPORT.md"
    atomic_write_text(path, "\n".join(lines) + "\n")
    headline = {o.name: o.headline for o in outputs}
    atomic_write_text(
        root / ("headline-quick.json" if quick else "headline.json"),
        json.dumps(_jsonable(headline), indent=2, sort_keys=True) + "\n",
    )
    write_index(root, "springfem report: the spring model against FEM on the same meshes",
                f"Generated by springfem report{flag}; REPORT.md beside this page holds the "
                "same text.")  # fmt: skip
    return path


def run_report(
    out: str | Path = "reports",
    quick: bool = False,
    names: tuple[str, ...] | None = None,
    workers: int | None = None,
) -> list[StudyOutput]:
    """Run the studies (default: all registered, in report order) and write ``REPORT.md``.

    Parameters
    ----------
    out
        The report folder.
    quick
        The quick preset of every study.
    names
        Only these studies.
    workers
        Run each study's cases on a local Dask cluster of this many processes (0: one per
        core; the studies share it); ``None``: in-process.

    Returns
    -------
    list of StudyOutput
        One per study, in the order run.
    """
    outputs = []
    for name in names or tuple(REGISTRY):
        print(f"study {name} …", flush=True)
        outputs.append(run_study(name, out, quick, workers=workers))
        print(study_time_line(outputs[-1]), flush=True)
    write_report(outputs, Path(out), quick)
    return outputs


def study_time_line(output: StudyOutput) -> str:
    """The line the report prints after each study: its wall time and the machine's load
    (a shared machine's load stretches every time: read them together).

    Examples
    --------
    >>> o = StudyOutput(name="locking", title="t", findings=[], tables=[], figures=[])
    >>> o.seconds = 12.3
    >>> study_time_line(o).startswith("study locking: 12 s (load average ")
    True
    """
    import os

    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    return f"study {output.name}: {output.seconds:.0f} s (load average {load})"
