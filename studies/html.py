"""A browsable report: ``index.html`` beside ``REPORT.md``, self-contained and offline.

Every study run writes ``<root>/<study>/output.json`` (its title, findings, tables, figures,
the command that regenerates it: :func:`write_output`); :func:`write_index` reads every
such file under a report folder and writes one ``index.html`` for all of them, in the
registry's order. The page holds everything it shows: the CSS inline, each figure embedded
as a PNG data URI, each table read from its CSV, so it opens offline, copied anywhere.

Examples
--------
>>> import tempfile
>>> from pathlib import Path
>>> root = Path(tempfile.mkdtemp())
>>> out = StudyOutput("demo", "A demo study", findings=["It works."], headline={"x": 1.0})
>>> _ = write_output(root / "demo", out, "springfem study demo")
>>> page = write_index(root, "Demo report")
>>> "It works." in page.read_text(), page.name
(True, 'index.html')
"""

from __future__ import annotations

import base64
import html
import json
from pathlib import Path

import pandas as pd

from springfem.files import atomic_write_text
from springfem.files import jsonable as _jsonable

from .registry import REGISTRY, StudyOutput

#: The study's summary file, read by :func:`write_index`.
OUTPUT_FILE = "output.json"

CSS = """
body { font-family: system-ui, sans-serif; max-width: 72rem; margin: 2rem auto;
       padding: 0 1rem; line-height: 1.45; color: #222; }
h1 { font-size: 1.6rem; } h2 { font-size: 1.25rem; border-bottom: 1px solid #ccc;
     margin-top: 2.5rem; }
code { background: #f4f4f4; padding: 0 .25rem; }
nav ul { columns: 2; margin: .3rem 0; } nav h2 { margin-top: 1rem; }
.summary li { margin: .1rem 0; } .caption { font-size: .9rem; color: #444; margin: .3rem 0 1.2rem; }
table { border-collapse: collapse; font-size: .8rem; margin: .5rem 0; display: block;
        overflow-x: auto; max-width: 100%; }
th, td { border: 1px solid #ddd; padding: .15rem .4rem; text-align: right;
         white-space: nowrap; }
th { background: #f0f0f0; } tr:nth-child(even) td { background: #fafafa; }
img { max-width: 100%; height: auto; border: 1px solid #eee; }
.headline td:first-child, .headline th:first-child { text-align: left; }
"""


def write_output(folder: Path, out: StudyOutput, command: str) -> Path:
    """Write a study's ``output.json``: what :func:`write_index` shows of it.

    Parameters
    ----------
    folder
        The study's folder (its tables and figures are named relative to it).
    out
        The study's output.
    command
        The command that regenerates it.

    Returns
    -------
    Path
    """
    folder.mkdir(parents=True, exist_ok=True)

    def rel(p: Path) -> str:
        p = Path(p)
        try:
            return str(p.resolve().relative_to(folder.resolve()))
        except ValueError:
            return str(p)

    data = {
        "name": out.name,
        "title": out.title,
        "command": command,
        "seconds": out.seconds,
        "findings": out.findings,
        "tables": [{"path": rel(t.path), "caption": t.caption} for t in out.tables],
        "figures": [{"path": rel(f.path), "caption": f.caption} for f in out.figures],
        "headline": _jsonable(out.headline),
    }
    path = folder / OUTPUT_FILE
    atomic_write_text(path, json.dumps(data, indent=1, sort_keys=True))
    return path


def read_outputs(root: Path) -> list[tuple[Path, dict]]:
    """The study summaries under ``root``: ``(folder, output.json)``, in registry order.

    Parameters
    ----------
    root
        A report folder.

    Returns
    -------
    list of tuple
    """
    found = []
    for f in sorted(Path(root).glob(f"*/{OUTPUT_FILE}")):
        try:
            found.append((f.parent, json.loads(f.read_text(encoding="utf-8"))))
        except (OSError, ValueError):  # a damaged summary: that study is left out
            continue
    order = {name: i for i, name in enumerate(REGISTRY)}
    return sorted(found, key=lambda x: (order.get(x[1].get("name"), len(order)), x[0].name))


#: Sections of a report folder that a command other than ``springfem report`` writes
#: (``springfem bench scale`` into ``reports/scale/``): the report shows them as they are when
#: they are there, and never re-runs them (they take too long).
STATIC_SECTIONS = ("scale",)


def static_markdown(root: Path) -> list[str]:
    """The Markdown lines of the :data:`STATIC_SECTIONS` found under ``root``: title, the
    command that regenerates it, findings, tables (their ``.md``) and figures, with paths
    relative to ``root``. The HTML page shows them as any study (:func:`read_outputs`).

    Parameters
    ----------
    root
        A report folder.

    Returns
    -------
    list of str
    """
    lines: list[str] = []
    for name in STATIC_SECTIONS:
        try:
            d = json.loads((Path(root) / name / OUTPUT_FILE).read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        lines += ["", f"## {d['title']}", "",
                  f"Regenerate: `{d['command']}` ({d.get('seconds', 0):.0f} s; "
                  "`springfem report` shows this section as written, it does not re-run it).",
                  ""]  # fmt: skip
        lines += [f"- {f}" for f in d.get("findings", [])]
        for t in d.get("tables", []):
            md = Path(root) / name / t["path"]
            try:
                body = md.read_text(encoding="utf-8").rstrip()
            except OSError:
                body = f"*table {t['path']} is missing*"
            lines += ["", f"**Table.** {t['caption']} (`{name}/{t['path']}`, CSV beside it)", "",
                      body]  # fmt: skip
        for f in d.get("figures", []):
            lines += ["", f"![{name}]({name}/{f['path']})", "", f"*Figure.* {f['caption']}"]
    return lines


def _table_html(folder: Path, table: dict) -> str:
    csv = (folder / table["path"]).with_suffix(".csv")
    try:
        df = pd.read_csv(csv)
    except (OSError, ValueError, pd.errors.EmptyDataError):
        return f"<p><em>table {html.escape(table['path'])} is missing</em></p>"
    body = df.to_html(index=False, na_rep="", float_format=lambda v: f"{v:.4g}", border=0)
    return body + f'<p class="caption">{html.escape(table["caption"])}</p>'


def _figure_html(folder: Path, figure: dict) -> str:
    png = folder / figure["path"]
    try:
        data = base64.b64encode(png.read_bytes()).decode("ascii")
    except OSError:
        return f"<p><em>figure {html.escape(figure['path'])} is missing</em></p>"
    alt = html.escape(Path(figure["path"]).stem)
    return (
        f'<figure><img alt="{alt}" src="data:image/png;base64,{data}">'
        f'<figcaption class="caption">{html.escape(figure["caption"])}</figcaption></figure>'
    )


def _headline_html(studies: list[tuple[Path, dict]]) -> str:
    rows = [
        {"study": d["name"], "quantity": k, "value": v}
        for _, d in studies
        for k, v in sorted(d.get("headline", {}).items())
    ]
    if not rows:
        return ""
    df = pd.DataFrame(rows)
    table = df.to_html(index=False, na_rep="", border=0, classes="headline",
                       float_format=lambda v: f"{v:.6g}")  # fmt: skip
    return "<details><summary>Headline numbers</summary>" + table + "</details>"


#: Lines of the page's summary (one per study; the rest of the studies share the last).
SUMMARY_LINES = 10
#: Characters of a study's first finding shown in the summary.
SUMMARY_CHARS = 180


def shorten(text: str, n: int = SUMMARY_CHARS) -> str:
    """``text`` cut at a word boundary to at most ``n`` characters, with an ellipsis.

    Examples
    --------
    >>> shorten("one two three", 9)
    'one two…'
    """
    if len(text) <= n:
        return text
    return text[: n - 1].rsplit(" ", 1)[0].rstrip(",;:") + "…"


def summary_html(studies: list[tuple[Path, dict]], lines: int = SUMMARY_LINES) -> str:
    """The summary under the contents: at most ``lines`` lines, each a study's first
    finding (shortened) linking to its section; the full findings stay in the sections.
    """
    if not studies:
        return ""
    items = []
    shown = studies if len(studies) <= lines else studies[: lines - 1]
    for folder, d in shown:
        first = shorten(d["findings"][0]) if d.get("findings") else ""
        link = f'<a href="#{folder.name}">{html.escape(d["name"].replace("_", "-"))}</a>'
        items.append(f"<li>{link}: {html.escape(first)}</li>")
    rest = studies[len(shown) :]
    if rest:
        links = ", ".join(
            f'<a href="#{f.name}">{html.escape(d["name"].replace("_", "-"))}</a>' for f, d in rest
        )
        items.append(f"<li>More in {links}.</li>")
    return '<h2>Summary</h2><ul class="summary">' + "".join(items) + "</ul>"


def write_index(root: Path, title: str, intro: str = "") -> Path:
    """Write ``root/index.html`` for every study summary under ``root``.

    Parameters
    ----------
    root
        The report folder.
    title
        The page's title.
    intro
        A sentence under the title.

    Returns
    -------
    Path
    """
    root = Path(root)
    studies = read_outputs(root)
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{html.escape(title)}</title><style>{CSS}</style></head><body>",
        f"<h1>{html.escape(title)}</h1>",
    ]
    if intro:
        parts.append(f"<p>{html.escape(intro)}</p>")
    if not studies:
        parts.append("<p>No study has been run into this folder yet.</p>")
    parts.append('<nav id="contents"><h2>Contents</h2><ul>')
    for folder, d in studies:
        parts.append(f'<li><a href="#{folder.name}">{html.escape(d["title"])}</a></li>')
    parts.append("</ul></nav>")
    parts.append(summary_html(studies))
    parts.append(_headline_html(studies))
    for folder, d in studies:
        parts.append(f'<section id="{folder.name}"><h2>{html.escape(d["title"])}</h2>')
        parts.append(
            f"<p>Regenerate: <code>{html.escape(d['command'])}</code> "
            f"({d.get('seconds', 0):.0f} s).</p><ul>"
        )
        parts += [f"<li>{html.escape(f)}</li>" for f in d["findings"]]
        parts.append("</ul>")
        parts += [_table_html(folder, t) for t in d["tables"]]
        parts += [_figure_html(folder, f) for f in d["figures"]]
        parts.append("</section>")
    parts.append("</body></html>")
    path = root / "index.html"
    atomic_write_text(path, "\n".join(parts) + "\n")
    return path
