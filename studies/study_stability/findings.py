"""Findings and headline numbers of the stability study."""

from __future__ import annotations

import pandas as pd

from .cases import LOAD_METHODS, LOCK_METHODS, Settings


def report_findings(f: dict[str, pd.DataFrame], q: Settings) -> tuple[list[str], dict[str, float]]:
    """One finding per series (critical step, largest load, locking) and the headline.

    Parameters
    ----------
    f
        The series' frames (:func:`~.tables.frames`).
    q
        The study's settings.

    Returns
    -------
    findings : list of str
    headline : dict
        Median measured/predicted step per method, largest load solved per method, tip
        ratio at the largest ν per method.
    """
    findings: list[str] = []
    headline: dict[str, float] = {}
    ratios = f["dt"].groupby("method")["ratio"].median()
    for m, r in ratios.items():
        headline[f"dt_ratio_{m}"] = round(float(r), 2)
    findings.append(
        "Measured/predicted critical step (median over meshes): "
        + ", ".join(f"{m} {r:.2f}" for m, r in ratios.items())
        + " — the linearised bound 2/ω_max predicts the explicit limit of the gradient-"
        "consistent models; a ratio far from 1 flags forces whose linearisation misleads."
    )

    dl = f["load"]
    survive = {}
    for m in LOAD_METHODS:
        ok = dl[(dl.method == m) & (dl.status == "ok")]["load_factor"]
        survive[m] = float(ok.max()) if len(ok) else 0.0
        headline[f"max_load_{m}"] = survive[m]
    findings.append(
        "Largest load factor solved without failure: "
        + ", ".join(f"{m} {v:g}" for m, v in survive.items())
        + "; failures are recorded as 'diverged' (solver), 'inverted' (J ≤ 0 elements) or, "
        "for linear FEM, 'unphysical' (tip deflection beyond 10% of the length, where "
        "small-strain kinematics no longer describe the bar)."
    )

    dk = f["lock"]
    hi = dk[dk.nu == max(q.nus)].set_index("method")["tip_ratio"]
    for m in LOCK_METHODS:
        headline[f"locking_tip_ratio_{m}"] = round(float(hi[m]), 3)
    findings.append(
        f"Near incompressibility (ν = {max(q.nus)}) the P1 cantilever keeps "
        f"{hi['fem-p1']:.0%} of the Timoshenko deflection (locking), P2 {hi['fem-p2']:.0%}, "
        f"the spring model {hi['spring']:.0%}"
        + (
            f", the exact spring element {hi['spring-exact']:.0%}: it is P1's element at "
            "small strain, so it locks like P1 — the seed model's freedom from locking is its "
            "calibration error, not a virtue of springs."
            if "spring-exact" in hi.index
            else "."
        )
    )
    return findings, headline
