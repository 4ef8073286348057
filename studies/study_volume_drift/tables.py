"""Tables of the volume-drift study, and the numbers read off the runs.

:class:`Runs` holds every run's outcome; :func:`summary` reads the numbers the figures'
captions and the findings quote; :func:`final_table` and :func:`static_table` write the
two tables.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from ..registry import StudyContext, Table
from ..tables import write_table
from .cases import CUBE_E, CUBE_STRESS, K_MAX, K_MIN, VARIANTS, Settings, analytic_drift


@dataclass
class Runs:
    """Outcomes of the study's runs.

    Parameters
    ----------
    dyn
        ``(case, label, kind, result)`` of each explicit run; ``label`` is ``compressed``,
        ``pulled`` or ``sag``, ``kind`` is ``step`` or ``ramp``.
    stat
        One row per static equilibrium (``model``, signed ``load``, drifts, ``status``).
    sag_ref
        The static neo-Hookean FEM drift of the sag scene (``None``: no sag runs).
    nu
        Poisson's ratio of the cube.
    """

    dyn: list[tuple[dict[str, Any], str, str, dict[str, Any]]]
    stat: pd.DataFrame
    sag_ref: dict[str, Any] | None
    nu: float

    def final(self, label: str, kind: str, variant: str, key: str = "dV") -> float:
        """A final value of one explicit run (``nan`` if it has none).

        Parameters
        ----------
        label, kind, variant
            Which run.
        key
            A key of its ``final`` measures.

        Returns
        -------
        float
        """
        for c, lab, knd, r in self.dyn:
            if lab == label and knd == kind and c["variant"] == variant:
                return float(r.get("final", {}).get(key, np.nan))
        return float("nan")

    def fem(self, law: str, load: float, key: str = "dV") -> float:
        """A drift measure of the static P1 FEM cube (``nan`` if not run).

        Parameters
        ----------
        law
            ``linear`` or ``neo-hookean``.
        load
            Signed load factor.
        key
            ``dV``, ``element_drift`` or ``dL``.

        Returns
        -------
        float
        """
        g = self.stat[(self.stat.model == f"FEM P1 {law}") & (self.stat.load == load)]
        return float(g[key].iloc[0]) if len(g) else float("nan")

    def sag(self) -> dict[str, dict[str, Any]]:
        """Variant -> result of the sag runs (empty without them)."""
        return {c["variant"]: r for c, lab, knd, r in self.dyn if lab == "sag"}


@dataclass
class Summary:
    """The numbers quoted by captions and findings (absolute drifts |dV|/V0)."""

    comp: dict[str, float]
    pull: dict[str, float]
    ramp_c: dict[str, float]
    ramp_p: dict[str, float]
    a_cube: float
    k_spec: float
    k_abs: float
    fem_c: float
    fem_p: float
    dl_on: float
    dl_fem: float


def summary(runs: Runs) -> Summary:
    """Read the quoted numbers off the runs.

    Parameters
    ----------
    runs
        The study's runs.

    Returns
    -------
    Summary
        Final drifts after the sudden load (``comp``, ``pull``) and at the end of the slow
        ramps (``ramp_c``, ``ramp_p``) per variant, the analytic and FEM drifts at full
        load, the LMS median stiffness ratios and the radial-sum changes.
    """
    fin = runs.final
    return Summary(
        comp={v: abs(fin("compressed", "step", v)) for v in VARIANTS},
        pull={v: abs(fin("pulled", "step", v)) for v in VARIANTS},
        ramp_c={v: abs(fin("compressed", "ramp", v)) for v in VARIANTS},
        ramp_p={v: abs(fin("pulled", "ramp", v)) for v in VARIANTS},
        a_cube=abs(analytic_drift(runs.nu, CUBE_STRESS)),
        k_spec=fin("compressed", "step", "LMS spec", "k_median"),
        k_abs=fin("compressed", "step", "LMS abs", "k_median"),
        fem_c=abs(runs.fem("neo-hookean", -1.0)),
        fem_p=abs(runs.fem("neo-hookean", 1.0)),
        dl_on=fin("compressed", "ramp", "volume on", "dL"),
        dl_fem=runs.fem("neo-hookean", -1.0, "dL"),
    )


def static_frame(cases: list[dict[str, Any]], results: list[dict[str, Any]]) -> pd.DataFrame:
    """One row per static case: model, signed load factor, drifts, status.

    Parameters
    ----------
    cases, results
        The static cases and their results (:func:`~.cases.static_case`).

    Returns
    -------
    DataFrame
    """
    return pd.DataFrame(
        [
            {
                "model": (f"FEM P1 {c['law']}" if c["model"] == "fem" else c["variant"]),
                "load": np.sign(c["stress"]) * c["load"],
                **{k: r.get(k, np.nan) for k in ("dV", "element_drift", "dL")},
                "status": r["status"],
            }
            for c, r in zip(cases, results)
        ]
    )


def final_table(ctx: StudyContext, runs: Runs, s: Settings) -> Table:
    """The table of drifts at the end of each explicit run, with the references.

    Parameters
    ----------
    ctx
        Where to write.
    runs
        The study's runs.
    s
        Its settings (for the caption).

    Returns
    -------
    Table
    """
    dyn, stat, sag_ref, nu = runs.dyn, runs.stat, runs.sag_ref, runs.nu
    rows = []
    for c, label, kind, r in dyn:
        f = r.get("final", {})
        rows.append(
            {
                "case": f"cube {label}, {kind}" if c["scene"] == "cube" else f"sag, {kind}",
                "variant": c["variant"],
                "status": r["status"],
                "dV/V0": f.get("dV", np.nan),
                "element drift": f.get("element_drift", np.nan),
                "peak |dV|/V0": f.get("peak_dV", np.nan),
                "|dL|/L0": f.get("dL", np.nan),
                "k/k0 median": f.get("k_median", np.nan) if "LMS" in c["variant"] else np.nan,
                "k/k0 min": f.get("k_min", np.nan) if "LMS" in c["variant"] else np.nan,
                "k/k0 max": f.get("k_max", np.nan) if "LMS" in c["variant"] else np.nan,
                "first inverted (s)": r.get("first_inverted") or np.nan,
            }
        )
    final = pd.DataFrame(rows)
    ref_rows = []
    for sign, label in ((-1.0, "compressed"), (1.0, "pulled")):
        a = analytic_drift(nu, sign * CUBE_STRESS)
        ref_rows.append(
            {
                "case": f"cube {label}",
                "variant": "analytic (linear)",
                "status": "ok",
                "dV/V0": a,
                "element drift": abs(a),
            }
        )
        for law in ("linear", "neo-hookean"):
            g = stat[(stat.model == f"FEM P1 {law}") & (stat.load == sign)]
            if len(g):
                ref_rows.append(
                    {
                        "case": f"cube {label}",
                        "variant": f"FEM P1 {law} (static)",
                        "status": g.status.iloc[0],
                        "dV/V0": g.dV.iloc[0],
                        "element drift": g.element_drift.iloc[0],
                        "|dL|/L0": g.dL.iloc[0],
                    }
                )
    if sag_ref is not None:
        ref_rows.append(
            {
                "case": "sag",
                "variant": "FEM P1 neo-hookean (static)",
                "status": sag_ref["status"],
                "dV/V0": sag_ref.get("dV", np.nan),
                "element drift": sag_ref.get("element_drift", np.nan),
                "|dL|/L0": sag_ref.get("dL", np.nan),
            }
        )
    final = pd.concat([final, pd.DataFrame(ref_rows)], ignore_index=True)
    mesh_note = f"cube {s.n}³×6 tets, ν = {nu}" + (
        f"; sag {s.sag[0]}×{s.sag[1]}×{s.sag[2]}×6 tets, ν = 0.45" if s.sag else ""
    )
    return Table(
        write_table(final, ctx.path("final_drift")),
        f"Volume drift at the end of each explicit run ({mesh_note}; peak cube stress "
        f"±{CUBE_STRESS / CUBE_E:.0%} of E) with the references: dV/V0 signed total change, "
        "element drift Σ|ΔV_k|/V0, |dL|/L0 mean change of the radial sums Σ|ξ_j| that the "
        "volume springs restore, and the LMS stiffness ratio k_s/k_s0 (clamp "
        f"[{K_MIN:g}, {K_MAX:g}]).",
    )


def static_table(ctx: StudyContext, runs: Runs) -> Table:
    """The table of the cube's static equilibria against signed load factor.

    Parameters
    ----------
    ctx
        Where to write.
    runs
        The study's runs.

    Returns
    -------
    Table
    """
    return Table(
        write_table(runs.stat, ctx.path("static_drift")),
        "Static equilibria of the cube against signed load factor (−1 = full compression): "
        "FEM P1 linear and neo-Hookean, and the spring variants without LMS (Newton) at "
        "full load, which check that the slow ramps of the dynamic runs are quasi-static.",
    )


def compare_words(x: float, ref: float) -> str:
    """``"1.15× the drift (more)"`` for captions and findings.

    Parameters
    ----------
    x, ref
        A drift and the one it is compared with.

    Returns
    -------
    str
    """
    r = x / ref if ref else float("nan")
    if not np.isfinite(r):
        return "an incomparable drift"
    if abs(r - 1.0) < 0.02:
        return f"{r:.2f}× the drift (about the same)"
    return f"{r:.2f}× the drift ({'more' if r > 1 else 'less'})"
