"""Tables of the convergence study: errors per level, fitted rates, the spring–P1 gap.

The displacement ``w`` the tip columns track is the scene's closed-form reference quantity
(:mod:`studies.analytic`: the cantilever's tip deflection ``u_z``) when it has one, else
its first probe's largest component in the reference, else the largest component of the
level-1 vertex that moves most in the reference.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .. import metrics
from ..analytic import reference
from ..registry import StudyContext, Table
from .cases import COSINE, SPRING, Plan, richardson_limit
from .levels import grid_box, level_label

L2 = "L2 err (level-1 vertices)"


@dataclass(frozen=True)
class Tracked:
    """The displacement component the tip columns track: a probe's or a level-1 vertex's.

    Attributes
    ----------
    name
        Its name in headline keys (the probe's, or ``vertex``).
    probe
        The probe, or ``None`` for a vertex.
    vertex
        The level-1 vertex (when there is no probe).
    component
        0, 1 or 2.
    """

    name: str
    probe: str | None
    vertex: int | None
    component: int

    @property
    def label(self) -> str:
        where = f"probe {self.probe}" if self.probe else f"level-1 vertex {self.vertex}"
        return f"u{'xyz'[self.component]} at {where}"

    def value(self, r: dict) -> float:
        """Its value in one case's result."""
        if self.probe is not None:
            return float(r["probes"][self.probe][self.component])
        return float(r["u_coarse"][self.vertex][self.component])


def tracked(p: Plan, ref: dict) -> tuple[Tracked, tuple[float, str] | None]:
    """What the tip columns track, and the scene's closed-form value of it if it has one."""
    hook = reference(p.scene, None)
    if hook is not None:
        probe, component, value, source = hook
        return Tracked(probe, probe, None, component), (value, source)
    if ref["probes"]:
        probe, u = next(iter(ref["probes"].items()))
        return Tracked(probe, probe, None, int(np.argmax(np.abs(u)))), None
    u = np.asarray(ref["u_coarse"], float)
    vertex = int(np.argmax(np.linalg.norm(u, axis=1)))
    return Tracked("vertex", None, vertex, int(np.argmax(np.abs(u[vertex])))), None


@dataclass
class Analysis:
    """The convergence of one scene: level rows, rates, the gap, the checks.

    Attributes
    ----------
    plan, ref, track, analytic
        The plan, the reference's result, the tracked component, its closed form.
    levels, rates
        The level and rate tables.
    rate
        ``model -> {"l2", "tip", "limit", "order"}``.
    gap
        ``spring / P1 − 1`` of ``w`` per level, its rate and extrapolated limit and order.
    cosine_vs_energy
        ``w`` of cosine over energy torsion minus 1 at the check level.
    """

    plan: Plan
    ref: dict
    track: Tracked
    analytic: tuple[float, str] | None
    levels: pd.DataFrame
    rates: pd.DataFrame
    rate: dict = field(default_factory=dict)
    gap: pd.Series | None = None
    gap_rate: float = float("nan")
    gap_limit: float = float("nan")
    gap_order: float = float("nan")
    cosine_vs_energy: float = float("nan")

    @property
    def w_ref(self) -> float:
        return self.track.value(self.ref)


def analyse(p: Plan, cases: list[dict], results: list[dict]) -> Analysis:
    """Errors of every level against the reference (the first case), rates and the gap, from
    :meth:`Plan.cases` and their results; a :class:`~springfem.errors.SolverError` if the
    reference solve failed.
    """
    from springfem.errors import SolverError

    ref = results[0]
    if ref["status"] != "ok":
        raise SolverError(f"the reference {p.fem[1]} on level {p.ref} failed: {ref['message']}")
    track, analytic = tracked(p, ref)
    w_ref, u_ref = track.value(ref), np.asarray(ref["u_coarse"], float)
    rows = []
    for c, r in zip(cases[1:], results[1:], strict=True):
        ok = r["status"] == "ok"
        w = track.value(r) if ok else np.nan
        rows.append(
            {
                "model": c["model"],
                "factor": c["factor"],
                "mesh": level_label(p.scene.table, c["factor"]),
                "tets": r["tets"],
                "dofs": r.get("dofs", np.nan),
                "h": p.h1 / c["factor"],
                "w": w,
                "w / w_ref": w / w_ref,
                "w err": abs(w - w_ref) / abs(w_ref),
                L2: metrics.relative_l2_error(r["u_coarse"], u_ref) if ok else np.nan,
                "wall time (s)": r.get("wall", np.nan),
                "status": r["status"],
            }
        )
    df = pd.DataFrame(rows)
    cos = df[df["model"] == COSINE]
    df = df[df["model"] != COSINE].reset_index(drop=True)
    a = Analysis(p, ref, track, analytic, df, pd.DataFrame())
    _rates(a)
    _gap(a, float(cos["w"].iloc[0]))
    return a


def _rates(a: Analysis) -> None:
    rows = []
    for m in a.plan.models:
        d = a.levels[(a.levels["model"] == m) & (a.levels["status"] == "ok")]
        d = d.sort_values("h", ascending=False)
        if not len(d):
            continue
        rl2, rtip = metrics.fitted_rate(d["h"], d[L2]), metrics.fitted_rate(d["h"], d["w err"])
        L, order = richardson_limit(d["h"].values[-3:], d["w / w_ref"].values[-3:])
        a.rate[m] = {"l2": rl2, "tip": rtip, "limit": L, "order": order}
        last = d.iloc[-1]
        rows.append(
            {
                "model": m,
                "levels": len(d),
                "rate (L2)": rl2,
                "rate (w)": rtip,
                "finest factor": int(last["factor"]),
                "L2 err at finest": last[L2],
                "w err at finest": last["w err"],
                "extrapolated w / w_ref": L,
                "extrapolation order": order,
            }
        )
    a.rates = pd.DataFrame(rows)


def _gap(a: Analysis, w_cosine: float) -> None:
    ok = a.levels[a.levels["status"] == "ok"]
    sp = ok[ok["model"] == SPRING].set_index("factor")
    p1 = ok[ok["model"] == a.plan.fem[0]].set_index("factor")
    common = sp.index.intersection(p1.index)
    gap = (sp.loc[common, "w"] / p1.loc[common, "w"] - 1.0).sort_index()
    h = sp.loc[gap.index, "h"]
    a.gap = gap
    a.gap_rate = metrics.fitted_rate(h, gap.abs())
    a.gap_limit, a.gap_order = richardson_limit(h.values[-3:], gap.values[-3:])
    if a.plan.cosine in sp.index:
        a.cosine_vs_energy = w_cosine / float(sp.at[a.plan.cosine, "w"]) - 1.0


def write_tables(ctx: StudyContext, a: Analysis, suffix: str = "") -> list[Table]:
    """Write the level and rate tables of one scene."""
    p, label = a.plan, a.plan.scene.label
    how = (
        "its divisions times the factor"
        if grid_box(p.scene.table)
        else "uniform refinement (each tet into 8 per doubling)"
    )
    levels = ctx.table(
        a.levels,
        f"convergence_levels{suffix}",
        f"{label} refined by {how}: w = {a.track.label} and errors against {p.fem[1]} on level "
        f"{p.ref} ({a.ref['tets']} tets, w = {a.w_ref:.6g}); h = h₁ / factor with h₁ = "
        f"{p.h1:.4g} the mean edge length of the scene's mesh (its length unit)"
        + (f"; {'; '.join(p.notes)}" if p.notes else "")
        + ".",
    )
    rates = ctx.table(
        a.rates,
        f"convergence_rates{suffix}",
        "Fitted rates (slope of log error over log h, all levels) and w extrapolated from "
        f"each model's three finest levels (w = L + C h^p); {p.fem[0]}'s true limit is the "
        "reference's, so its extrapolated value shows the extrapolation's own bias.",
    )
    return [levels, rates]
