"""References to the manual name existing sections: ``docs/<page>.rst#<label>`` in the source.

Comments and docstrings point at the theory manual as ``docs/theory.rst#some-label``. Each
label is an explicit reStructuredText target (``.. _some-label:``) placed right above a
section title of that page, which is also the section's anchor in the built HTML. This test
parses the pages themselves (it needs neither Sphinx nor the ``docs`` extra) and checks that
every such reference in the repository names a page that exists and a label of that page,
and that every label heads a section and is unique. It skips when ``docs/`` is absent.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
#: ``docs/<page>.rst`` with an optional ``#<label>``.
REFERENCE = re.compile(r"docs/((?:[\w-]+/)*[\w-]+\.rst)(?:#([\w-]+))?")
LABEL = re.compile(r"^\.\. _([\w-]+):\s*$")
#: Folders never searched for references (environments, caches, build output).
SKIP_DIRS = {".git", ".venv", "_build", "__pycache__", ".pytest_cache", ".ruff_cache", "out"}
SOURCE_SUFFIXES = {".py", ".md", ".rst", ".toml", ".txt", ".cfg"}

pytestmark = pytest.mark.skipif(not DOCS.is_dir(), reason="no docs/ folder in this checkout")


def _is_underline(line: str, title: str) -> bool:
    s = line.rstrip()
    return bool(s) and len(set(s)) == 1 and s[0] in "=-~^\"'`#*+.:_" and len(s) >= len(title)


def section_labels(page: Path) -> dict[str, int]:
    """Explicit labels of ``page`` that head a section title, with their line numbers.

    Parameters
    ----------
    page
        A reStructuredText file.

    Returns
    -------
    dict
        ``label -> line number`` (1-based).

    Raises
    ------
    AssertionError
        If a label is not followed (after blank lines) by a title and its underline.
    """
    lines = page.read_text(encoding="utf-8").splitlines()
    labels: dict[str, int] = {}
    for n, line in enumerate(lines):
        m = LABEL.match(line)
        if not m:
            continue
        k = n + 1
        while k < len(lines) and not lines[k].strip():
            k += 1
        title = lines[k].strip() if k < len(lines) else ""
        under = lines[k + 1] if k + 1 < len(lines) else ""
        heads = bool(title) and not LABEL.match(lines[k]) and _is_underline(under, title)
        assert heads, f"{page.name}:{n + 1}: label {m[1]!r} heads no section"
        labels[m[1]] = n + 1
    return labels


def references(text: str) -> list[tuple[str, str | None]]:
    """The ``(page, label)`` pairs of the manual references in ``text``.

    Parameters
    ----------
    text
        Source text.

    Returns
    -------
    list of tuple
        ``("theory.rst", "the-spring-element-is-a-p1-element")``; ``label`` is ``None`` for
        a reference to a whole page.
    """
    return [(m[1], m[2]) for m in REFERENCE.finditer(text)]


def broken(refs: list[tuple[str, str | None]], labels: dict[str, dict[str, int]]) -> list[str]:
    """The references of ``refs`` whose page or label does not exist.

    Parameters
    ----------
    refs
        ``(page, label)`` pairs.
    labels
        Page path relative to ``docs/`` -> its labels.

    Returns
    -------
    list of str
        ``docs/page.rst#label`` of each broken reference.
    """
    bad = []
    for page, label in refs:
        if page not in labels or (label is not None and label not in labels[page]):
            bad.append(f"docs/{page}" + (f"#{label}" if label else ""))
    return bad


def _pages() -> dict[str, dict[str, int]]:
    return {
        p.relative_to(DOCS).as_posix(): section_labels(p)
        for p in sorted(DOCS.rglob("*.rst"))
        if "_build" not in p.parts
    }


def _source_files():
    """The repository's text files, without this file (whose examples are made up)."""
    for folder, dirs, files in os.walk(ROOT):
        dirs[:] = [d for d in dirs if d not in SKIP_DIRS and not d.endswith(".egg-info")]
        for name in files:
            path = Path(folder) / name
            if path.suffix in SOURCE_SUFFIXES and path != Path(__file__).resolve():
                yield path


def test_every_label_heads_a_section_and_is_unique():
    seen: dict[str, str] = {}
    for page, labels in _pages().items():
        for label in labels:
            assert label not in seen, f"label {label!r} in {page} and {seen[label]}"
            seen[label] = page
    # the manual's central sections are there under their documented labels
    assert {"the-spring-element-is-a-p1-element", "where-the-specification-is-wrong-or-open",
            "volumetric-treatments-and-locking", "verification"} <= set(seen)  # fmt: skip


def test_every_manual_reference_in_the_source_names_an_existing_section():
    labels = _pages()
    bad = []
    for path in _source_files():
        text = path.read_text(encoding="utf-8", errors="replace")
        bad += [f"{path.relative_to(ROOT)}: {b}" for b in broken(references(text), labels)]
    assert not bad, "references to missing manual sections:\n" + "\n".join(bad)


def test_the_checker_catches_a_wrong_label_and_a_wrong_page():
    # the test above can fail: a misspelt label and a missing page are both reported
    labels = _pages()
    text = (
        "see docs/theory.rst#the-spring-element-is-a-p1-element, "
        "docs/theory.rst#the-spring-element-is-a-p2-element and docs/nosuchpage.rst#x"
    )
    assert broken(references(text), labels) == [
        "docs/theory.rst#the-spring-element-is-a-p2-element",
        "docs/nosuchpage.rst#x",
    ]


def test_a_label_that_heads_no_section_is_rejected(tmp_path):
    page = tmp_path / "page.rst"
    page.write_text(".. _good:\n\nTitle\n=====\n\ntext\n\n.. _dangling:\n\njust a paragraph\n")
    with pytest.raises(AssertionError, match="dangling"):
        section_labels(page)
