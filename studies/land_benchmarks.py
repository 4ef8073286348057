"""Land et al. 2015's ventricle benchmarks (problems 2 and 3) on a family of meshes.

Each problem is solved with the P2/P1 mixed FEM of its bundled scene on a documented family
of gmsh meshes (the gmsh ellipsoid cannot be refined in a nested way without moving the
boundary, so the family is one of sizes): problem 2 (``land-ventricle``) on uniform sizes
:data:`P2_LEVELS`; problem 3 (``land-ventricle-active``) on :data:`P3_LEVELS`, sizes whose
axis size (``[mesh] axis_size``) shrinks in proportion, because its fibre field is singular
on the long axis (docs/verification.rst#land-problem-3-fibres). The observed order and the
Richardson value of the three finest levels come from
:func:`studies.study_tissue.convergence.observed_order`, with the gmsh size as ``h``.

Each level is one background-friendly process step: ``python -m studies.land_benchmarks
--problem 3 --level 2`` solves one level and merges it into ``reports/land_benchmarks/
problem3.json``; ``--table`` prints the Markdown table of what is there. Per level it records
the apex z, the tets and DOFs, the wall time, Newton's iterations, load steps and cut-backs.

Examples
--------
>>> rows = [{"problem": "3", "size": h, "axis_size": h / 4, "tets": 1, "dofs": 1,
...          "endo": -12.0 + 0.5 * h**2, "epi": -15.0 + 0.25 * h**2, "wall": 1.0,
...          "iterations": 1, "load_steps": 1, "cutbacks": 0} for h in (4.0, 2.0, 1.0)]
>>> ext = extrapolate(rows)["3"]
>>> round(ext["endo"]["order"], 6), round(ext["endo"]["extrapolated"], 6)
(2.0, -12.0)
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

from springfem.files import atomic_write_text

from .scenes import bundled_table
from .study_tissue.convergence import observed_order

#: Problem 2: uniform gmsh sizes (mm), coarse to fine.
P2_LEVELS = ((4.0, None), (3.0, None), (2.0, None), (1.5, None))
#: Problem 3: (size, axis size) in mm, coarse to fine, the axis size a quarter of the size.
P3_LEVELS = ((4.0, 1.0), (3.0, 0.75), (2.0, 0.5), (1.5, 0.375))
SCENES = {"2": "land-ventricle", "3": "land-ventricle-active"}
LEVELS = {"2": P2_LEVELS, "3": P3_LEVELS}
#: FEniCS-pulse's apex z (mm; github.com/finsberg/pulse pull request 98).
PULSE = {"2": {"endo": -26.5328, "epi": -28.1790}, "3": {"endo": -12.00, "epi": -15.22}}
#: Land et al. 2015: typical relative difference between the groups' fine solutions.
BAND = 0.005
#: One JSON file of levels per problem (two problems can run at once).
OUT = Path(__file__).resolve().parents[1] / "reports" / "land_benchmarks"


def solve_level(problem: str, level: int, load_steps: int = 10) -> dict:
    """Solve one level of one problem and return its row.

    Parameters
    ----------
    problem
        ``"2"`` or ``"3"``.
    level
        Index into :data:`LEVELS` ``[problem]``.
    load_steps
        Initial load steps (the core's Newton adapts them).

    Returns
    -------
    dict
        ``problem``, ``size``, ``axis_size``, ``tets``, ``dofs``, ``endo``, ``epi`` (apex
        z, mm), ``wall`` (s), ``iterations``, ``load_steps``, ``cutbacks``, ``intorder`` and
        ``error`` (empty when the full load was reached).
    """
    import reference_fem
    from springfem.errors import SolverError
    from springfem.scene import scene_from_dict

    size, axis = LEVELS[problem][level]
    data = bundled_table(SCENES[problem])
    data["mesh"]["size"] = size
    data["mesh"].pop("axis_size", None)
    if axis is not None:
        data["mesh"]["axis_size"] = axis
    data["fem"]["load_steps"] = load_steps
    row: dict = {"problem": problem, "size": size, "axis_size": axis}
    t0 = time.perf_counter()
    try:
        r = reference_fem.solve(scene_from_dict(data)).result
    except SolverError as exc:
        return {**row, "error": str(exc), "wall": time.perf_counter() - t0,
                "load_factor": exc.load_factor}  # fmt: skip
    return {**row, "tets": r.counts["tets"], "dofs": r.counts["dofs"],
            "endo": -17.0 + r.probes["endo_apex"][2], "epi": -20.0 + r.probes["epi_apex"][2],
            "wall": r.wall_time, "iterations": r.iterations, "load_steps": r.info["load_steps"],
            "cutbacks": r.info["cutbacks"], "intorder": r.info["intorder"],
            "error": ""}  # fmt: skip


def load_rows(folder: Path = OUT) -> list[dict]:
    """The rows recorded so far in ``folder`` (``problem<N>.json``), by problem and size."""
    rows = [r for f in sorted(folder.glob("problem*.json")) for r in json.loads(f.read_text())]
    return sorted(rows, key=lambda r: (r["problem"], -r["size"]))


def merge_row(row: dict, folder: Path = OUT) -> list[dict]:
    """Replace the row of the same (size, axis size) in its problem's file (atomically)."""
    path = folder / f"problem{row['problem']}.json"
    key = (row["size"], row["axis_size"])
    old = json.loads(path.read_text()) if path.exists() else []
    rows = sorted([*(r for r in old if (r["size"], r["axis_size"]) != key), row],
                  key=lambda r: -r["size"])  # fmt: skip
    folder.mkdir(parents=True, exist_ok=True)
    atomic_write_text(path, json.dumps(rows, indent=1) + "\n")
    return rows


def extrapolate(rows: list[dict]) -> dict:
    """Per problem and surface: the observed order and Richardson value of the three finest
    converged levels, and the note of :func:`observed_order` (why not, if not)."""
    out: dict = {}
    for problem in sorted({r["problem"] for r in rows}):
        ok = sorted((r for r in rows if r["problem"] == problem and not r.get("error")),
                    key=lambda r: -r["size"])[-3:]  # fmt: skip
        out[problem] = {}
        for s in ("endo", "epi"):
            if len(ok) < 3:
                out[problem][s] = {"order": math.nan, "extrapolated": math.nan,
                                   "note": "fewer than 3 levels"}  # fmt: skip
                continue
            p, f0, note = observed_order([r["size"] for r in ok], [r[s] for r in ok])
            out[problem][s] = {"order": p, "extrapolated": f0, "note": note}
    return out


def markdown(rows: list[dict]) -> str:
    """The verification table: each level, the extrapolation, pulse's value and the band."""
    ext = extrapolate(rows)
    lines = [
        "| problem | size / axis size (mm) | tets | DOFs | endo apex z | epi apex z | "
        "Newton its / steps / cut-backs | wall (s) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        mesh = f"{r['size']:g}" + ("" if r["axis_size"] is None else f" / {r['axis_size']:g}")
        if r.get("error"):
            stop = r.get("load_factor") or math.nan
            lines.append(f"| {r['problem']} | {mesh} | | | stopped at load {stop:.3g} | | | "
                         f"{r['wall']:.0f} |")  # fmt: skip
            continue
        lines.append(f"| {r['problem']} | {mesh} | {r['tets']:,} | {r['dofs']:,} | "
                     f"{r['endo']:.3f} | {r['epi']:.3f} | {r['iterations']} / "
                     f"{r['load_steps']} / {r['cutbacks']} | {r['wall']:.0f} |")  # fmt: skip
    for problem, e in ext.items():
        cells = []
        for s in ("endo", "epi"):
            v = e[s]
            cells.append(f"{v['extrapolated']:.3f} (p = {v['order']:.2g})"
                         if math.isfinite(v["extrapolated"]) else v["note"])  # fmt: skip
        lines.append(f"| {problem} | Richardson | | | {cells[0]} | {cells[1]} | | |")
        pub = PULSE[problem]
        lines.append(f"| {problem} | FEniCS-pulse (+/- {100 * BAND:g} %) | | | "
                     f"{pub['endo']:.2f} (+/- {abs(BAND * pub['endo']):.2f}) | "
                     f"{pub['epi']:.2f} (+/- {abs(BAND * pub['epi']):.2f}) | | |")  # fmt: skip
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Command line: solve one level (``--problem``, ``--level``) or print ``--table``."""
    ap = argparse.ArgumentParser(prog="python -m studies.land_benchmarks")
    ap.add_argument("--problem", choices=sorted(SCENES))
    ap.add_argument("--level", type=int)
    ap.add_argument("--table", action="store_true")
    ap.add_argument("--out", type=Path, default=OUT)
    a = ap.parse_args(argv)
    if a.problem is not None and a.level is not None:
        row = solve_level(a.problem, a.level)
        merge_row(row, a.out)
        print(json.dumps(row))
    if a.table:
        print(markdown(load_rows(a.out)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
