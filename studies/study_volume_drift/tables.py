"""Tables of the volume-drift study, and the runs' outcomes they are read from.

:class:`Runs` holds every case's outcome and answers the questions the tables, figures and
findings ask (a run's final drift, a static drift, the scene's measure and its FEM
reference); :func:`final_table` and :func:`static_table` write the two tables.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from ..registry import StudyContext, Table
from ..scenes import StudyScene
from .cases import K_MAX, K_MIN

#: The drift measures in words.
MEASURE_WORDS = {"dV": "|ΔV|/V0", "element_drift": "Σ|ΔV_k|/V0"}
#: Small-strain laws: their solution measured on the deformed mesh is no volume reference.
SMALL_STRAIN = ("linear", "transverse-linear")


@dataclass
class Runs:
    """Outcomes of the study's cases.

    Parameters
    ----------
    scenes
        The scenes.
    static
        One row per static case (:func:`static_frame`).
    dynamic
        ``(case, result)`` of every explicit run.
    volume
        Scene label -> its closed-form volume change ``(value, source)`` or ``None``.
    """

    scenes: list[StudyScene]
    static: pd.DataFrame
    dynamic: list[tuple[dict[str, Any], dict[str, Any]]]
    volume: dict[str, tuple[float, str] | None]

    def run(self, scene: str, kind: str, model: str) -> dict[str, Any] | None:
        """The result of one explicit run (``None`` if it did not run)."""
        for c, r in self.dynamic:
            if c["scene"] == scene and c["kind"] == kind and c["model"] == model:
                return r
        return None

    def final(self, scene: str, kind: str, model: str, key: str = "dV") -> float:
        """A final measure of one explicit run (``nan`` if it has none)."""
        r = self.run(scene, kind, model)
        return float((r or {}).get("final", {}).get(key, np.nan))

    def kinds(self, scene: str) -> list[str]:
        """The explicit series that ran on ``scene`` (``step``, ``ramp``)."""
        return [
            k
            for k in ("step", "ramp")
            if any(c["scene"] == scene and c["kind"] == k for c, _ in self.dynamic)
        ]

    def stat(self, scene: str, model: str, key: str = "dV", load: float = 1.0) -> float:
        """A measure of one static equilibrium (``nan`` if it did not solve)."""
        s = self.static
        g = s[(s.scene == scene) & (s.model == model) & (s.load == load) & (s.status == "ok")]
        return float(g[key].iloc[0]) if len(g) else float("nan")

    def measure(self, scene: str) -> str:
        """The scene's drift measure: the total ``dV`` where a closed form gives the
        material's (a uniform state), else the element drift (in a non-uniform state
        compressed and stretched elements cancel in the total)."""
        return "dV" if self.volume.get(scene) else "element_drift"

    def material(self, scene: str) -> str | None:
        """The static FEM that says what the material itself does: P1 neo-Hookean, else
        the scene's own FEM (a finite-strain one first); ``None`` if neither solved."""
        s = self.static
        ok = s[(s.scene == scene) & (s.load == 1.0) & (s.status == "ok")].set_index("model")
        if "P1-NH" in ok.index:
            return "P1-NH"
        if "fem" in ok.index:
            return "fem"
        return None

    def small_strain(self, scene: str, model: str) -> bool:
        """Whether a static FEM row solved a small-strain law."""
        s = self.static
        g = s[(s.scene == scene) & (s.model == model) & (s.load == 1.0)]
        return bool(len(g)) and str(g.law.iloc[0]).split("/")[0] in SMALL_STRAIN

    def sign(self, scene: str) -> float:
        """``-1`` where the material loses volume under the scene's load, else ``1``."""
        ref = self.volume.get(scene)
        m = self.material(scene)
        dv = ref[0] if ref else (self.stat(scene, m) if m else np.nan)
        return -1.0 if dv < 0 else 1.0


def static_frame(cases: list[dict[str, Any]], results: list[dict[str, Any]]) -> pd.DataFrame:
    """One row per static case: scene, model, load factor, drifts, status, law."""
    keys = ("dV", "element_drift", "dL", "inverted", "dV (P2 volume)")
    rows = [
        {
            "scene": c["scene"],
            "model": c["model"],
            "load": c["load"],
            **{k: r.get(k, np.nan) for k in keys},
            "status": r["status"],
            "law": r.get("law", ""),
            "message": r.get("message", ""),
        }
        for c, r in zip(cases, results, strict=True)
    ]
    cols = ["scene", "model", "load", *keys, "status", "law", "message"]
    return pd.DataFrame(rows, columns=cols)


def final_table(ctx: StudyContext, runs: Runs) -> Table:
    """The drifts at the end of each explicit run, with each scene's references."""
    rows = []
    for c, r in runs.dynamic:
        f = r.get("final", {})
        lms = "lms" in c["model"]
        rows.append(
            {
                "scene": c["scene"],
                "run": c["kind"],
                "model": c["model"],
                "status": r["status"],
                "dV/V0": f.get("dV", np.nan),
                "element drift": f.get("element_drift", np.nan),
                "peak |dV|/V0": f.get("peak_dV", np.nan),
                "|dL|/L0": f.get("dL", np.nan),
                **{
                    f"k/k0 {q}": f.get(f"k_{q}", np.nan) if lms else np.nan
                    for q in ("median", "min", "max")
                },
                "first inverted (s)": r.get("first_inverted") or np.nan,
            }
        )
    for sc in runs.scenes:
        ref = runs.volume.get(sc.label)
        if ref:
            rows.append(
                {
                    "scene": sc.label,
                    "run": "closed form",
                    "model": ref[1],
                    "status": "ok",
                    "dV/V0": ref[0],
                    "element drift": abs(ref[0]),
                }
            )
        g = runs.static[(runs.static.scene == sc.label) & (runs.static.load == 1.0)]
        for _, s in g[g.model.str.match("P1|fem")].iterrows():
            rows.append(
                {
                    "scene": sc.label,
                    "run": "static",
                    "model": s.model,
                    "status": s.status,
                    "dV/V0": s.dV,
                    "element drift": s.element_drift,
                    "|dL|/L0": s.dL,
                }
            )
    return ctx.table(
        pd.DataFrame(rows),
        "final_drift",
        "Volume drift at the end of each explicit run (step: a suddenly applied load; ramp: "
        "a slow load ramp) with each scene's references (its closed form, the static FEM): "
        "dV/V0 signed total change, element drift Σ|ΔV_k|/V0, |dL|/L0 mean change of the "
        "radial sums Σ|ξ_j| that the volume springs restore, and the LMS stiffness ratio "
        f"k_s/k_s0 (clamp [{K_MIN:g}, {K_MAX:g}]).",
    )


def static_table(ctx: StudyContext, runs: Runs) -> Table:
    """The static equilibria of every scene."""
    return ctx.table(
        runs.static,
        "static_drift",
        "Static equilibria under each scene's loads (× load factor): the spring variants "
        "without LMS (Newton, full load; they check that the slow ramps are quasi-static), "
        "same-mesh P1 FEM (the scene's small-strain law, and neo-Hookean for an isotropic "
        "material) and the scene's own FEM ('fem', its P2 volume for a mixed formulation): "
        "relative volume change dV of the P1 mesh at the vertex positions, element drift "
        "Σ|V_k − V0_k|/V0, mean change of the radial sums dL.",
    )


def compare_words(x: float, ref: float) -> str:
    """``"1.15× the drift (more)"``: the drift ``x`` against ``ref``, for captions and findings.

    Examples
    --------
    >>> compare_words(0.06, 0.05)
    '1.20× the drift (more)'
    """
    r = x / ref if ref else float("nan")
    if not np.isfinite(r):
        return "an incomparable drift"
    if abs(r - 1.0) < 0.02:
        return f"{r:.2f}× the drift (about the same)"
    return f"{r:.2f}× the drift ({'more' if r > 1 else 'less'})"
