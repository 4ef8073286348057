"""The manual's command-line reference lists every argument of every command.

The reference (docs/cli.rst) is generated at build time by ``docs/_ext/springfem_docs.py``
from :func:`studies.cli.build_parser`. Checked independently of that generator's walk over
the parsers: every option string that argparse itself prints in a command's ``--help``
must appear in that command's section of the generated text, and every subcommand has a
section. The check is shown to fail on a parser that gained an option the reference text
lacks.
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest
from support.commands import docs_extension

from studies.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]
springfem_docs = docs_extension()

OPTION = re.compile(r"(?<![\w`-])(--?[A-Za-z][\w-]*)")


def help_options(parser: argparse.ArgumentParser) -> set[str]:
    """The option strings argparse prints in ``parser``'s help."""
    return set(OPTION.findall(parser.format_help())) - {"-h", "--help"}


def sections(text: str) -> dict[str, str]:
    """``command -> its section`` of the generated reference (titled ````springfem NAME````);
    ``""`` is the text before the first command (the global options)."""
    parts = re.split(r"^``springfem ([\w-]+)``\n-+\n", text, flags=re.M)
    out = {"": parts[0]}
    out.update(dict(zip(parts[1::2], parts[2::2])))
    return out


def missing(parser: argparse.ArgumentParser, text: str) -> list[str]:
    """``command option`` of each option in a command's help but not in its section."""
    secs = sections(text)
    bad = [f"springfem {o}" for o in help_options(parser) if f"``{o}``" not in secs[""]]
    for name, (_, sub) in springfem_docs.subcommands(parser).items():
        if name not in secs:
            bad.append(f"springfem {name} (no section)")
            continue
        bad += [f"springfem {name} {o}" for o in sorted(help_options(sub))
                if f"``{o}``" not in secs[name]]  # fmt: skip
    return bad


@pytest.fixture(scope="module")
def reference() -> str:
    return springfem_docs.cli_reference_rst(build_parser())


def test_the_manual_generates_the_reference():
    assert ".. springfem-cli::" in (ROOT / "docs" / "cli.rst").read_text(encoding="utf-8")


def test_every_option_of_every_command_is_in_the_reference(reference):
    assert missing(build_parser(), reference) == []


def test_every_command_and_positional_argument_has_its_place(reference):
    secs = sections(reference)
    parser = build_parser()
    subs = springfem_docs.subcommands(parser)
    assert {"inspect", "solve", "compare", "verdict", "study", "sweep", "report", "bench"} <= set(
        subs
    )
    for name, (_, sub) in subs.items():
        for action in sub._actions:
            if not action.option_strings:
                assert f"``{action.dest}``" in secs[name], (name, action.dest)
    # the study section lists the registered studies, as `springfem study --help` does
    assert "``locking``" in secs["study"] and "``ablation``" in secs["study"]


def test_a_parser_that_gains_an_option_fails_the_check(reference):
    parser = build_parser()
    sub = springfem_docs.subcommands(parser)["verdict"][1]
    sub.add_argument("--brand-new", type=float, help="an option the reference has not seen")
    assert missing(parser, reference) == ["springfem verdict --brand-new"]
    # and regenerating the reference from that parser takes it in
    assert missing(parser, springfem_docs.cli_reference_rst(parser)) == []


def test_ci_builds_the_manual_with_warnings_as_errors_after_the_tests():
    import tomllib

    run = (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()
    steps = [ln.strip() for ln in run if ln.strip().startswith(("make ", "if ! make "))]
    assert steps.index("make test") < next(i for i, s in enumerate(steps) if "make docs" in s)
    makefile = (ROOT / "Makefile").read_text(encoding="utf-8")
    (docs_recipe,) = re.findall(r"^docs:.*\n\t(.*)", makefile, re.M)
    assert "sphinx -W" in docs_recipe
    # every extension the manual loads comes with Sphinx, from docs/_ext, or from the extra
    extra = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"][
        "optional-dependencies"
    ]["docs"]
    names = {re.split(r"[<>=\[ ]", r)[0].lower() for r in extra}
    conf = (ROOT / "docs" / "conf.py").read_text(encoding="utf-8")
    loaded = re.findall(r'^\s+"([\w.]+)",$', conf.split("extensions = [")[1].split("]")[0], re.M)
    for ext in loaded:
        top = ext.split(".")[0]
        local = (ROOT / "docs" / "_ext" / f"{top}.py").exists()
        assert top == "sphinx" or local or top in names, ext
