"""Commands shown in the README and the manual, checked against the real parser.

Examples
--------
>>> parse_exit(["compare", "sag"])[0], parse_exit(["compare", "--no-such-option"])[0]
(0, 2)
"""

from __future__ import annotations

import contextlib
import importlib.util
import io
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[2]


def parse_exit(argv: list[str]) -> tuple[int, str]:
    """The exit code and output of parsing ``springfem ARGV`` (0: parsed; nothing runs)."""
    from studies.cli import build_parser

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            build_parser().parse_args(argv)
        except SystemExit as exc:
            return int(exc.code or 0), out.getvalue() + err.getvalue()
    return 0, out.getvalue() + err.getvalue()


def docs_extension() -> ModuleType:
    """The manual's Sphinx extension (``docs/_ext/springfem_docs.py``), imported by path."""
    spec = importlib.util.spec_from_file_location(
        "springfem_docs", ROOT / "docs" / "_ext" / "springfem_docs.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
