"""The verdict's table and sentences: what :func:`studies.verdict.verdict` has so far, made
into a :class:`Verdict` after every model and at the end.

Examples
--------
>>> t = pd.DataFrame({"model": ["P2", "P1"], "static time (s)": [4.0, 1.0]})
>>> _cheapest(t, "static time (s)")
'P1'
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from springfem.model_api import declared
from springfem.plausibility import check_solution
from springfem.scene import Scene

from . import metrics, models

#: The same mesh's P1 of a reference's law: the model error of a P1-based fast model.
SAME_MESH_P1 = {"P2-NH": "P1-NH", "P2": "P1"}


@dataclass
class Verdict:
    """The outcome of :func:`verdict`.

    Attributes
    ----------
    scene
        The scene's name.
    tolerance
        The error tolerance.
    reference
        The reference model.
    table
        One row per model: status, error, its rank by error, static time, step cost, stable
        step, cost per simulated second, what it solves against the reference's law, and
        whether it is within the tolerance.
    static_pick, dynamic_pick
        The cheapest model within the tolerance for static solves (the reference when no
        other model within it is cheaper) and for explicit dynamics (``None``: none
        qualifies).
    sentence
        The answer in words (:func:`verdict_sentence`).
    ranking
        Every model by its error against the reference (:func:`ranking_line`; the table's
        ``rank`` column).
    notes
        What was skipped, merged or substituted, and why.
    """

    scene: str
    tolerance: float
    reference: str
    table: pd.DataFrame
    static_pick: str | None
    dynamic_pick: str | None
    sentence: str
    notes: list[str] = field(default_factory=list)
    ranking: str = ""


@dataclass
class VerdictState:
    """What the verdict has so far; :meth:`verdict` makes a :class:`Verdict` of it.

    Its fields are filled by :func:`studies.verdict.verdict` as the models finish.
    """

    scene: Scene
    tolerance: float
    names: list[str]
    notes: list[str]
    reference: str = ""
    reference_valid: bool = True
    outcomes: dict = field(default_factory=dict)
    skipped: dict[str, tuple[str, str]] = field(default_factory=dict)
    peaks: dict[str, float] = field(default_factory=dict)
    alias: dict[str, str] = field(default_factory=dict)
    times: dict[str, float] = field(default_factory=dict)
    timed: dict[str, str] = field(default_factory=dict)
    costs: dict[str, tuple[float, float]] = field(default_factory=dict)

    def check_reference(self) -> None:
        """A reference with inverted elements, or strains its law and mesh cannot carry, is
        not valid: it is said, and no model is named against it."""
        got = self.outcomes[self.reference]
        findings = check_solution(self.scene, got.u, got.solution.result.law)
        if findings:
            self.reference_valid = False
            self.notes.append(
                f"the reference {self.reference} is not valid: {findings[0].line}; "
                "no model is named against it"
            )

    def row(self, n: str, u_ref, ref_law: str) -> dict:
        ref, got = self.reference, self.outcomes.get(n)
        first = self.alias.get(n, n)
        if got is None:
            status, why = self.skipped.get(n) or self.skipped.get(first) or ("not run", "")
            return {"model": n, "status": status, "rel L2 error": np.nan,
                    "within tolerance": False, "message": why[:160]}  # fmt: skip
        err = (
            metrics.relative_l2_error(got.u, u_ref)
            if got.ok and u_ref is not None and n != ref
            else (0.0 if n == ref and got.ok else float("nan"))
        )
        step, dt = self.costs.get(first, (float("nan"), float("nan")))
        seconds = self.times.get(first, float(got.seconds))
        return {
            "model": n,
            "status": got.status,
            "rel L2 error": err,
            "static time (s)": seconds,
            "timed": self.timed.get(first, "one solve"),
            "peak memory (GB)": self.peaks.get(first, np.nan) / 1e9,
            "step cost (s)": step,
            "stable step (s)": dt,
            "cost per simulated s": step / dt if np.isfinite(step) and dt > 0 else np.nan,
            "law vs reference": models.law_versus(self.scene, n, ref_law) if ref else "",
            "within tolerance": bool(
                self.reference_valid and got.ok and np.isfinite(err) and err <= self.tolerance
            ),
            "message": got.message[:160],
        }

    def verdict(self, final: bool = False) -> Verdict:
        """The verdict of the models done so far (all of them when ``final``)."""
        from . import models as registry

        scene, ref, names, alias = self.scene, self.reference, self.names, self.alias
        done = [n for n in names
                if n in self.outcomes or alias.get(n, n) in self.outcomes
                or n in self.skipped or alias.get(n, n) in self.skipped]  # fmt: skip
        for n in done:
            if n not in self.outcomes and alias.get(n, n) in self.outcomes:
                self.outcomes[n] = self.outcomes[alias[n]]
        ref_ok = bool(ref) and ref in self.outcomes and self.outcomes[ref].ok
        u_ref = self.outcomes[ref].u if ref_ok else None
        ref_law = self.outcomes[ref].solution.result.law if ref_ok else ""
        table = pd.DataFrame([self.row(n, u_ref, ref_law) for n in done],
                             columns=COLUMNS)  # fmt: skip
        table["within tolerance"] = table["within tolerance"].fillna(False).astype(bool)
        numeric = [c for c in COLUMNS if "(" in c or c in ("rel L2 error", "cost per simulated s")]
        table[numeric] = table[numeric].astype(float)
        p1 = SAME_MESH_P1.get(ref)
        # the model error of the linear-tet models: against the same mesh's P1 of the law
        same_mesh = p1 in done and p1 in self.outcomes and self.outcomes[p1].ok
        if same_mesh:
            u_p1 = self.outcomes[p1].u
            quadratic = {
                n for n in done
                if getattr(declared(registry.get(n), "fem_options", scene), "order", 1) == 2
            }  # fmt: skip
            same = {n for n in done if alias.get(n, n) == alias.get(p1, p1)}  # p1's own solve
            table.insert(3, f"vs {p1} (same mesh)", [
                metrics.relative_l2_error(self.outcomes[n].u, u_p1)
                if n in self.outcomes and self.outcomes[n].ok and n not in same
                and n not in quadratic
                else (0.0 if n in same else float("nan")) for n in done
            ])  # fmt: skip
        same_as_ref = table["model"].map(lambda n: alias.get(n, n) == alias.get(ref, ref))
        ok = table[table["within tolerance"] & (~same_as_ref | (table["model"] == ref))]
        static_pick = _cheapest(ok, "static time (s)") if self.reference_valid else None
        dynamic_pick = _cheapest(ok, "cost per simulated s") if self.reference_valid else None
        if not ref_ok:
            sentence = verdict_sentence(table, "", self.tolerance, None, None)
        elif not self.reference_valid:
            sentence = (
                f"The reference {ref} is not a valid solution of this scene (see the notes): "
                "no model is named."
            )
        else:
            sentence = verdict_sentence(table, ref, self.tolerance, static_pick, dynamic_pick)
        left_out = [n for n in done if str(self.skipped.get(n, ("",))[0]).startswith(
            ("skipped (budget)", "skipped (memory)"))]  # fmt: skip
        if left_out and ref_ok:
            sentence += (
                f" Not weighed for want of time or memory: {', '.join(left_out)} (the table "
                "says why)."
            )
        if not final:
            sentence = f"(part way: {len(done)} of {len(names)} models) " + sentence
        table.insert(3, "rank", rank_by_error(table, ref, same_as_ref))
        v = Verdict(scene.name, self.tolerance, ref, table, static_pick, dynamic_pick,
                    sentence, list(self.notes))  # fmt: skip
        v.ranking = ranking_line(table, ref) if ref_ok else ""
        if ref_ok and same_mesh:
            v.ranking += " " + same_mesh_line(table, ref, p1, same_as_ref)
        return v


#: The verdict table's columns (a ``rank`` and a same-mesh column are inserted after ``rel L2
#: error``).
COLUMNS = [
    "model", "status", "rel L2 error", "static time (s)", "timed", "peak memory (GB)",
    "step cost (s)", "stable step (s)", "cost per simulated s", "law vs reference",
    "within tolerance", "message",
]  # fmt: skip


def _cheapest(rows: pd.DataFrame, column: str) -> str | None:
    rows = rows[np.isfinite(rows[column])]
    return None if rows.empty else str(rows.loc[rows[column].idxmin(), "model"])


def _unlike(row: pd.Series) -> str:
    what = row.get("law vs reference", "same law")
    return "" if what in ("same law", "") else f" ({what}, not the reference's law)"


def verdict_sentence(
    table: pd.DataFrame,
    ref: str,
    tol: float,
    static_pick: str | None,
    dynamic_pick: str | None,
) -> str:
    """The verdict in at most two short sentences: the cheapest model within the tolerance
    for a static solve, its error and its time as a ratio to the reference's; the same for
    explicit dynamics (per simulated second, against explicit P1) when a model qualifies.

    A model that solves another law than the reference (``law vs reference``) is marked so,
    and no speed is called faster or slower: the ratio is a ratio of times.

    Parameters
    ----------
    table
        The verdict's table.
    ref
        The reference model.
    tol
        The tolerance.
    static_pick, dynamic_pick
        The picks.

    Returns
    -------
    str

    Examples
    --------
    >>> t = pd.DataFrame({"model": ["P2", "P1", "spring-exact"], "rel L2 error": [0, .02, .03],
    ...     "static time (s)": [4.0, 1.0, 2.0], "cost per simulated s": [np.nan, 9.0, 12.0],
    ...     "law vs reference": ["same law", "same law", "small-strain calibration"]})
    >>> print(verdict_sentence(t, "P2", 0.05, "P1", "spring-exact"))
    P1 is the cheapest static solve within 5% of P2: 2% off, in 0.25× the reference's time. \
For explicit dynamics spring-exact (small-strain calibration, not the reference's law) is: \
3% off, 12 s per simulated second, 1.33× explicit P1's.
    """
    t = table.set_index("model")
    within = f"within {pct(tol)} of {ref}"
    if not ref:
        return "No FEM reference finished: no error, no verdict."
    if static_pick and static_pick != ref:
        r = t.loc[static_pick]
        ratio = r["static time (s)"] / t.at[ref, "static time (s)"]
        in_time = f", in {ratio:.2g}× the reference's time" if np.isfinite(ratio) else ""
        first = (
            f"{static_pick}{_unlike(r)} is the cheapest static solve {within}: "
            f"{pct(r['rel L2 error'])} off{in_time}."
        )
    else:
        others = t[(t["rel L2 error"] > 0) & np.isfinite(t["rel L2 error"])]
        good = others[others["rel L2 error"] <= tol]
        if not good.empty:  # within it, but dearer than the reference
            n = good["static time (s)"].idxmin()
            ratio = good.at[n, "static time (s)"] / t.at[ref, "static time (s)"]
            rest = f"{n} ({pct(good.at[n, 'rel L2 error'])} off) takes {ratio:.2g}× its time"
        elif not others.empty:
            n = others["rel L2 error"].idxmin()
            rest = f"no other model is (closest: {n}, {pct(others.at[n, 'rel L2 error'])} off)"
        else:
            rest = "no other model is"
        first = f"{ref}, the reference, is the cheapest static solve {within}: {rest}."
    if not dynamic_pick:
        return first
    r = t.loc[dynamic_pick]
    cost = r["cost per simulated s"]
    vs = ""
    if dynamic_pick != "P1" and "P1" in t.index and np.isfinite(t.at["P1", "cost per simulated s"]):
        vs = f", {cost / t.at['P1', 'cost per simulated s']:.3g}× explicit P1's"
    if dynamic_pick == static_pick:
        return f"{first} For explicit dynamics it is too: {cost:.3g} s per simulated second{vs}."
    return (
        f"{first} For explicit dynamics {dynamic_pick}{_unlike(r)} is: "
        f"{pct(r['rel L2 error'])} off, {cost:.3g} s per simulated second{vs}."
    )


# -- the ranking: by the error against the reference, and against the same mesh's P1 ----


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
