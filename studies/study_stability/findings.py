"""Findings and headline numbers of the stability study."""

from __future__ import annotations

import pandas as pd

from .. import models
from .cases import LOCK_METHODS, UNPHYSICAL, Settings, own_steppers

#: Failure-map statuses of a run that ended (not stopped or skipped by the budget).
RAN = ("ok", "inverted", "blew up")


def report_findings(f: dict[str, pd.DataFrame], q: Settings) -> tuple[list[str], dict[str, float]]:
    """One finding per series that ran, and the headline: the median measured/predicted step
    per method (over the scenes), the largest load solved per method, the tip ratio at the
    largest ν per method, the share of the failure map that runs ok per method.
    """
    findings: list[str] = []
    headline: dict[str, float] = {}
    if len(f["dt"]):
        ratios = f["dt"].groupby("method", sort=False)["ratio"].median()
        for m, r in ratios.items():
            headline[f"dt_ratio_{m}"] = round(float(r), 2)
        own = own_steppers(models.plugins())  # a plug-in's own step search: own finding
        explicit = ratios[[m not in own for m in ratios.index]]
        findings.append(
            "Measured/predicted critical step (median over meshes): "
            + ", ".join(f"{m} {r:.2f}" for m, r in explicit.items())
            + " — the linearised bound 2/ω_max predicts the explicit limit of the gradient-"
            "consistent models; a ratio far from 1 flags forces whose linearisation misleads."
        )
        findings += own_step_findings(f["dt"], headline)
    dl = f["load"]
    if len(dl):
        first = dl[dl.scene == dl.scene.iloc[0]]
        survive = {}
        for m in dict.fromkeys(first["method"]):
            ok = first[(first.method == m) & (first.status == "ok")]["load_factor"]
            survive[m] = float(ok.max()) if len(ok) else 0.0
            headline[f"max_load_{m}"] = survive[m]
        factors = ", ".join(f"{x:g}" for x in dict.fromkeys(first["load_factor"]))
        findings.append(
            f"Largest load factor solved without failure ({dl.scene.iloc[0]}, of {factors}): "
            + ", ".join(f"{m} {v:g}" for m, v in survive.items())
            + "; failures are recorded as 'diverged' (solver), 'inverted' (J ≤ 0 elements) "
            f"or, for a small-strain law, 'unphysical' (largest displacement beyond "
            f"{UNPHYSICAL:.0%} of the body's size, where small-strain kinematics no longer "
            "describe the body)."
        )
    dk = f["lock"]
    if len(dk):
        hi = dk[dk.nu == max(q.nus)].set_index("method")["tip_ratio"]
        for m in LOCK_METHODS:
            headline[f"locking_tip_ratio_{m}"] = round(float(hi[m]), 3)
        findings.append(
            f"Near incompressibility (ν = {max(q.nus)}) the P1 cantilever keeps "
            f"{hi['P1']:.0%} of the Timoshenko deflection (locking), P2 {hi['P2']:.0%}, "
            f"the spring model {hi['spring']:.0%}, the exact spring element "
            f"{hi['spring-exact']:.0%}: it is P1's element at small strain, so it locks like "
            "P1 — the freedom from locking of the specification's element is its calibration "
            "error, not a virtue of springs."
        )
    ran = f["map"][f["map"]["status"].isin(RAN)] if len(f["map"]) else f["map"]
    if len(ran):  # the cells the budget stopped or skipped are no verdict either way
        share = ran.groupby("method", sort=False)["status"].apply(lambda s: (s == "ok").mean())
        missing = len(f["map"]) - len(ran)
        findings.append(
            "Share of the load × time-step grid that runs ok in damped explicit dynamics: "
            + ", ".join(f"{m} {v:.0%}" for m, v in share.items())
            + (f" ({missing} cells not run: the budget stopped or skipped them)" if missing else "")
            + "."
        )
    elif len(f["map"]):
        findings.append("No cell of the failure map ran within the budget.")
    return findings, headline


def own_step_findings(dt: pd.DataFrame, headline: dict[str, float]) -> list[str]:
    """One sentence per scene with the step searches of plug-ins with their own dynamics
    (``largest_step``, and their variants): the largest surviving step against the bound of
    the plug-in's own energy, and its configured step over that limit (into ``headline``:
    ``<plug-in>_setting_over_limit_<method>``, the median over scenes)."""
    own = own_steppers(models.plugins())
    x = dt[dt.method.isin(tuple(own))]
    out = []
    over: dict[str, list[float]] = {}
    for scene, g in x.groupby("scene", sort=False):
        parts = []
        for _, r in g.iterrows():
            if r.ratio != r.ratio:
                parts.append(f"{r.method} fails at every step tried ({r.failure})")
                continue
            o = float(r.setting_h / r.dt_measured)
            over.setdefault(r.method, []).append(o)
            parts.append(
                f"{r.method} {r.ratio:.2f} × 2/ω_max ({r.dt_measured:.3g} s; the configured "
                f"{r.setting_h:.3g} s is {o:.2f} of it"
                + (f"; beyond it: {r.failure}" if r.failure else "")
                + ")"
            )
        out.append(
            f"Largest surviving step of the models with their own dynamics on {scene} "
            "(undamped, loads off, the explicit runs' perturbation; against 2/ω_max of each "
            "one's own energy): "
            + "; ".join(parts)
            + (
                " — on this scene their own integration does not lift the explicit limit of "
                "their energy by much: a little past it the energy grows without bound."
                if (g.ratio < 4).all()
                else "."
            )
        )
    for m, v in over.items():
        headline[f"{own[m][0]}_setting_over_limit_{m}"] = round(float(pd.Series(v).median()), 3)
    return out
