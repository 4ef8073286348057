"""The README stays short, and every command it shows is one the command line accepts.

Each ``springfem ...`` line of the README's shell blocks, and each inline ```springfem ...```,
is parsed by the real parser, as it stands and with ``--help`` appended: a misspelt
subcommand, an option that no longer exists or a value the option refuses exits 2 instead
of giving the parsed arguments or printing the help (exit 0). The ``make`` targets it names
must be targets of the Makefile.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest
from support.commands import parse_exit

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
#: The README is the five-minute page; everything else lives in docs/.
MAX_LINES = 150


def shown_commands(text: str, program: str) -> list[str]:
    """The ``program ...`` commands of ``text``: lines of its sh/console blocks (comments cut)
    and inline code spans.

    Examples
    --------
    >>> shown_commands("Run `make demo`.\\n```sh\\nmake test   # all\\n```\\n", "make")
    ['make test', 'make demo']
    """
    out = []
    for block in re.findall(r"```(?:sh|console|bash)\n(.*?)```", text, re.S):
        for line in block.splitlines():
            line = line.split(" #", 1)[0].strip().removeprefix("$ ")
            if line.startswith(program + " ") or line == program:
                out.append(line)
    for span in re.findall(r"(?<!`)`([^`\n]+)`(?!`)", text):
        if span.startswith(program + " ") and span not in out:
            out.append(span)
    return out


def test_the_readme_is_at_most_150_lines():
    n = len(README.read_text(encoding="utf-8").splitlines())
    assert n <= MAX_LINES, f"README.md has {n} lines; move the detail into docs/"


COMMANDS = shown_commands(README.read_text(encoding="utf-8"), "springfem")


def test_the_readme_shows_the_three_kinds_of_example():
    kinds = {c.split()[1] for c in COMMANDS}
    assert {"compare", "verdict", "study", "inspect"} <= kinds
    assert any("--scene" in c for c in COMMANDS if c.split()[1] == "study")


@pytest.mark.parametrize("command", COMMANDS)
def test_every_command_the_readme_shows_parses(command):
    argv = shlex.split(command)[1:]
    code, output = parse_exit(argv)
    assert code == 0, f"{command!r} does not parse: {output.strip()}"
    code, output = parse_exit([*argv, "--help"])
    assert code == 0 and "usage: springfem" in output, f"{command!r} --help: {output.strip()}"


def test_the_check_catches_a_wrong_command():
    # the check above can fail: an unknown option and a refused value exit 2
    assert parse_exit(["compare", "sag", "--no-such-option"])[0] == 2
    assert parse_exit(["verdict", "sag", "--tolerance", "-1"])[0] == 2
    assert parse_exit(["no-such-command", "--help"])[0] == 2


def test_the_make_targets_the_readme_names_exist():
    makefile = (ROOT / "Makefile").read_text(encoding="utf-8")
    targets = set(re.findall(r"^([\w-]+):", makefile, re.M))
    named = {c.split()[1] for c in shown_commands(README.read_text(encoding="utf-8"), "make")}
    assert {"demo", "test"} <= named
    assert named <= targets
