"""What ``springfem bench scale`` writes: tables, the figure, the cost laws, the report entry.

Into the output folder (default ``reports/scale/``):

- ``cases.csv`` / ``cases.md``: every model and size, measured or why not (``cases.json``:
  the same in full precision, which ``--resume`` reads);
- ``laws.csv`` / ``laws.md``: each model's fitted exponents, the largest size it solved and
  the largest mesh its laws allow in 24 GB and in an hour
  (:func:`studies.bench_scale_fit.laws_table`);
- ``scale.png``: static time, explicit step time and peak memory against tets, log-log,
  one line per model, the fitted laws extrapolated dotted, the 24 GB line;
- ``cost_laws.json``: the laws for the verdict's cost model
  (:func:`studies.bench_scale_fit.cost_laws_document`), and a copy at ``--cost-laws``;
- ``output.json``: the entry ``springfem report`` shows as a static section
  (:func:`studies.html.write_output`; the report never re-runs the benchmark).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from springfem.files import atomic_write_text

from .bench_scale_fit import (
    MACHINE_BYTES,
    SOLVED,
    cost_laws_document,
    evaluate,
    laws_table,
    machine_description,
    model_laws,
)

#: The figure's file name.
FIGURE = "scale.png"
#: The raw cases (full precision, bytes and seconds), read back by ``--resume``.
RAW_CASES = "cases.json"


def read_cases(out: Path) -> list[dict]:
    """The raw cases an earlier run wrote into ``out`` (none when there are none).

    Parameters
    ----------
    out
        The output folder.

    Returns
    -------
    list of dict
    """
    try:
        rows = json.loads((Path(out) / RAW_CASES).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return []
    return [{k: (np.nan if v is None else v) for k, v in r.items()} for r in rows]


def cases_table(cases: pd.DataFrame) -> pd.DataFrame:
    """The cases in readable units (GB, ms), one row per model and size."""
    df = pd.DataFrame(
        {
            "model": cases["model"],
            "tets": cases["tets"].astype(float).round().astype("Int64"),
            "status": cases["status"],
            "static (s)": cases["static (s)"].astype(float),
            "step (ms)": cases["step (s)"].astype(float) * 1e3,
            "peak memory (GB)": cases["peak memory (bytes)"].astype(float) / 1e9,
            "baseline (GB)": cases["baseline (bytes)"].astype(float) / 1e9,
            "predicted static (s)": cases["predicted static (s)"].astype(float),
            "predicted memory (GB)": cases["predicted memory (bytes)"].astype(float) / 1e9,
            "load average": cases["load average"].astype(float),
            "note": cases["message"].fillna("").str.slice(0, 100),
        }
    )
    return df


def scale_figure(cases: pd.DataFrame, laws: dict[str, dict], path: Path,
                 machine_bytes: float = MACHINE_BYTES) -> Path:  # fmt: skip
    """Static time, explicit step time and peak memory against tets (log-log), one line per
    model (measured: solid with markers; the fitted law extrapolated: dotted), a cross where a
    model did not fit, and the machine's memory as a line.

    Parameters
    ----------
    cases
        The cases.
    laws
        :func:`studies.bench_scale_fit.model_laws`.
    path
        The PNG.
    machine_bytes
        The memory line.

    Returns
    -------
    Path
    """
    from matplotlib.ticker import FuncFormatter, NullFormatter

    from .tables import plain_log_ticks, pyplot, save_figure

    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(17, 6.2))
    names = list(laws)
    colours = plt.get_cmap("tab10").colors
    markers = "os^vD<>"  # 7 markers and 10 colours: no two of 70 models look alike
    tets_all = cases["tets"].astype(float)
    top = max(float(tets_all.max()) * 2.5, 1e6)
    grid = np.geomspace(float(tets_all.min()), top, 60)
    panels = (
        ("static (s)", "time", "static solve (s)", 1.0),
        ("step (s)", "step", "explicit force pass (ms)", 1e3),
        ("peak memory (bytes)", "memory", "peak memory, RSS (GB)", 1e-9),
    )
    for ax, (column, key, label, scale) in zip(axes, panels, strict=True):
        for i, name in enumerate(names):
            rows = cases[cases["model"] == name].sort_values("tets")
            good = rows[np.isfinite(rows[column].astype(float))]
            if key != "step":
                good = good[good["status"].isin(SOLVED)]
            if good.empty:
                continue
            style = {"color": colours[i % len(colours)], "marker": markers[i % len(markers)]}
            line = "-" if i < len(colours) else "--"
            ax.plot(good["tets"], good[column].astype(float) * scale, line, ms=5, lw=1.4,
                    label=name, **style)  # fmt: skip
            law = laws[name][key]
            if key == "memory" and not laws[name]["memory above baseline"]:
                law = None  # every size near the process's baseline: no law to draw
            if law is not None:
                x = grid[grid >= float(good["tets"].min())]
                ax.plot(x, evaluate(law, x) * scale, ":", color=style["color"], lw=1)
            if key != "step":
                bad = rows[rows["status"].str.startswith("did not fit")]
                if not bad.empty:
                    y = float(good[column].astype(float).iloc[-1]) * scale
                    ax.plot(bad["tets"].iloc[:1], [y], "x", color=style["color"], ms=9, mew=2)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("tets")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.25)
        ax.set_xlim(float(tets_all.min()) / 1.5, top)
    axes[2].axhline(machine_bytes / 1e9, color="k", lw=1.5, ls="--")
    axes[2].text(float(tets_all.min()), machine_bytes / 1e9 * 1.12,
                 f"{machine_bytes / 1e9:.0f} GB: the machine", fontsize=9)  # fmt: skip
    lo, hi = axes[2].get_ylim()
    axes[2].set_ylim(lo, max(hi, machine_bytes / 1e9 * 2))
    for ax in axes:
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _p: _tets(v)))
        ax.xaxis.set_minor_formatter(NullFormatter())
        plain_log_ticks(ax.yaxis)
    axes[0].set_title("static solve: measured (solid), law (dotted), × did not fit",
                      fontsize=10)  # fmt: skip
    axes[1].set_title("explicit step (one force pass)", fontsize=10)
    axes[2].set_title("peak memory of the case's process", fontsize=10)
    handles, labels = axes[0].get_legend_handles_labels()
    for h, lab in zip(*axes[1].get_legend_handles_labels(), strict=True):
        if lab not in labels:
            handles.append(h)
            labels.append(lab)
    fig.legend(handles, labels, loc="lower center", ncol=min(8, max(len(labels), 1)),
               fontsize=9, frameon=False, bbox_to_anchor=(0.5, -0.08))  # fmt: skip
    fig.tight_layout()
    return save_figure(fig, path)


def findings(cases: pd.DataFrame, table: pd.DataFrame, settings, seconds: float) -> list[str]:
    """The benchmark's findings in a few sentences, with its numbers."""
    out = []
    ran = cases[np.isfinite(cases["case wall (s)"].astype(float))]
    sizes = sorted({int(t) for t in ran["tets"].astype(float) if np.isfinite(t)})
    loads = cases["load average"].astype(float)
    out.append(
        f"Organ meshes of {', '.join(f'{s:,}' for s in sizes)} tets on {machine_description()}; "
        f"each case in its own process, capped at {settings.max_time:g} s per static solve "
        f"({settings.reference_cap:g} s for the reference) and "
        f"{settings.max_memory / 1e9:g} GB of address space; load average "
        f"{np.nanmin(loads):.2f}–{np.nanmax(loads):.2f} during the cases ({seconds:.0f} s in all)."
    )
    if not table.empty:
        biggest = table.sort_values("largest solved (tets)", ascending=False)
        solved = biggest["largest solved (tets)"].astype(float)
        parts = [f"{m} {int(n):,}" for m, n in zip(biggest["model"], solved, strict=True)
                 if np.isfinite(n)]  # fmt: skip
        if parts:
            out.append("Largest organ solved within the caps: " + ", ".join(parts) + ".")
        col = [c for c in table.columns if c.startswith("largest in ")][0]
        how = table[col.replace(" (tets)", "").replace("largest ", "")].astype(str)
        sound = np.isfinite(table[col].astype(float)) & ~how.str.contains("guess")
        ext = table[sound].sort_values(col, ascending=False)
        if ext.empty:
            out.append(
                f"No memory law reaches {MACHINE_BYTES / 1e9:.0f} GB within ten times the sizes "
                "measured: at these sizes a case's peak is mostly the process's baseline and its "
                "mesh, and time, not memory, is where the machine ends."
            )
        else:
            out.append(
                f"Extrapolated from the memory laws, the largest organ in "
                f"{MACHINE_BYTES / 1e9:.0f} GB: "
                + ", ".join(f"{r['model']} {_tets(r[col])}" for _, r in ext.iterrows())
                + " (a law fitted over sizes at most "
                f"{settings.max_memory / 1e9:g} GB; beyond them it is a guess)."
            )
        exps = table[np.isfinite(table["time b"])]
        if not exps.empty:
            out.append(
                "Static time exponents b (time ~ N^b): "
                + ", ".join(f"{r['model']} {r['time b']:.2f}" for _, r in exps.iterrows())
                + "; memory exponents d: "
                + ", ".join(
                    f"{r['model']} {r['memory d']:.2f}"
                    for _, r in table[np.isfinite(table["memory d"])].iterrows()
                )
                + "."
            )
    out += list(settings.notes)
    return out


def _tets(n: float) -> str:
    if not np.isfinite(n):
        return "—"
    if n >= 1e6:
        return f"{n / 1e6:.3g}M"
    return f"{n / 1e3:.3g}k" if n >= 1e3 else f"{n:.3g}"


def write_outputs(
    cases: pd.DataFrame, settings, seconds: float, command: str = "springfem bench scale"
) -> dict[str, Path]:
    """Write the tables, the figure, the cost laws and the report entry (module docstring).

    Parameters
    ----------
    cases
        One row per case (:func:`studies.bench_scale.bench_scale`).
    settings
        The :class:`~studies.bench_scale.ScaleSettings`.
    seconds
        The run's wall time so far.
    command
        The command line that regenerates it (:func:`studies.bench_scale.command`).

    Returns
    -------
    dict
        ``cases``, ``laws``, ``figure``, ``cost_laws`` (and ``output``): the paths written.
    """
    from .html import write_output
    from .registry import Figure, StudyOutput, Table
    from .tables import write_table

    out = Path(settings.out)
    out.mkdir(parents=True, exist_ok=True)
    laws = model_laws(cases)
    table = laws_table(laws, cases)
    paths = {
        "cases": write_table(cases_table(cases), out / "cases"),
        "laws": write_table(table, out / "laws"),
        "figure": scale_figure(cases, laws, out / FIGURE),
    }
    raw = cases.astype(object).where(pd.notna(cases), None).to_dict(orient="records")
    atomic_write_text(out / RAW_CASES, json.dumps(raw, indent=0, default=float) + "\n")
    loads = cases["load average"].astype(float)
    machine = machine_description()
    if np.isfinite(loads).any():
        machine += f" (shared: load average {np.nanmin(loads):.1f}-{np.nanmax(loads):.1f})"
    doc = cost_laws_document(laws, machine=machine, aliases=getattr(settings, "aliases", None))
    text = json.dumps(doc, indent=1, sort_keys=True) + "\n"
    paths["cost_laws"] = out / "cost_laws.json"
    atomic_write_text(paths["cost_laws"], text)
    if settings.cost_laws is not None:
        Path(settings.cost_laws).parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(Path(settings.cost_laws), text)
    found = findings(cases, table, settings, seconds)
    gb = MACHINE_BYTES / 1e9
    result = StudyOutput(
        "scale",
        "Scale benchmark: every model on organ meshes up to where the machine ends",
        findings=found,
        tables=[
            Table(paths["laws"], f"Fitted laws per model (time ~ a N^b, memory ~ c N^d, step "
                  f"~ e N^f, N in units of 1e4 tets) and the largest organ in {gb:.0f} GB."),
            Table(paths["cases"], "Every model and organ size: measured, or why not."),
        ],  # fmt: skip
        figures=[Figure(paths["figure"], "Static solve time, explicit force pass and peak "
                        f"memory against tets; dotted: the fitted laws; dashed: {gb:.0f} GB.")],
        headline={f"{r['model']} time exponent": round(float(r["time b"]), 2)
                  for _, r in table.iterrows() if np.isfinite(r["time b"])},
        seconds=seconds,
    )  # fmt: skip
    paths["output"] = write_output(out, result, command)
    return paths
