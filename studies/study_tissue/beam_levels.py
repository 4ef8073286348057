"""Land's problem-1 beam on three meshes: the P2/P1 mixed FEM's tip z, observed order and
Richardson value beside the published range of the 11 codes (4.14-4.20 mm).

The box meshes are structured (``n x n/10 x n/10`` divisions of the 10 x 1 x 1 mm beam), so
the element length ``h = 10 / n`` mm is exact; the finest level is the study's own beam
mesh, whose FEM case the cache shares with the beam measurement.

Examples
--------
>>> cases = [{"divisions": [n, n // 10, n // 10]} for n in (10, 20, 40)]
>>> results = [{"tip_z": 4.17 - 0.1 / n**2, "wall_time": 1.0, "error": ""} for n in (10, 20, 40)]
>>> df = beam_levels_frame(cases, results)
>>> round(float(df.tip_z.iloc[-1]), 6), df.mesh.iloc[-1]
(4.17, 'Richardson (p = 2)')
"""

from __future__ import annotations

import math

import pandas as pd

from ..scenes import StudyScene
from .convergence import observed_order

#: The published range of the deformed z of (10, 0.5, 1) mm over Land et al.'s 11 codes.
PUBLISHED_RANGE = (4.14, 4.20)


def beam_level_scenes(finest: tuple[int, int, int]) -> list[StudyScene]:
    """The beam at a third, two thirds and all of ``finest``'s divisions (role ``beam-level``).

    Parameters
    ----------
    finest
        The study's beam divisions; three levels need the cross-section's divisions to be a
        multiple of 3 (otherwise the one level).

    Returns
    -------
    list of StudyScene
    """
    nx, ny, nz = finest
    if ny % 3 or nz % 3 or nx % 3:
        levels = [finest]
    else:
        levels = [(nx * k // 3, ny * k // 3, nz * k // 3) for k in (1, 2, 3)]
    out = []
    for d in levels:
        s = StudyScene.bundled("land-beam", {"mesh.divisions": list(d)}, roles=("beam-level",))
        out.append(s)
    return out


def beam_levels_frame(cases: list[dict], results: list[dict]) -> pd.DataFrame:
    """One row per level (``h``, tip z, wall time) and a Richardson row when three converged.

    Parameters
    ----------
    cases
        The level cases (their ``divisions``, or the table's ``mesh.divisions``).
    results
        :func:`~.cases.beam_case` results.

    Returns
    -------
    pandas.DataFrame
        ``mesh``, ``h``, ``tip_z``, ``wall_time``, ``error``, ``published_range``.
    """
    rows = []
    for c, r in zip(cases, results, strict=True):
        d = c.get("divisions") or c["table"]["mesh"]["divisions"]
        rows.append({"mesh": "x".join(map(str, d)), "h": 10.0 / d[0], "tip_z": r["tip_z"],
                     "wall_time": r["wall_time"], "error": r["error"]})  # fmt: skip
    ok = [r for r in rows if not r["error"] and math.isfinite(r["tip_z"])]
    if len(ok) >= 3:
        p, f0, note = observed_order([r["h"] for r in ok[-3:]], [r["tip_z"] for r in ok[-3:]])
        label = f"Richardson (p = {p:.2g})" if math.isfinite(p) else f"Richardson: {note}"
        rows.append({"mesh": label, "h": 0.0, "tip_z": f0, "wall_time": math.nan, "error": ""})
    df = pd.DataFrame(rows)
    df["published_range"] = "{:.2f}-{:.2f}".format(*PUBLISHED_RANGE)
    return df


def beam_levels_finding(df: pd.DataFrame) -> list[str]:
    """One sentence: the finest level and the extrapolated tip z against the published range."""
    rich = df[df.mesh.str.startswith("Richardson")]
    if not len(rich):
        return []
    f0, finest = float(rich.tip_z.iloc[0]), df.iloc[-2]
    lo, hi = PUBLISHED_RANGE
    inside = "inside" if lo <= f0 <= hi else "outside"
    return [f"Land problem 1 (beam), P2/P1 mixed on {len(df) - 1} meshes: tip z "
            f"{finest.tip_z:.4f} mm on {finest.mesh}, {rich.mesh.iloc[0]} {f0:.4f} mm, "
            f"{inside} the 11 codes' {lo:.2f}-{hi:.2f} mm."]  # fmt: skip
