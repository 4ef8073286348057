"""Tables and figures written atomically: CSV + Markdown from pandas, PNG from matplotlib."""

from __future__ import annotations

import os
from pathlib import Path

import pandas as pd

from springfem.files import atomic_write_text


def write_table(df: pd.DataFrame, path_stem: str | os.PathLike, floatfmt: str = ".4g") -> Path:
    """Write ``df`` as ``<stem>.csv`` and ``<stem>.md``; returns the Markdown path."""
    stem = Path(path_stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(stem.with_suffix(".csv"), df.to_csv(index=False))
    md = df.to_markdown(index=False, floatfmt=floatfmt)
    atomic_write_text(stem.with_suffix(".md"), md + "\n")
    return stem.with_suffix(".md")


def pyplot():
    """``matplotlib.pyplot`` on the ``Agg`` backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plain_log_ticks(*axes) -> None:
    """Label a log axis at its decades and at 2 and 5 between them, in plain numbers
    (``0.2``, ``1``, ``5e-04``): matplotlib labels every minor tick of an axis spanning under
    a decade, and their ``2×10⁻⁴`` labels overlap.

    Parameters
    ----------
    *axes
        matplotlib ``Axis`` objects (``ax.xaxis``, ``ax.yaxis``) already on a log scale.
    """
    from matplotlib.ticker import FuncFormatter, LogLocator

    plain = FuncFormatter(lambda v, _pos: f"{v:g}")
    for axis in axes:
        axis.set_minor_locator(LogLocator(subs=(2.0, 5.0)))
        axis.set_major_formatter(plain)
        axis.set_minor_formatter(plain)


def save_figure(fig, path: str | os.PathLike, dpi: int = 120) -> Path:
    """Save a matplotlib figure atomically as PNG and close it."""
    plt = pyplot()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp.png")
    fig.savefig(tmp, dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    os.replace(tmp, path)
    return path
