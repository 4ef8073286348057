"""The sweep's table and default figures, assembled from the case files.

One row per case × model: the swept keys first (a list value such as
``mesh.divisions = [20, 2, 2]`` appears as its text ``[20, 2, 2]``), then the row fields
of :mod:`studies.sweep_case`. Written as ``results.parquet`` and ``results.csv``
(atomically); figures: the error against each swept key and against wall time.

Examples
--------
>>> rows = [{"values": {"material.nu": 0.3}, "rows": [{"model": "spring", "rel_l2": 0.1}]}]
>>> sweep_table(rows, ("material.nu",)).to_dict(orient="records")
[{'case': 0, 'material.nu': 0.3, 'model': 'spring', 'rel_l2': 0.1}]
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from springfem.files import atomic_write_text, safe_filename

from .tables import pyplot, save_figure


def _cell(v: Any) -> Any:
    """A swept value as a table cell: scalars as they are, lists/tables as compact text."""
    if isinstance(v, (list, dict)):
        return json.dumps(v, separators=(", ", ": "))
    return v


def sweep_table(case_results: Sequence[dict[str, Any]], keys: Sequence[str]) -> pd.DataFrame:
    """One row per case × model from the results of :func:`studies.sweep_case.run_case`.

    Parameters
    ----------
    case_results
        Per case, in case order.
    keys
        The swept keys (columns first, in this order).

    Returns
    -------
    pandas.DataFrame
        Column ``case`` (the case's index), the keys, then the row fields.
    """
    records = []
    for i, res in enumerate(case_results):
        values = {k: _cell(res["values"].get(k)) for k in keys}
        for row in res["rows"]:
            records.append({"case": i, **values, **row})
    df = pd.DataFrame.from_records(records)
    for k in keys:  # one type per column (parquet): mixed strings and numbers become text
        kinds = {type(v) for v in df[k].dropna()}
        if len(kinds - {int, float}) > 0 and len(kinds) > 1:
            df[k] = df[k].map(lambda v: None if v is None else str(v))
    return df


def write_tables(df: pd.DataFrame, out: Path) -> tuple[Path, Path]:
    """``results.parquet`` and ``results.csv`` in ``out`` (each written atomically)."""
    out.mkdir(parents=True, exist_ok=True)
    parquet = out / "results.parquet"
    fd, tmp = tempfile.mkstemp(dir=out, prefix=f".{parquet.name}.", suffix=f".{os.getpid()}.tmp")
    os.close(fd)
    try:
        df.to_parquet(tmp, index=False)
        os.replace(tmp, parquet)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    csv = out / "results.csv"
    atomic_write_text(csv, df.to_csv(index=False))
    return parquet, csv


def _compared(df: pd.DataFrame, reference: str) -> pd.DataFrame:
    """Rows with a finite positive error (the reference itself has zero error)."""
    ok = df[(df["model"] != reference) & (df["status"] == "ok")]
    return ok[np.isfinite(ok["rel_l2"]) & (ok["rel_l2"] > 0)]


#: Swept keys that change the mesh: their figure's axis is the number of tets.
MESH_SIZE_KEYS = ("mesh.file", "mesh.divisions", "mesh.size", "mesh.scale")


def _error_against_tets(ax, data: pd.DataFrame, models: list, key: str) -> None:
    """Error against the mesh's tet count (log-log), one colour per model."""
    for m in models:
        d = data[data["model"] == m].sort_values("tets")
        ax.scatter(d["tets"], d["rel_l2"], label=m, alpha=0.75, s=22)
        med = d.groupby("tets")["rel_l2"].median()
        ax.plot(med.index.to_numpy(float), med.to_numpy(), lw=1, alpha=0.6)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(f"tets (swept: {key})")
    ax.set_title("error against mesh size (points: cases; lines: median)", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    if models:
        ax.legend(fontsize=8)


def sweep_figures(df: pd.DataFrame, keys: Sequence[str], reference: str, out: Path) -> list[Path]:
    """Error against each swept key and against wall time, one colour per model.

    Parameters
    ----------
    df
        :func:`sweep_table`.
    keys
        The swept keys (one figure each).
    reference
        The reference model (its rows have no error and are left out).
    out
        Folder of the PNGs.

    Returns
    -------
    list of Path
    """
    plt = pyplot()

    data = _compared(df, reference)
    models = list(dict.fromkeys(data["model"]))
    paths = []
    for key in keys:
        fig, ax = plt.subplots(figsize=(5.5, 3.8))
        levels = list(dict.fromkeys(df[key].dropna()))
        numeric = all(isinstance(v, (int, float)) for v in levels)
        if key in MESH_SIZE_KEYS and "tets" in data:  # a mesh is read by its size, not its name
            _error_against_tets(ax, data, models, key)
            ax.set_ylabel(f"relative L2 error vs {reference}")
            paths.append(save_figure(fig, out / f"error_vs_{safe_filename(key)}.png"))
            continue
        spread = np.linspace(-0.15, 0.15, max(len(models), 1))
        for j, m in enumerate(models):
            d = data[data["model"] == m]
            if numeric:
                x = d[key].to_numpy(float)
            else:  # categories at 0, 1, 2 … with the models side by side
                x = np.array([levels.index(v) for v in d[key]], float) + spread[j]
            ax.scatter(x, d["rel_l2"], label=m, alpha=0.75, s=22)
            med = d.groupby(key, sort=False)["rel_l2"].median()
            xm = (
                med.index.to_numpy(float)
                if numeric
                else [levels.index(v) + spread[j] for v in med.index]
            )
            order = np.argsort(xm)
            ax.plot(np.asarray(xm)[order], med.to_numpy()[order], lw=1, alpha=0.6)
        if not numeric:
            ax.set_xticks(range(len(levels)), [str(v) for v in levels])
        ax.set_yscale("log")
        ax.set_xlabel(key)
        ax.set_ylabel(f"relative L2 error vs {reference}")
        ax.set_title(f"error against {key} (points: cases; lines: median)", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        if models:
            ax.legend(fontsize=8)
        paths.append(save_figure(fig, out / f"error_vs_{safe_filename(key)}.png"))
    fig, ax = plt.subplots(figsize=(5.5, 3.8))
    cold_seen = False
    for m in models:
        d = data[data["model"] == m]
        cold = ~d["warm"].fillna(True).astype(bool) if "warm" in d else np.zeros(len(d), bool)
        (h,) = [ax.scatter(d["wall_time"][~cold], d["rel_l2"][~cold], label=m, alpha=0.75, s=22)]
        if cold.any():  # a worker's first solve of the model: imports and compilation
            ax.scatter(d["wall_time"][cold], d["rel_l2"][cold], s=22, facecolors="none",
                       edgecolors=h.get_facecolor()[0])  # fmt: skip
            cold_seen = True
    ref = df[(df["model"] == reference) & (df["status"] == "ok")]["wall_time"]
    if len(ref):
        ax.axvline(float(ref.median()), color="k", ls="--", lw=1, label=f"{reference} (median)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time of the solve (s)")
    ax.set_ylabel(f"relative L2 error vs {reference}")
    ax.set_title(
        "error against cost (one point per case"
        + ("; hollow: a worker's first solve of the model, with its set-up)" if cold_seen else ")"),
        fontsize=9,
    )
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    paths.append(save_figure(fig, out / "error_vs_wall_time.png"))
    return paths
