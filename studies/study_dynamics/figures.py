"""Figures of the dynamics study: the probe displacement (and its error against explicit
P1) against time, and each model's energy balance against time.

Examples
--------
>>> _style("P1", "P1", 0)["color"], _style("spring-exact", "P1", 1)["ls"]
('k', '-.')
"""

from __future__ import annotations

import numpy as np

from ..registry import Figure, StudyContext
from ..tables import pyplot
from .cases import COLORS
from .tables import dominant

#: Errors below this are drawn on it (log axis).
ERROR_FLOOR = 1e-14
#: Line styles: the reference solid black, springs dashed in their colours.
_STYLES = ("--", "-.", ":", (0, (5, 1, 1, 1)))


def _style(m: str, ref: str, i: int) -> dict:
    if m == ref:
        return {"color": "k", "lw": 2.4, "ls": "-", "label": f"{m} (explicit, reference)"}
    return {"color": COLORS.get(m, f"C{i}"), "lw": 1.4, "ls": _STYLES[i % len(_STYLES)],
            "label": m}  # fmt: skip


def probe_figure(ctx: StudyContext, runs: list[tuple[dict, dict]], refs: dict[str, str]) -> Figure:
    """Top: the probe's dominant displacement component against time, every model; bottom:
    ``|u - u_ref|`` (log) against time. One column per scene."""
    plt = pyplot()
    scenes = list(refs)
    fig, axes = plt.subplots(2, len(scenes), figsize=(6.4 * len(scenes), 6.6), squeeze=False,
                             sharex="col", layout="constrained")  # fmt: skip
    for j, scene in enumerate(scenes):
        ax = axes[:, j]
        mine = [(c, r) for c, r in runs if c["scene"] == scene and r["status"] == "ok"]
        ref = next((r for c, r in mine if c["model"] == refs[scene]), None)
        if ref is None:
            continue
        k = dominant(ref["u"][0])
        u_ref = np.asarray(ref["u"])
        for i, (c, r) in enumerate(mine):
            t, u = np.asarray(r["t"]) * 1e3, np.asarray(r["u"])
            st = _style(c["model"], refs[scene], i)
            ax[0].plot(t, u[:, k], **st)
            if c["model"] != refs[scene]:
                err = np.linalg.norm(u - u_ref, axis=1)
                st.pop("label")
                ax[1].semilogy(t, np.maximum(err, ERROR_FLOOR), **st)
        ax[0].set_ylabel(f"probe u_{'xyz'[k]} (scene length unit)")
        ax[0].set_title(f"{scene}: released from the static state")
        ax[0].legend(fontsize=8, loc="best")
        ax[0].grid(alpha=0.3)
        ax[1].set_ylabel("|u − u_P1| at the probe")
        ax[1].set_xlabel("time after release (ms)")
        ax[1].grid(alpha=0.3, which="both")
    caption = (
        "Probe displacement after the release (top: its largest component, every model; "
        f"bottom: distance from explicit P1's probe, log scale, floored at {ERROR_FLOOR:g})."
    )
    return ctx.figure(fig, "probe_vs_time.png", caption)


def energy_figure(ctx: StudyContext, runs: list[tuple[dict, dict]], refs: dict[str, str]) -> Figure:
    """``(E(t) - E(0)) / E(0)`` of each model's own balance against time, one panel per
    scene."""
    plt = pyplot()
    scenes = list(refs)
    fig, axes = plt.subplots(1, len(scenes), figsize=(6.4 * len(scenes), 4.2), squeeze=False,
                             layout="constrained")  # fmt: skip
    for ax, scene in zip(axes[0], scenes):
        mine = [(c, r) for c, r in runs if c["scene"] == scene and "energy" in r]
        for i, (c, r) in enumerate(mine):
            E = np.asarray(r["energy"], dtype=float)
            if not np.all(np.isfinite(E)):
                continue
            t = np.asarray(r["energy_t"]) * 1e3
            ax.plot(t, (E - E[0]) / E[0], **_style(c["model"], refs[scene], i))
        ax.set_title(f"{scene}: energy balance (kinetic + strain − work)")
        ax.set_xlabel("time after release (ms)")
        ax.set_ylabel("(E(t) − E(0)) / E(0)")
        ax.ticklabel_format(axis="y", style="sci", scilimits=(-2, 2))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="best")
    caption = (
        "Energy balance of each model after the release, relative to its initial (strain) "
        "energy: undamped symplectic Euler at half each model's critical step, whose recorded "
        "energy oscillates by O((ω dt)²) and does not drift; XPBD (where it applies) by its "
        "own undamped substeps, whose projection dissipates."
    )
    return ctx.figure(fig, "energy_vs_time.png", caption)
