"""Figures of the accuracy study: error bars per scene and the captions of the error fields."""

from __future__ import annotations

import numpy as np
import pandas as pd

from springfem.scene import Scene

from .. import metrics
from ..plots import grouped_bars
from ..registry import Figure, StudyContext
from ..tables import pyplot
from .cases import ERROR_KINDS, nan_float


def field_conclusion(scene: Scene, r: dict, e: dict) -> str:
    """Where the spring model's error peaks, and the three error numbers."""
    model, total, disc = (nan_float(e[k].get("rel_l2")) for k in ERROR_KINDS)
    ref = np.asarray(r["u"][r["reference"]], float)
    err = metrics.nodal_error(np.asarray(r["u"]["spring"], float), ref)
    unit = "m" if scene.units == "SI" else "mm"
    lo, hi = scene.mesh.bounding_box()
    at = (scene.mesh.points[int(np.argmax(err))] - lo) / np.where(hi > lo, hi - lo, 1.0)
    return (
        f"The spring model's error peaks at {err.max():.3g} {unit}, at "
        f"({at[0]:.2f}, {at[1]:.2f}, {at[2]:.2f}) of the box (fractions of its size); its "
        f"total error is {total:.1%} (L2) against {r['p1']}'s discretisation error "
        f"{disc:.1%}, its model error (vs {r['p1']}) {model:.1%}."
    )


def bar_figure(ctx: StudyContext, errors: pd.DataFrame, probes: pd.DataFrame) -> Figure:
    plt = pyplot()
    fig, (a, b) = plt.subplots(1, 2, figsize=(12, 4.8), layout="constrained")
    groups = list(errors["scene"])
    grouped_bars(
        a,
        groups,
        {
            "model (spring vs P1)": errors["model err L2"],
            "total (spring vs ref)": errors["total err L2"],
            "discretisation (P1 vs ref)": errors["discretisation err L2"],
        },
        "relative L2 error over vertices",
        log=False,
    )
    a.set_title("displacement error per scene", fontsize=10)
    grouped_bars(
        b,
        groups,
        {
            "spring / ref − 1": probes["spring / ref − 1"],
            "P1 / ref − 1": probes["P1 / ref − 1"],
            "lateral: spring / ref − 1": probes["lateral spring / ref − 1"],
        },
        "signed relative difference",
        log=False,
    )
    b.axhline(0.0, color="k", lw=0.8)
    b.set_title("main probe component vs reference (negative = stiffer)", fontsize=10)
    worst = errors.loc[errors["model err L2"].idxmax()]
    return ctx.figure(
        fig,
        "accuracy_errors.png",
        "Left: relative L2 displacement error per scene, split into the spring element's model "
        "error, its total error and P1's discretisation error. Right: signed error of the main "
        "probe component (and the stretch scenes' lateral contraction) against the reference. "
        f"The spring model's largest model error is in {worst['scene']} "
        f"({worst['model err L2']:.1%}).",
    )
