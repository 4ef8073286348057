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
