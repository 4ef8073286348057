"""The tutorial's commands: all of them run, by the docs build, and here.

docs/tutorial.rst shows its commands in ``tutorial-run`` blocks, which the docs build runs
(``docs/_ext/springfem_docs.py``; a failing one fails ``make docs``). The fast tests check
that no command on the page escapes those blocks and that every ``springfem`` command on
it, run or only mentioned, parses; the slow one runs the page's commands in a fresh folder
the way the build does and checks the files the page shows exist.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest
from support.commands import docs_extension, parse_exit

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "tutorial.rst"
ext = docs_extension()
TEXT = PAGE.read_text(encoding="utf-8")
COMMANDS = ext.page_commands(TEXT)


def test_the_tutorial_runs_the_whole_path():
    kinds = [shlex.split(c)[:2] for c in COMMANDS]
    assert ["python", "organ_mesh.py"] in kinds
    assert {"inspect", "verdict", "study"} <= {k[1] for k in kinds if k[0] == "springfem"}
    assert any("--scene" in c for c in COMMANDS if c.startswith("springfem study"))


def test_every_dollar_line_is_in_a_block_the_build_runs():
    dollar = [ln.strip()[2:] for ln in TEXT.splitlines() if ln.strip().startswith("$ ")]
    assert dollar == COMMANDS


def test_the_page_has_no_other_console_blocks():
    # a console or shell block, or a literal block of commands, would show commands the
    # build does not run
    assert not re.search(r"^\.\. code-block:: (console|sh|bash|shell)", TEXT, re.M)
    lines = TEXT.splitlines()
    for n, line in enumerate(lines):
        if line.rstrip().endswith("::") and not line.startswith(".. tutorial-run::"):
            following = [ln for ln in lines[n + 1 :] if ln.strip()][:1]
            assert not following or not following[0].strip().startswith("$"), line


RUN = [c for c in COMMANDS if c.startswith("springfem ")]
#: Commands the prose names (``springfem verdict``, or a whole command to try next).
MENTIONED = re.findall(r"``(springfem [^`]+)``", TEXT)


@pytest.mark.parametrize("command", RUN)
def test_every_springfem_command_the_page_runs_parses(command):
    code, output = parse_exit(shlex.split(command)[1:])
    assert code == 0, f"{command!r}: {output.strip()}"


@pytest.mark.parametrize("command", MENTIONED)
def test_every_springfem_command_the_page_names_parses_with_help(command):
    code, output = parse_exit([*shlex.split(command)[1:], "--help"])
    assert code == 0 and "usage: springfem" in output, f"{command!r}: {output.strip()}"


def test_the_pictures_are_files_of_the_run():
    images = re.findall(r"^\.\. image:: (\S+)", TEXT, re.M)
    assert images, "the tutorial shows no picture"
    assert all(i.startswith("_build/tutorial/") for i in images)


@pytest.mark.slow
def test_the_tutorial_commands_run(tmp_path):
    folder = ext.lay_tutorial_folder(tmp_path / "tutorial")
    for command in COMMANDS:
        proc = ext.run_command(command, folder)
        assert proc.returncode == 0, f"{command}: {proc.stdout[-2000:]}"
    for image in re.findall(r"^\.\. image:: _build/tutorial/(\S+)", TEXT, re.M):
        assert (folder / image).stat().st_size > 10_000, image
    assert "hilum" in ext.run_command("springfem inspect organ.toml", folder).stdout
