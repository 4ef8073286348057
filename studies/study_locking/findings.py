"""Findings of the locking study: the cheapest adequate method per Poisson ratio, which
methods lock, the references, and the headline numbers."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from springfem.materials.tissue import TISSUE_LAWS

from .cases import COSTLIER, REFERENCE, TOLERANCE

#: The methods whose error at the most incompressible ratio and finest level is a headline
#: number: those that solve well inside the quick preset's cap, so that the headline does
#: not depend on the machine's speed (the stabilised spring elements and displacement P2
#: can take the cap on a busy machine; the cheapest method depends on timings too).
HEADLINE_METHODS = ("P1", "P1-nodal-volume", "P1-nodal-strain", "MINI", "spring-spec",
                    "spring-exact", "spring-nodal-volume")  # fmt: skip


def _name(row: pd.Series) -> str:
    return f"{row['cheapest within tolerance']} on {int(row['its tets'])} tets"


def answer_sentences(answers: pd.DataFrame, tolerance: float = TOLERANCE) -> list[str]:
    """One sentence per scene: the cheapest method within ``tolerance`` at each nu.

    Examples
    --------
    >>> a = pd.DataFrame({"scene": "s", "nu": [0.3, 0.4999],
    ...     "cheapest within tolerance": ["P1", "none"], "its tets": [6, np.nan],
    ...     "its error": [0.01, np.nan], "its seconds": [0.1, np.nan],
    ...     "reference seconds": [2.0, 3.0]})
    >>> s = answer_sentences(a)[0]
    >>> "at ν = 0.3, P1 on 6 tets (error 1.0%, 0.1 s" in s, "at ν = 0.4999, none:" in s
    (True, True)
    """
    out = []
    for scene, g in answers.groupby("scene", sort=False):
        parts = []
        for _, r in g.iterrows():
            if r["cheapest within tolerance"] == "none":
                parts.append(f"at ν = {r.nu:g}, none: no method other than the reference is "
                             f"within {tolerance:.0%}")  # fmt: skip
            else:
                parts.append(
                    f"at ν = {r.nu:g}, {_name(r)} (error {r['its error']:.1%}, "
                    f"{r['its seconds']:.2g} s; the reference {r['reference seconds']:.2g} s)"
                )
        out.append(
            f"{scene}: the cheapest method within {tolerance:.0%} of the converged {REFERENCE} "
            "deflection is, " + "; ".join(parts) + "."
        )
        if "cheapest on linear tets" in g:
            lin = [
                f"ν = {r.nu:g}: "
                + (
                    "none"
                    if r["cheapest on linear tets"] == "none"
                    else f"{r['cheapest on linear tets']} on {int(r['its tets (linear)'])} tets "
                    f"({r['its error (linear)']:.1%}, {r['its seconds (linear)']:.2g} s)"
                )
                for _, r in g.iterrows()
            ]
            out.append(
                f"{scene}: on linear tets (P1-type FEM, spring elements) the cheapest within "
                f"{tolerance:.0%} is: " + "; ".join(lin) + "."
            )
    return out


def locking_sentence(df: pd.DataFrame) -> list[str]:
    """Per scene: the finest-level deflection of every method at the highest nu, as a share
    of the reference (locked methods keep a small share)."""
    out = []
    for scene, g in df.groupby("scene", sort=False):
        nu = g.nu.max()
        top = g[(g.nu == nu) & (g.factor == g.factor.max())]
        if not (top.status == "ok").any():
            continue  # nothing solved there (skipped by the budget)
        shares = []
        for _, r in top.iterrows():
            if r.status == "ok":
                shares.append(f"{r.method} {r.deflection / r.ref_value:.0%}")
            else:
                load = f" at load {r.load:.2g}" if np.isfinite(r.load) else ""
                shares.append(f"{r.method} {r.status}{load}")
        out.append(
            f"{scene} at ν = {nu:g}, finest level ({int(top.tets.max())} tets): deflection as a "
            "share of the reference: " + ", ".join(shares) + "."
        )
    return out


def costlier_sentences(df: pd.DataFrame, left: pd.DataFrame) -> list[str]:
    """Per scene: the cases not run because they could not be the cheapest
    (:attr:`~.cases.Settings.skip_costlier`), and each such method's error at the lowest and
    highest ν on the finest level where it ran at both (a rise with ν is locking).

    Examples
    --------
    >>> df = pd.DataFrame({"scene": "s", "method": "P2", "nu": [0.3, 0.4999, 0.4999],
    ...     "tets": [24, 24, 192], "status": ["ok", "ok", "skipped"],
    ...     "error": [0.03, 0.2, np.nan]})
    >>> text = costlier_sentences(df, df[df.status == "skipped"])[0]
    >>> "P2 at ν = 0.4999 on 192 tets; where it ran, P2 is 3.0% off at ν = 0.3" in text
    True
    >>> "and 20.0% at ν = 0.4999 on 24 tets" in text
    True
    """
    out = []
    for scene, g in left.groupby("scene", sort=False):
        parts = []
        for m, x in g.groupby("method", sort=False):
            where = "; ".join(f"ν = {nu:g} on {', '.join(str(int(t)) for t in sorted(y.tets))} "
                              "tets" for nu, y in x.groupby("nu"))  # fmt: skip
            ran = df[(df.scene == scene) & (df.method == m) & (df.status == "ok")]
            if "reference" in ran:
                ran = ran[~ran.reference.astype(bool)]
            lo, hi = df.nu.min(), df.nu.max()
            both = sorted(set(ran[ran.nu == lo].tets) & set(ran[ran.nu == hi].tets))
            text = f"{m} at {where}"
            if both and lo < hi:
                t = both[-1]
                e = {nu: float(ran[(ran.nu == nu) & (ran.tets == t)].error.iloc[0])
                     for nu in (lo, hi)}  # fmt: skip
                text += (f"; where it ran, {m} is {e[lo]:.1%} off at ν = {lo:g} and "
                         f"{e[hi]:.1%} at ν = {hi:g} on {int(t)} tets")  # fmt: skip
            parts.append(text)
        out.append(
            f"{scene}: not run where they cannot be the cheapest of their kind of tets (on a "
            f"coarser level a method on the same tets was within {TOLERANCE:.0%} in less than "
            "their predicted time, or at least twice as accurate and no slower; the cases "
            "table gives each reason): " + "; ".join(parts) + ". An error "
            "that rises with ν on one mesh is locking."
            + (
                " Displacement P2 locks as ν → 1/2, and its Newton solve on the stiffening "
                "penalty takes hundreds of iterations there (274 on the quick beam's 486 tets "
                "at ν = 0.4999), while P2/P1 on the coarsest mesh is within the tolerance in "
                "a fraction of a second."
                if "P2" in set(g.method)
                else ""
            )
        )
    return out


#: Why a reference has no extrapolation.
NO_EXTRAPOLATION = "— (none possible: fewer than three levels, or values not monotone)"


def reference_sentence(refs: pd.DataFrame) -> list[str]:
    """Per scene: the reference values and how far a Richardson extrapolation moves them."""
    out = []
    for scene, g in refs.groupby("scene", sort=False):
        vals = ", ".join(
            (
                f"ν = {r.nu:g}: {r.reference:.4g}"
                if np.isfinite(r.reference)
                else f"ν = {r.nu:g}: none ({REFERENCE} did not solve)"
            )  # fmt: skip
            + (
                f" (Richardson {r.richardson:.4g}, order {r['observed order']:.2g})"
                if np.isfinite(r.richardson)
                else ""
            )
            for _, r in g.iterrows()
        )
        shift = g["extrapolation shift"].max()
        out.append(
            f"{scene}: the reference u_{g.axis.iloc[0]} is {REFERENCE} on the finest level "
            f"({int(g.tets.max()) if g.tets.notna().any() else 0} tets): {vals}. The "
            "extrapolations move it by at most "
            + (f"{shift:.1%}" if np.isfinite(shift) else NO_EXTRAPOLATION)
            + "; they are shown, not used, because three levels cannot show the order to be "
            "asymptotic."
        )
    return out


def report_findings(
    df: pd.DataFrame,
    refs: pd.DataFrame,
    answers: pd.DataFrame,
    laws: dict[str, str],
    max_time: float,
) -> tuple[list[str], dict[str, float]]:
    """The findings and the headline numbers (per scene and nu: the cheapest method's
    error, and the finest-level error of every method at the highest nu)."""
    findings = answer_sentences(answers)
    findings += locking_sentence(df)
    findings += reference_sentence(refs)
    tissue = [s for s, law in laws.items() if law in TISSUE_LAWS]
    if tissue:
        findings.append(
            f"{', '.join(tissue)}: a tissue law has its own shear response, so ν only sets "
            "its volumetric penalty, κ = 2μ(1 + ν) / (3(1 − 2ν)) with μ the mean shear "
            "modulus of the law's small-strain tangent; an incompressible scene is solved "
            "nearly incompressible at each ν (Land's beam: κ/μ = 500 at ν = 0.499, "
            "5000 at 0.4999)."
        )
    skipped = df[df.status == "skipped"]
    costlier = skipped.message.astype(str).str.contains(COSTLIER, regex=False)
    over = skipped[~costlier]
    if len(over):
        which = ", ".join(f"{m} ({len(x)})" for m, x in over.groupby("method", sort=False))
        findings.append(
            f"Not run (count): {which}: their predicted time (DOFs × the method's measured "
            f"cost per DOF) was over the {max_time:g} s cap of a solve or the study's "
            "budget; a method within 5 % on a coarser level does not run its finer levels "
            "either (they cannot be cheaper)."
        )
    findings += costlier_sentences(df, skipped[costlier])
    stopped = df[~df.status.isin(["ok", "skipped"])]
    if len(stopped):
        which = ", ".join(f"{m} ({len(x)})" for m, x in stopped.groupby("method", sort=False))
        # a stopped solve could only have been the answer where no adequate method is
        # faster than the cap
        open_ = [
            f"{r.scene} ν = {r.nu:g}"
            for _, r in answers.iterrows()
            if not (r["its seconds"] < max_time)
            and len(stopped[(stopped.scene == r.scene) & (stopped.nu == r.nu)])
        ]
        findings.append(
            f"Solves that stopped at the {max_time:g} s cap or failed (count): {which}. "
            + (
                "Where they stopped, a method within the tolerance solved in less than the "
                "cap, so none of them could have been the cheapest."
                if not open_
                else "The answer may miss a slower method at " + ", ".join(open_) + "."
            )
        )
    headline: dict[str, float] = {}
    for _, r in answers.iterrows():
        headline[f"cheapest_error_{r.scene}_nu{r.nu:g}"] = float(r["its error"])
    nu = df.nu.max()
    for (scene, m), g in df[df.nu == nu].groupby(["scene", "method"], sort=False):
        fine = g[g.factor == g.factor.max()]
        if m in HEADLINE_METHODS and len(fine) and not fine.reference.iloc[0]:
            ok = fine.status.iloc[0] == "ok"
            value = round(float(fine.error.iloc[0]), 4) if ok else math.nan
            headline[f"error_{scene}_{m}_nu{nu:g}"] = value
    return findings, headline
