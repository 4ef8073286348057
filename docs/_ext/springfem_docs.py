"""Sphinx directives of the springfem manual: references generated from the code, and a
tutorial whose commands the build runs.

- ``.. springfem-cli::`` writes the command-line reference from the argparse parsers
  (:func:`studies.cli.build_parser`): one section per command, its usage, and a table of
  every argument with its value, default and help (:func:`cli_reference_rst`).
- ``.. springfem-scene-keys::`` writes the scene-file tables of
  :func:`springfem.scene.reference.reference_rst`.
- ``.. tutorial-run::`` runs each ``$ command`` line of its content in the tutorial's
  working folder (``docs/_build/tutorial``, laid anew from ``docs/tutorial/`` at every
  build) and shows the commands with the end of their output. A command that fails (an
  exit code other than ``:returncode:``, 0 by default) is a build warning, which ``make
  docs`` (``-W``) turns into a failed build; the page's figures are files that run wrote.
  The tutorial page is read again at every build, so its commands always run.

The functions are plain Python so that ``tests/test_docs_reference.py`` and
``tests/test_tutorial.py`` use them without Sphinx.
"""

from __future__ import annotations

import argparse
import os
import re
import shlex
import shutil
import subprocess
import sys
import time
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1]
ROOT = DOCS.parent
#: Where the tutorial runs, and the files laid there before it does.
TUTORIAL_DIR = DOCS / "_build" / "tutorial"
TUTORIAL_FILES = DOCS / "tutorial"
#: The page whose ``tutorial-run`` blocks share that folder.
TUTORIAL_PAGE = "tutorial"
#: A tutorial command that runs longer than this is a failure.
COMMAND_TIMEOUT = 600


# -- the command-line reference -------------------------------------------------------------


def subcommands(parser: argparse.ArgumentParser) -> dict[str, tuple[str, argparse.ArgumentParser]]:
    """``name -> (help, parser)`` of each subcommand of ``parser``, in the parser's order."""
    out: dict[str, tuple[str, argparse.ArgumentParser]] = {}
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {a.dest: a.help or "" for a in action._choices_actions}
            for name, sub in action.choices.items():
                out[name] = (helps.get(name, ""), sub)
    return out


def _value(action: argparse.Action) -> str:
    if action.nargs == 0:
        return ""
    if action.choices is not None and not isinstance(action, argparse._SubParsersAction):
        text = " | ".join(f"``{c}``" for c in action.choices)
    else:
        metavar = action.metavar or (action.dest.upper() if action.option_strings else action.dest)
        text = f"``{metavar}``"
    if action.nargs == "?":
        text = f"[{text}]"
    return text


def _default(action: argparse.Action) -> str:
    d = action.default
    if d is None or d is False or d is argparse.SUPPRESS or action.nargs == 0:
        return ""
    return f"``{d}``"


#: An option named in a help text (``--set``), shown as code, not typeset (``--`` → "–").
_OPTION_IN_TEXT = re.compile(r"(?<![\w-])(--?[A-Za-z][\w-]*)")


def _rst_text(text: str) -> str:
    """Help text as reStructuredText: ``*`` and backquotes escaped, ``%%`` unformatted,
    option names as code.

    Examples
    --------
    >>> _rst_text("override, e.g. --set a=1 (100%% *bold*)")
    'override, e.g. ``--set`` a=1 (100% \\\\*bold\\\\*)'
    """
    text = text.replace("\\", "\\\\").replace("*", "\\*").replace("`", "\\`").replace("%%", "%")
    return _OPTION_IN_TEXT.sub(r"``\1``", text)


def _rows(parser: argparse.ArgumentParser) -> list[list[str]]:
    rows = []
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction):
            continue
        if isinstance(action, argparse._SubParsersAction):
            continue
        names = ", ".join(f"``{o}``" for o in action.option_strings) or f"``{action.dest}``"
        rows.append([names, _value(action), _default(action), _rst_text(action.help or "")])
    return rows


def _table(rows: list[list[str]]) -> list[str]:
    lines = [".. list-table::", "   :header-rows: 1", "   :widths: 22 22 12 44", ""]
    for row in [["argument", "value", "default", "meaning"], *rows]:
        lines.append(f"   * - {row[0]}")
        lines += [f"     - {cell}" for cell in row[1:]]
    return lines


def _usage(parser: argparse.ArgumentParser) -> list[str]:
    usage = parser.format_usage().removeprefix("usage: ").rstrip()
    return ["::", "", *("   " + line for line in usage.splitlines()), ""]


def _study_list() -> list[str]:
    """The registered studies, as ``springfem study --help`` lists them."""
    import inspect

    from studies.cli import _first_line
    from studies.runner import REGISTRY

    lines = ["The studies (``*``: also runs on ``--scene FILE``):", ""]
    for name, spec in REGISTRY.items():
        doc = _rst_text(_first_line(inspect.getmodule(spec.run).__doc__))
        mark = " (``*``)" if spec.user_scenes is None else ""
        lines.append(f"- ``{name.replace('_', '-')}``{mark}: {doc}")
    return [*lines, ""]


def cli_reference_rst(parser: argparse.ArgumentParser | None = None) -> str:
    """The command-line reference of ``parser`` (default: the ``springfem`` command).

    Parameters
    ----------
    parser
        An argparse parser with subcommands.

    Returns
    -------
    str
        reStructuredText: the global options, then one section per subcommand titled
        ````springfem NAME````.
    """
    if parser is None:
        from studies.cli import build_parser

        parser = build_parser()
    prog = parser.prog
    lines = [*_usage(parser), "Options of every command:", "", *_table(_rows(parser)), ""]
    for name, (help_text, sub) in subcommands(parser).items():
        title = f"``{prog} {name}``"
        lines += [f".. _cli-{name}:", "", title, "-" * len(title), ""]
        if help_text:
            lines += [_rst_text(help_text[0].upper() + help_text[1:]) + ".", ""]
        lines += _usage(sub)
        lines += _table(_rows(sub))
        lines.append("")
        if name == "study":
            lines += _study_list()
    return "\n".join(lines)


# -- the tutorial ---------------------------------------------------------------------------


def tutorial_env() -> dict[str, str]:
    """The environment of the tutorial's commands: headless, one BLAS thread, the
    checkout's packages first."""
    env = dict(os.environ)
    env.update(PYVISTA_OFF_SCREEN="true", MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1")
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    return env


def lay_tutorial_folder(folder: Path = TUTORIAL_DIR) -> Path:
    """Empty ``folder`` and copy the tutorial's input files (``docs/tutorial/``) into it."""
    if folder.exists():
        shutil.rmtree(folder)
    shutil.copytree(TUTORIAL_FILES, folder, ignore=shutil.ignore_patterns("__pycache__"))
    return folder


def command_argv(command: str) -> list[str]:
    """The argv of a tutorial command: ``springfem`` and ``python`` are this interpreter's.

    Examples
    --------
    >>> command_argv("springfem verdict organ.toml")[1:]
    ['-m', 'studies.cli', 'verdict', 'organ.toml']
    """
    argv = shlex.split(command)
    if argv[0] == "springfem":
        return [sys.executable, "-m", "studies.cli", *argv[1:]]
    if argv[0] == "python":
        return [sys.executable, *argv[1:]]
    return argv


def run_command(command: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """Run one tutorial command in ``cwd``; stdout and stderr together."""
    return subprocess.run(
        command_argv(command),
        cwd=cwd,
        env=tutorial_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        timeout=COMMAND_TIMEOUT,
        check=False,
    )


def page_commands(text: str) -> list[str]:
    """The ``$ command`` lines of the ``tutorial-run`` blocks of a page's source.

    Examples
    --------
    >>> page_commands(".. tutorial-run::\\n\\n   $ springfem inspect organ.toml\\n\\nText.\\n")
    ['springfem inspect organ.toml']
    """
    out, inside = [], False
    for line in text.splitlines():
        if line.startswith(".. "):
            inside = line.strip() == ".. tutorial-run::"
        elif inside and line.strip().startswith("$ "):
            out.append(line.strip()[2:])
        elif inside and line.strip() and not line.startswith(" "):
            inside = False
    return out


#: A progress bar's line (tqdm): not output worth showing.
_PROGRESS = re.compile(r"\d+%\|")


def _shown(output: str, lines: int) -> list[str]:
    """The last ``lines`` lines of a command's output, without blank lines and progress bars."""
    kept = [ln.rstrip() for ln in output.splitlines() if ln.strip() and not _PROGRESS.search(ln)]
    if lines == 0:
        return []
    if len(kept) > lines:
        return ["...", *kept[-lines:]]
    return kept


# -- Sphinx ---------------------------------------------------------------------------------


def setup(app):  # pragma: no cover - exercised by the docs build
    from docutils import nodes
    from docutils.parsers.rst import directives
    from docutils.statemachine import StringList
    from sphinx.util import logging
    from sphinx.util.docutils import SphinxDirective
    from sphinx.util.nodes import nested_parse_with_titles

    logger = logging.getLogger(__name__)

    class _Generated(SphinxDirective):
        def generated(self) -> str:
            raise NotImplementedError

        def run(self):
            node = nodes.section()
            node.document = self.state.document
            text = StringList(self.generated().splitlines(), source="(generated)")
            nested_parse_with_titles(self.state, text, node)
            return node.children

    class CliReference(_Generated):
        def generated(self) -> str:
            return cli_reference_rst()

    class SceneKeys(_Generated):
        def generated(self) -> str:
            from springfem.scene.reference import reference_rst

            return reference_rst()

    class TutorialRun(SphinxDirective):
        has_content = True
        option_spec = {
            "lines": directives.nonnegative_int,
            "returncode": int,
        }

        def run(self):
            shown: list[str] = []
            lines = self.options.get("lines", 12)
            expected = self.options.get("returncode", 0)
            for raw in self.content:
                line = raw.strip()
                if not line:
                    continue
                if not line.startswith("$ "):
                    logger.warning(f"tutorial-run: not a '$ command' line: {line!r}",
                                   location=self.get_location())  # fmt: skip
                    continue
                command = line[2:]
                t0 = time.perf_counter()
                try:
                    proc = run_command(command, TUTORIAL_DIR)
                    code, output = proc.returncode, proc.stdout
                except subprocess.TimeoutExpired:
                    code, output = -1, f"timed out after {COMMAND_TIMEOUT} s"
                seconds = time.perf_counter() - t0
                logger.info(f"tutorial: {command} -> {code} ({seconds:.1f} s)")
                if code != expected:
                    tail = "\n".join(output.splitlines()[-15:])
                    logger.warning(f"tutorial command failed (exit {code}): {command}\n{tail}",
                                   location=self.get_location())  # fmt: skip
                shown += [f"$ {command}", *_shown(output, lines)]
            text = "\n".join(shown)
            block = nodes.literal_block(text, text)
            block["language"] = "console"
            return [block]

    def builder_inited(app):
        lay_tutorial_folder()

    def always_read_tutorial(app, env, added, changed, removed):
        return [TUTORIAL_PAGE] if TUTORIAL_PAGE in env.found_docs else []

    app.add_directive("springfem-cli", CliReference)
    app.add_directive("springfem-scene-keys", SceneKeys)
    app.add_directive("tutorial-run", TutorialRun)
    app.connect("builder-inited", builder_inited)
    app.connect("env-get-outdated", always_read_tutorial)
    return {"version": "1", "parallel_read_safe": False, "parallel_write_safe": True}
