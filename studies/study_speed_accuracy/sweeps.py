"""Findings of the speed-accuracy study per fast model: its best point within the tolerance,
and the plug-ins' sweeps of their own settings (error against each setting, observed rate).

A plug-in's sweep (:func:`.cases.sweep`, e.g. XPBD's substeps x iterations) is read one
setting at a time: the points whose other settings are the plug-in's defaults, on the
finest level where the setting varies, error against the P1-NH answer of the same mesh
(:data:`.tables.SAME`, the error the setting controls) where the table has it, else against
the reference. The observed rate ``p`` is the slope of ``-log(error)`` on ``log(setting)``,
least squares (``error ~ setting**-p``).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .tables import SAME


def model_of(method: str) -> str:
    """The model of a method name (``xpbd 20x2 static`` -> ``xpbd``)."""
    return method.split()[0]


def most_accurate(df: pd.DataFrame, err: str, suffix: str = ""):
    """The row of least error ``err`` among methods ending in ``suffix`` (``None``: none)."""
    g = df[df["method"].str.endswith(suffix)] if suffix else df
    return g.sort_values(err).iloc[0] if len(g) else None


def per_model_sentence(good: pd.DataFrame, err: str, tolerance: float) -> str:
    """Per model, its cheapest point (CPU time) within ``tolerance``, or, when none is, its
    most accurate point (the cheapest within 1 % of its least error), in a sentence.

    Examples
    --------
    >>> df = pd.DataFrame({"method": ["P1 static", "xpbd 20x2 static", "xpbd 40x2 static"],
    ...     "mesh": ["10x1x1", "10x1x1", "10x1x1"], "seconds": [0.1, 0.5, 0.9],
    ...     "err": [0.2, 0.04, 0.03]})
    >>> within, outside = per_model_sentence(df, "err", 0.05).split(". ")
    >>> within[within.index("xpbd:"):]
    'xpbd: xpbd 20x2 static on 10x1x1 (0.50 s, 4.0% off)'
    >>> outside
    'None within it: P1 (best P1 static on 10x1x1 (0.10 s, 20.0% off)).'
    """

    def point(r) -> str:
        return f"{r['method']} on {r['mesh']} ({r['seconds']:.2f} s, {100 * r[err]:.1f}% off)"

    parts, outside = [], []
    for name, g in good.groupby(good["method"].map(model_of), sort=False):
        within = g[g[err] <= tolerance].sort_values("seconds")
        if len(within):
            parts.append(f"{name}: {point(within.iloc[0])}")
        else:  # its most accurate, the cheapest of those within 1 % of that error
            near = g[g[err] <= 1.01 * g[err].min()].sort_values("seconds")
            outside.append(f"{name} (best {point(near.iloc[0])})")
    text = f"Per model, its cheapest point within {tolerance:.0%} of the reference: "
    text += "; ".join(parts) if parts else "none"
    if outside:
        text += f". None within it: {'; '.join(outside)}"
    return text + "."


def observed_rate(values, errors) -> float:
    """``p`` of ``error ~ value**-p`` (least squares in log-log; NaN below two points).

    Examples
    --------
    >>> round(observed_rate([10, 20, 40], [4e-2, 1e-2, 2.5e-3]), 6)
    2.0
    """
    v, e = np.asarray(values, float), np.asarray(errors, float)
    keep = np.isfinite(e) & (e > 0)
    if np.unique(v[keep]).size < 2:
        return float("nan")
    return float(-np.polyfit(np.log(v[keep]), np.log(e[keep]), 1)[0])


def sweep_findings(
    df: pd.DataFrame, cases: list[dict], err: str, finest: str
) -> tuple[list[str], dict[str, float]]:
    """For each plug-in sweep and each of its settings that varies (the others at the
    plug-in's defaults), on the finest level where it varies (``finest`` first): the errors
    by setting and the observed rate, a sentence each, and headline keys
    ``rate_<model>_<setting>_<level>``."""
    from .. import models

    own = [c["setting"].get("model") or {} for c in cases]
    ok = df["status"] == "ok"
    column = SAME if SAME in df and df.loc[ok, SAME].notna().any() else err
    against = "P1-NH on the same mesh" if column == SAME else "the reference"
    meshes = df.sort_values("tets", ascending=False, kind="stable")["mesh"].unique().tolist()
    meshes = sorted(meshes, key=lambda m: m != finest)  # stable: finest, then by size
    lines, rates = [], {}
    for name in dict.fromkeys(c["model"] for c, o in zip(cases, own, strict=True) if o):
        defaults = models.get(name).plugin.settings
        swept = [i for i, c in enumerate(cases) if c["model"] == name and own[i] and ok.iloc[i]]
        for key in dict.fromkeys(k for i in swept for k in own[i]):
            for mesh in meshes:
                series = sorted(
                    (own[i][key], float(df[column].iloc[i]))
                    for i in swept
                    if df["mesh"].iloc[i] == mesh
                    and all(v == defaults.get(k) for k, v in own[i].items() if k != key)
                )
                if len({v for v, _ in series}) >= 2:
                    break
            else:
                continue
            rate = observed_rate(*zip(*series, strict=True))
            fixed = ", ".join(f"{k} {v}" for k, v in defaults.items() if k in own[swept[0]]
                              and k != key)  # fmt: skip
            errors = ", ".join(f"{v}: {100 * e:.3g}%" for v, e in series)
            lines.append(
                f"{name} on {mesh}, error against {against} by {key} ({fixed}): {errors}; "
                f"observed rate {rate:.2f} (error ~ {key}^-p, least squares)."
            )
            rates[f"rate_{name}_{key}_{mesh}"] = round(rate, 4)
    return lines, rates
