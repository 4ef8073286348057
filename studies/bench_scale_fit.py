"""The laws of ``springfem bench scale``: power laws fitted to its cases, and what they say.

Each model's static solve time, explicit step time and peak memory are fitted in log-log
(``np.polyfit``) as ``a (tets / 1e4)^b`` over the sizes the model solved
(:func:`power_law`). The memory law is fitted to the sizes whose peak is at least
:data:`DOMINANT` times the process's warm baseline (imports, compiled kernels: the same at
every size) when two or more are, so that the baseline does not flatten the exponent that
the extrapolation to large meshes rests on; else to every size solved.

:func:`laws` gives them in the form the verdict's cost model reads (``studies/cost_laws.json``,
:func:`cost_laws_document`), :func:`largest_tets` the largest mesh a law allows in a given
memory or time.

Examples
--------
>>> tets = np.array([5e3, 3e4, 1.2e5])
>>> a, b = power_law(tets, 2.0 * (tets / 1e4) ** 1.5)
>>> round(a, 6), round(b, 6)
(2.0, 1.5)
>>> round(largest_tets((2.0, 1.5), 16.0))  # 2 (N/1e4)^1.5 = 16: N = 4e4
40000
"""

from __future__ import annotations

import datetime
import platform

import numpy as np
import pandas as pd

#: Tets of the laws' unit size: ``value = a (tets / UNIT)^b``.
UNIT = 1e4
#: A size's peak memory counts for the memory law when it is at least this many times the
#: process's warm baseline (with two or more such sizes).
DOMINANT = 2.0
#: The statuses of a case whose static solve finished (its time and memory count).
SOLVED = ("ok", "implausible")
#: The memory of the machine the benchmark speaks of (bytes): where one machine ends.
MACHINE_BYTES = 24e9
#: Exponents a law from one size assumes (static time, memory, explicit step): such a law
#: is only a size-aware stand-in for the cost model, and the laws table gives no
#: extrapolation from it.
ASSUMED = {"time": 1.5, "memory": 1.0, "step": 1.0}


def power_law(tets, values) -> tuple[float, float]:
    """``(a, b)`` of ``values = a (tets / 1e4)^b``, least squares in log-log.

    Parameters
    ----------
    tets
        Mesh sizes (two or more distinct).
    values
        Positive values, one per size.

    Returns
    -------
    tuple of float

    Raises
    ------
    ValueError
        Fewer than two distinct sizes, or a value that is not positive.
    """
    x = np.log(np.asarray(tets, dtype=float) / UNIT)
    y = np.asarray(values, dtype=float)
    if len(np.unique(x)) < 2:
        raise ValueError("a power law needs two or more distinct sizes")
    if not np.all(y > 0):
        raise ValueError("a power law needs positive values")
    b, log_a = np.polyfit(x, np.log(y), 1)
    return float(np.exp(log_a)), float(b)


def evaluate(law: tuple[float, float], tets) -> np.ndarray:
    """``a (tets / 1e4)^b``.

    Parameters
    ----------
    law
        ``(a, b)``.
    tets
        Sizes.

    Returns
    -------
    numpy.ndarray
    """
    a, b = law
    return a * (np.asarray(tets, dtype=float) / UNIT) ** b


def largest_tets(law: tuple[float, float], limit: float) -> float:
    """The size at which the law reaches ``limit`` (``inf`` when it does not grow).

    Parameters
    ----------
    law
        ``(a, b)``.
    limit
        The value.

    Returns
    -------
    float
    """
    a, b = law
    if b <= 0:
        return float("inf")
    return float(UNIT * (limit / a) ** (1.0 / b))


#: An extrapolation beyond this many times the largest size a law was fitted to is marked
#: a guess (a decade of extrapolation is already one).
REACH = 10.0


def _extrapolated(law: tuple[float, float], limit: float, sizes: list[int]) -> tuple[float, str]:
    """The size at which ``law`` reaches ``limit`` and how it is known (a guess beyond
    :data:`REACH` times the largest of ``sizes``)."""
    n = largest_tets(law, limit)
    top = max(sizes)
    if not np.isfinite(n):
        return np.nan, "the law does not grow"
    if n > REACH * top:
        return n, f"extrapolated {n / top:.0f}x beyond the largest size fitted: a guess"
    return (
        n,
        f"extrapolated ({len(sizes)} sizes)" if n > top else f"interpolated ({len(sizes)} sizes)",
    )


def _fit(
    rows: pd.DataFrame, column: str, assume: float | None = None
) -> tuple[float, float] | None:
    """The power law of ``column`` over ``rows``; from one size, the law of exponent
    ``assume`` through it (``None``: no law)."""
    rows = rows[np.isfinite(rows[column].astype(float)) & (rows[column].astype(float) > 0)]
    if rows["tets"].nunique() < 2:
        if rows.empty or assume is None:
            return None
        n, v = float(rows["tets"].iloc[-1]), float(rows[column].iloc[-1])
        return v / (n / UNIT) ** assume, assume
    return power_law(rows["tets"], rows[column])


def model_laws(cases: pd.DataFrame) -> dict[str, dict]:
    """Each model's fitted laws from the measured cases of :mod:`studies.bench_scale`.

    Parameters
    ----------
    cases
        One row per case: ``model``, ``tets``, ``status``, ``static (s)``, ``step (s)``,
        ``peak memory (bytes)``, ``baseline (bytes)``.

    Returns
    -------
    dict
        ``model -> {"time": (a, b) or None, "memory": ..., "step": ..., "sizes": [...],
        "memory sizes": [...], "memory above baseline": bool, "step sizes": [...]}``
        (``sizes``: the tets of the sizes solved; ``memory above baseline``: the memory law is
        fitted to two or more sizes at least :data:`DOMINANT` times the baseline); from one
        size a law has the :data:`ASSUMED` exponent, and ``assumed`` names those laws.
    """
    out = {}
    for name, rows in cases.groupby("model", sort=False):
        solved = rows[rows["status"].isin(SOLVED)].sort_values("tets")
        dominant = solved[solved["peak memory (bytes)"] >= DOMINANT * solved["baseline (bytes)"]]
        above = dominant["tets"].nunique() >= 2
        memory_rows = dominant if above else solved
        stepped = rows[np.isfinite(rows["step (s)"].astype(float))].sort_values("tets")
        out[str(name)] = {
            "time": _fit(solved, "static (s)", ASSUMED["time"]),
            "memory": _fit(memory_rows, "peak memory (bytes)", ASSUMED["memory"]),
            "step": _fit(stepped, "step (s)", ASSUMED["step"]),
            "assumed": [
                k
                for k, r in (("time", solved), ("memory", memory_rows), ("step", stepped))
                if r["tets"].nunique() == 1
            ],
            "sizes": [int(n) for n in solved["tets"]],
            "memory sizes": [int(n) for n in memory_rows["tets"]],
            "memory above baseline": bool(above),
            "step sizes": [int(n) for n in stepped["tets"]],
        }
    return out


def cost_laws_document(
    laws: dict[str, dict], machine: str | None = None, aliases: dict[str, str] | None = None
) -> dict:
    """The laws as the verdict's cost model reads them::

        {"machine": "...", "date": "...",
         "laws": {"<model>": {"time": [a, b], "memory": [c, d], "step": [e, f],
                              "sizes": [...]}}}

    with ``time_s = a (tets/1e4)^b``, ``memory_bytes = c (tets/1e4)^d``,
    ``step_s = e (tets/1e4)^f``; ``step`` is left out for a model without an explicit form,
    and a model no size of which was solved is left out. A law from one size has the
    :data:`ASSUMED` exponent (its ``sizes`` says so). ``aliases`` names models that are the
    same solve as a measured one (the scene's ``spring`` as ``spring-stabilised`` on the
    organ): they get its laws.

    Parameters
    ----------
    laws
        :func:`model_laws`.
    machine
        A description of the machine (default: cores, memory, processor).
    aliases
        Model -> the measured model it is the same solve as.

    Returns
    -------
    dict
    """
    out: dict[str, dict] = {}
    for name, law in laws.items():
        if law["time"] is None or law["memory"] is None:
            continue
        entry: dict = {"time": list(law["time"]), "memory": list(law["memory"])}
        if law["step"] is not None:
            entry["step"] = list(law["step"])
        entry["sizes"] = list(law["sizes"])
        out[name] = entry
    for name, first in (aliases or {}).items():
        if first in out and name not in out:
            out[name] = dict(out[first])
    now = datetime.datetime.now(datetime.UTC)
    return {"machine": machine or machine_description(), "date": now.strftime("%Y-%m-%d"),
            "laws": out}  # fmt: skip


def machine_description() -> str:
    """Cores, memory and processor of this machine, in one line."""
    import os

    memory = ""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            kb = int(f.readline().split()[1])
        memory = f", {kb / 1024**2:.0f} GB"
    except (OSError, ValueError, IndexError):
        pass
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="ascii", errors="replace") as f:
            names = [ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name")]
        cpu = names[0] if names else cpu
    except OSError:
        pass
    return f"{os.cpu_count()} cores{memory}, {cpu}, {platform.system()}"


def laws_table(
    laws: dict[str, dict], cases: pd.DataFrame, machine_bytes: float = MACHINE_BYTES,
    hour: float = 3600.0,
) -> pd.DataFrame:  # fmt: skip
    """One row per model: its exponents and coefficients, the largest size it solved, the
    largest mesh whose memory law stays under ``machine_bytes`` (extrapolated, or measured
    when a measured case was at or above it) and the largest whose static solve takes an
    hour (extrapolated); an extrapolation more than :data:`REACH` times beyond the sizes
    measured is marked a guess.

    Parameters
    ----------
    laws
        :func:`model_laws`.
    cases
        The cases.
    machine_bytes
        The machine's memory.
    hour
        The static solve time of the last column (s).

    Returns
    -------
    pandas.DataFrame
    """
    rows = []
    gb = machine_bytes / 1e9
    for name, law in laws.items():
        mine = cases[cases["model"] == name]
        solved = mine[mine["status"].isin(SOLVED)]
        largest = int(solved["tets"].max()) if not solved.empty else np.nan
        failed = mine[mine["status"].str.startswith("did not fit")]
        row = {
            "model": name,
            "sizes solved": len(law["sizes"]),
            "largest solved (tets)": largest,
            "first did not fit (tets)": int(failed["tets"].min()) if not failed.empty else np.nan,
            "assumed exponents": ", ".join(law["assumed"]),
            "time a (s)": law["time"][0] if law["time"] else np.nan,
            "time b": law["time"][1] if law["time"] else np.nan,
            "memory c (GB)": law["memory"][0] / 1e9 if law["memory"] else np.nan,
            "memory d": law["memory"][1] if law["memory"] else np.nan,
            "step e (ms)": law["step"][0] * 1e3 if law["step"] else np.nan,
            "step f": law["step"][1] if law["step"] else np.nan,
        }
        over = solved["peak memory (bytes)"] >= machine_bytes
        if over.any():  # a measured case at or over it: the largest measured under it
            under = solved.loc[~over, "tets"]
            row[f"largest in {gb:.0f} GB (tets)"] = under.max() if not under.empty else np.nan
            row[f"in {gb:.0f} GB"] = "measured"
        elif law["memory"] is not None and "memory" in law["assumed"]:
            row[f"largest in {gb:.0f} GB (tets)"] = np.nan
            row[f"in {gb:.0f} GB"] = "no law: one size"
        elif law["memory"] is not None and not law["memory above baseline"]:
            row[f"largest in {gb:.0f} GB (tets)"] = np.nan
            row[f"in {gb:.0f} GB"] = "no law: every size near the baseline"
        elif law["memory"] is not None:
            n, how = _extrapolated(law["memory"], machine_bytes, law["memory sizes"])
            row[f"largest in {gb:.0f} GB (tets)"], row[f"in {gb:.0f} GB"] = n, how
        else:
            row[f"largest in {gb:.0f} GB (tets)"] = np.nan
            row[f"in {gb:.0f} GB"] = "no law"
        if law["time"] is not None and "time" in law["assumed"]:
            n, how = np.nan, "no law: one size"
        elif law["time"] is not None:
            n, how = _extrapolated(law["time"], hour, law["sizes"])
        else:
            n, how = np.nan, "no law"
        row["static in 1 h (tets)"], row["in 1 h"] = n, how
        rows.append(row)
    return pd.DataFrame(rows)
