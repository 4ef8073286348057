"""Land et al. 2015's benchmarks (problems 1-3) on families of meshes.

Each problem is solved with the P2/P1 mixed FEM of its bundled scene on a family of meshes:
problem 1 (``land-beam``) on the nested box meshes :data:`P1_LEVELS` (divisions doubled);
the ventricles on documented families of gmsh meshes (the gmsh ellipsoid cannot be refined
in a nested way without moving the boundary, so the family is one of sizes): problem 2
(``land-ventricle``) on uniform sizes :data:`P2_LEVELS`; problem 3
(``land-ventricle-active``) on :data:`P3_LEVELS`, sizes whose axis size (``[mesh]
axis_size``) shrinks in proportion, because its fibre field is singular on the long axis
(docs/verification.rst#land-problem-3-fibres); families ``3a`` and ``3c`` refine only the
axis, ``3c`` with ``[fem] geometry = "curved"`` (the walls' P2 edge nodes on the true
ellipsoids). The observed order and the Richardson value
of the three finest levels come from
:func:`studies.metrics.observed_order`; ``h`` is the beam's element length
``10 / n`` mm, and for the ventricles the edge of the regular tet of the mean tet volume,
``(6 sqrt(2) V_wall / n_tets)^(1/3)`` (gmsh's size is only the bound it meshes to, as in
:mod:`studies.study_tissue.convergence`). With a fourth level, the coarser triple's order
says whether the three finest are in the asymptotic range.

Each level is one process (fit for a background run under ``timeout``):
``python -m studies.land_benchmarks --problem 3 --level 2`` solves one level and merges it
into ``reports/land_benchmarks/problem3.json``; ``--table`` prints the Markdown table of
what is there. Per level it records the deformed z of the probes (the beam's (10, 0.5, 1)
mm, the ventricles' apexes), the tets and DOFs, the wall time, Newton's iterations, load
steps and cut-backs.

Examples
--------
>>> rows = [{"problem": "1", "size": h, "axis_size": None, "tets": 1, "dofs": 1,
...          "tip": 4.17 - 0.1 * h**2, "wall": 1.0, "iterations": 1, "load_steps": 1,
...          "cutbacks": 0} for h in (2.0, 1.0, 0.5, 0.25)]
>>> ext = extrapolate(rows)["1"]["tip"]
>>> round(ext["order"], 6), round(ext["extrapolated"], 6), ext["asymptotic"]
(2.0, 4.17, True)
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

from springfem.ellipsoid import wall_volume
from springfem.files import atomic_write_text

from .metrics import observed_order
from .scenes import bundled_table

#: Problem 1: the beam's divisions (nested: each level halves the elements' edges).
P1_LEVELS = ((10, 1, 1), (20, 2, 2), (40, 4, 4))
#: Problem 2: uniform gmsh sizes (mm), coarse to fine.
P2_LEVELS = ((4.0, None), (3.0, None), (2.5, None), (2.0, None))
#: Problem 3: (size, axis size) in mm, coarse to fine, the axis size a quarter of the size.
P3_LEVELS = ((4.0, 1.0), (3.0, 0.75), (2.0, 0.5), (1.5, 0.375))
#: Problem 3 refined along the axis only (``3a``: size 4 mm, axis size halved): where its
#: fibre field is singular. ``3c``: the same meshes with curved (isoparametric) walls.
P3_AXIS_LEVELS = ((4.0, 1.0), (4.0, 0.5), (4.0, 0.25))
SCENES = {"1": "land-beam", "2": "land-ventricle", "3": "land-ventricle-active",
          "3a": "land-ventricle-active", "3c": "land-ventricle-active"}  # fmt: skip
LEVELS = {"1": P1_LEVELS, "2": P2_LEVELS, "3": P3_LEVELS, "3a": P3_AXIS_LEVELS,
          "3c": P3_AXIS_LEVELS}  # fmt: skip
#: Families solved with ``[fem] geometry = "curved"`` (``3c``: the ``3a`` meshes with the P2
#: edge nodes of the walls on the true ellipsoids).
CURVED = ("3c",)
#: Each problem's measured points: (probe name, its rest z, mm).
_APEXES = (("endo", -17.0), ("epi", -20.0))
PROBES = {"1": (("tip", 1.0),), "2": _APEXES, "3": _APEXES, "3a": _APEXES, "3c": _APEXES}
#: FEniCS-pulse's apex z (mm; github.com/finsberg/pulse pull request 98).
PULSE = {"2": {"endo": -26.5328, "epi": -28.1790}, "3": {"endo": -12.00, "epi": -15.22},
         "3a": {"endo": -12.00, "epi": -15.22}, "3c": {"endo": -12.00, "epi": -15.22}}  # fmt: skip
#: Land et al. 2015's range over its 11 codes (mm; problem 1, the beam's deformed z).
PAPER_RANGE = {"1": {"tip": (4.14, 4.20)}}
#: Land et al. 2015: typical relative difference between the groups' fine solutions.
BAND = 0.005
#: One JSON file of levels per problem (two problems can run at once).
OUT = Path(__file__).resolve().parents[1] / "reports" / "land_benchmarks"


def solve_level(problem: str, level: int, load_steps: int = 10) -> dict:
    """Solve one level of one problem and return its row.

    Parameters
    ----------
    problem
        ``"1"``, ``"2"`` or ``"3"``.
    level
        Index into :data:`LEVELS` ``[problem]``.
    load_steps
        Initial load steps (the core's Newton adapts them).

    Returns
    -------
    dict
        ``problem``, ``size`` (the beam: its element length), ``axis_size``, ``tets``,
        ``dofs``, the deformed z of each of :data:`PROBES` (``tip``; ``endo``, ``epi``: mm),
        ``wall`` (s), ``iterations``, ``load_steps``, ``cutbacks``, ``intorder`` and
        ``error`` (empty when the full load was reached).
    """
    import reference_fem
    from springfem.errors import SolverError
    from springfem.scene import scene_from_dict

    mesh, axis = _level(problem, level)
    data = bundled_table(SCENES[problem])
    if problem == "1":
        data["mesh"]["divisions"] = list(mesh)
        size = 10.0 / mesh[0]
    else:
        size = data["mesh"]["size"] = mesh
        data["mesh"].pop("axis_size", None)
        if axis is not None:
            data["mesh"]["axis_size"] = axis
    data["fem"]["load_steps"] = load_steps
    if problem in CURVED:
        data["fem"]["geometry"] = "curved"
    row: dict = {"problem": problem, "size": size, "axis_size": axis}
    t0 = time.perf_counter()
    try:
        r = reference_fem.solve(scene_from_dict(data)).result
    except SolverError as exc:
        return {**row, "error": str(exc), "wall": time.perf_counter() - t0,
                "load_factor": exc.load_factor}  # fmt: skip
    for name, z0 in PROBES[problem]:
        row[name] = z0 + r.probes[name if problem == "1" else f"{name}_apex"][2]
    return {**row, "tets": r.counts["tets"], "dofs": r.counts["dofs"], "wall": r.wall_time,
            "iterations": r.iterations, "load_steps": r.info["load_steps"],
            "cutbacks": r.info["cutbacks"], "intorder": r.info["intorder"],
            "error": ""}  # fmt: skip


def _level(problem: str, level: int):
    """``(mesh, axis size)`` of a level: the beam's divisions, a ventricle's gmsh size."""
    got = LEVELS[problem][level]
    return (got, None) if problem == "1" else got


def load_rows(folder: Path = OUT) -> list[dict]:
    """The rows recorded so far in ``folder`` (``problem<N>.json``), by problem and size."""
    rows = [r for f in sorted(folder.glob("problem*.json")) for r in json.loads(f.read_text())]
    return sorted(rows, key=lambda r: (r["problem"], -r["size"], -(r["axis_size"] or 0.0)))


def merge_row(row: dict, folder: Path = OUT) -> list[dict]:
    """Replace the row of the same (size, axis size) in its problem's file (atomically)."""
    path = folder / f"problem{row['problem']}.json"
    key = (row["size"], row["axis_size"])
    old = json.loads(path.read_text()) if path.exists() else []
    rows = sorted([*(r for r in old if (r["size"], r["axis_size"]) != key), row],
                  key=lambda r: (-r["size"], -(r["axis_size"] or 0.0)))  # fmt: skip
    folder.mkdir(parents=True, exist_ok=True)
    atomic_write_text(path, json.dumps(rows, indent=1) + "\n")
    return rows


def _h(row: dict) -> float:
    """The element size of a level: the beam's length, the axis size of families ``3a`` and
    ``3c``, a ventricle's mean-volume tet edge."""
    if row["problem"] == "1":
        return float(row["size"])
    if row["problem"] in ("3a", "3c"):
        return float(row["axis_size"])
    return float((6.0 * math.sqrt(2.0) * wall_volume() / row["tets"]) ** (1.0 / 3.0))


def extrapolate(rows: list[dict]) -> dict:
    """Per problem and probe: the observed order and Richardson value of the three finest
    converged levels, the coarser triple's order (``order_coarser``, with four levels),
    ``asymptotic`` (both orders within 25 % and in 0.5-6) and :func:`observed_order`'s
    ``note`` (why not, if not)."""
    out: dict = {}
    for problem in sorted({r["problem"] for r in rows}):
        ok = sorted((r for r in rows if r["problem"] == problem and not r.get("error")),
                    key=lambda r: -_h(r))  # fmt: skip
        out[problem] = {}
        for s, _ in PROBES[problem]:
            if len(ok) < 3:
                out[problem][s] = {"order": math.nan, "extrapolated": math.nan,
                                   "order_coarser": math.nan, "asymptotic": False,
                                   "note": "fewer than 3 levels"}  # fmt: skip
                continue
            h, f = [_h(r) for r in ok], [r[s] for r in ok]
            p, f0, note = observed_order(h[-3:], f[-3:])
            q = observed_order(h[-4:-1], f[-4:-1])[0] if len(ok) >= 4 else math.nan
            sure = bool(math.isfinite(p) and math.isfinite(q) and 0.5 <= p <= 6
                        and abs(p - q) <= 0.25 * p)  # fmt: skip
            out[problem][s] = {"order": p, "extrapolated": f0, "order_coarser": q,
                               "asymptotic": sure, "note": note}  # fmt: skip
    return out


def markdown(rows: list[dict]) -> str:
    """The verification table: each level, the extrapolation, pulse's value, the paper's
    range."""
    ext = extrapolate(rows)
    lines = [
        "| problem | mesh | tets | DOFs | z (mm): tip or endo / epi apex | "
        "Newton its / steps / cut-backs | wall (s) |",
        "|---|---|---|---|---|---|---|",
    ]
    for problem in sorted({r["problem"] for r in rows}):
        names = [n for n, _ in PROBES[problem]]
        for r in (r for r in rows if r["problem"] == problem):
            if problem == "1":
                mesh = f"h = {r['size']:g}"
            else:
                mesh = f"{r['size']:g}" + (
                    "" if r["axis_size"] is None else f" / {r['axis_size']:g}"
                )
            if r.get("error"):
                stop = r.get("load_factor") or math.nan
                lines.append(f"| {problem} | {mesh} | | | stopped at load {stop:.3g} | | "
                             f"{r['wall']:.0f} |")  # fmt: skip
                continue
            z = " / ".join(f"{r[n]:.3f}" for n in names)
            lines.append(f"| {problem} | {mesh} | {r['tets']:,} | {r['dofs']:,} | {z} | "
                         f"{r['iterations']} / {r['load_steps']} / {r['cutbacks']} | "
                         f"{r['wall']:.0f} |")  # fmt: skip
        cells = []
        for n in names:
            v = ext[problem][n]
            if not math.isfinite(v["extrapolated"]):
                cells.append(v["note"])
                continue
            coarser = (
                f", coarser {v['order_coarser']:.2g}" if math.isfinite(v["order_coarser"]) else ""
            )
            sure = "" if v["asymptotic"] else ", not shown asymptotic"
            cells.append(f"{v['extrapolated']:.3f} (p = {v['order']:.2g}{coarser}{sure})")
        lines.append(f"| {problem} | Richardson | | | {' / '.join(cells)} | | |")
        if problem in PULSE:
            pub = PULSE[problem]
            z = " / ".join(f"{pub[n]:.2f} (+/- {abs(BAND * pub[n]):.2f})" for n in names)
            lines.append(f"| {problem} | FEniCS-pulse (+/- {100 * BAND:g} %) | | | {z} | | |")
        if problem in PAPER_RANGE:
            z = " / ".join("{:.2f}-{:.2f}".format(*PAPER_RANGE[problem][n]) for n in names)
            lines.append(f"| {problem} | Land et al. 2015, 11 codes | | | {z} | | |")
    return "\n".join(lines)


def rst(rows: list[dict]) -> str:
    """:func:`markdown`'s table as a reStructuredText list table (for docs/verification.rst)."""
    body = [line.strip("|").split("|") for line in markdown(rows).splitlines()]
    out = [".. list-table::", "   :header-rows: 1", ""]
    for cells in [body[0], *body[2:]]:
        for i, c in enumerate(cells):
            text = c.strip().replace("+/- ", "\u00b1 ")
            text = text.replace("-", "\u2212") if i == 4 else text
            out.append((("   * - " if i == 0 else "     - ") + text).rstrip())
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    """Command line: solve one level (``--problem``, ``--level``) or print ``--table``."""
    ap = argparse.ArgumentParser(prog="python -m studies.land_benchmarks")
    ap.add_argument(
        "--problem",
        choices=sorted(SCENES),
        help="3a: problem 3, axis family; 3c: the same, curved geometry",
    )
    ap.add_argument("--level", type=int)
    ap.add_argument("--table", action="store_true")
    ap.add_argument("--rst", action="store_true", help="the table as reStructuredText")
    ap.add_argument("--out", type=Path, default=OUT)
    a = ap.parse_args(argv)
    if a.problem is not None and a.level is not None:
        row = solve_level(a.problem, a.level)
        merge_row(row, a.out)
        print(json.dumps(row))
    if a.table or a.rst:
        print(rst(load_rows(a.out)) if a.rst else markdown(load_rows(a.out)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
