"""The verdict's ranking: every model by its error against the reference, and against the
same mesh's P1 of the reference's law (the model error of a P1-based fast model, without
the mesh's discretisation error). :func:`studies.verdict.verdict` writes both lines.
"""

from __future__ import annotations

import numpy as np
import pandas as pd


def pct(x: float) -> str:
    """``5%``, ``12.3%``, ``0.04%``."""
    return f"{100 * x:.3g}%"


def rank_by_error(table: pd.DataFrame, ref: str, same_as_ref: pd.Series) -> pd.Series:
    """Each model's place by its error against the reference (1: closest), ties sharing
    the lower place; the reference, rows that are its solve and rows without an error get
    none (``<NA>``).

    Parameters
    ----------
    table
        The verdict's table (``model``, ``rel L2 error``).
    ref
        The reference model.
    same_as_ref
        Per row, whether it is the reference's solve.

    Returns
    -------
    pandas.Series
        Nullable integers, aligned with ``table``.

    Examples
    --------
    >>> t = pd.DataFrame({"model": ["P2", "xpbd", "P1"], "rel L2 error": [0, .02, .01]})
    >>> rank_by_error(t, "P2", t["model"] == "P2").tolist()
    [<NA>, 2, 1]
    """
    err = table["rel L2 error"].where(~same_as_ref & np.isfinite(table["rel L2 error"]))
    return err.rank(method="min").astype("Int64")


def ranking_line(table: pd.DataFrame, ref: str) -> str:
    """One line: every ranked model (:func:`rank_by_error`), closest first, with its error
    and its static time as a ratio to the reference's.

    Parameters
    ----------
    table
        The verdict's table with its ``rank`` column.
    ref
        The reference model.

    Returns
    -------
    str
        Empty when nothing is ranked.

    Examples
    --------
    >>> t = pd.DataFrame({"model": ["P2", "xpbd", "P1"], "rank": pd.array([None, 2, 1], "Int64"),
    ...     "rel L2 error": [0, .02, .01], "static time (s)": [4.0, 8.0, 1.0]})
    >>> ranking_line(t, "P2")
    'By error against P2: 1. P1 1% (0.25× its time), 2. xpbd 2% (2×).'
    """
    ranked = table[table["rank"].notna()].sort_values(["rank", "static time (s)"])
    if ranked.empty or not ref:
        return ""
    t_ref = float(table.set_index("model").at[ref, "static time (s)"])
    parts = []
    for i, (_, r) in enumerate(ranked.iterrows()):
        ratio = float(r["static time (s)"]) / t_ref
        when = f"{ratio:.2g}×" if np.isfinite(ratio) else "time n/a"
        when = f"{when} its time" if i == 0 and np.isfinite(ratio) else when
        parts.append(f"{int(r['rank'])}. {r['model']} {pct(float(r['rel L2 error']))} ({when})")
    return f"By error against {ref}: " + ", ".join(parts) + "."


def same_mesh_line(table: pd.DataFrame, ref: str, p1: str, same_as_ref: pd.Series) -> str:
    """One line: the models by their error against the same mesh's P1 of the reference's
    law (model error, without the mesh's discretisation error), closest first.

    Parameters
    ----------
    table
        The verdict's table with its ``vs <p1> (same mesh)`` column.
    ref, p1
        The reference and its same-mesh P1 model.
    same_as_ref
        Per row, whether it is the reference's solve.

    Returns
    -------
    str

    Examples
    --------
    >>> t = pd.DataFrame({"model": ["P2-NH", "P1-NH", "xpbd", "P1"],
    ...     "rel L2 error": [0, .3, .31, .4], "vs P1-NH (same mesh)": [.3, 0, .02, .4]})
    >>> same_mesh_line(t, "P2-NH", "P1-NH", t["model"] == "P2-NH")
    'Against P1-NH on the same mesh (itself 30% off P2-NH): 1. xpbd 2%, 2. P1 40%.'
    """
    col = f"vs {p1} (same mesh)"
    t = table[~same_as_ref & (table[col] > 0) & np.isfinite(table[col])]
    t = t.sort_values(col)
    own = float(table.set_index("model").at[p1, "rel L2 error"])
    parts = [f"{i}. {r['model']} {pct(float(r[col]))}" for i, (_, r) in enumerate(t.iterrows(), 1)]
    return f"Against {p1} on the same mesh (itself {pct(own)} off {ref}): " + ", ".join(parts) + "."
