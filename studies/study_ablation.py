"""Study ``ablation``: "model no more than a scene needs".

For every bundled scene (coarse meshes in the quick settings) the spring model is solved with its
parts switched on one by one:

============================  ===========================================================
``axial``                     axial springs only (torsion off, volume off)
``axial+volume``              + barycentric volume springs, no torsion (enough for a stretch
                              along the axes?)
``axial+cosine``              + torsion springs, the spec's cosine law (2.44–2.45)
``axial+energy``              + torsion springs, the energy-consistent law
``axial+cosine+volume``       + barycentric volume springs
``axial+energy+volume``       + barycentric volume springs
``+LMS (abs)``                axial+energy+volume with sign-consistent LMS; LMS acts once
                              per time step, so this variant needs a dynamic solver:
                              dynamic relaxation (kinetic damping) from rest
``+volume (nnls cal.)``       axial+energy+volume with the per-element least-squares
                              calibration instead of the analytic one
============================  ===========================================================

Model error is the relative L2 error of the vertex displacements against FEM P1 (the scene's
law) on the same mesh; total error (against a converged solution) is the convergence
study's business. Cost is the wall time of the static solve (Newton with the analytic
Hessian for the gradient variants, a coloured finite-difference Jacobian for cosine torsion;
median of 3 when a solve takes under half a second) and the throughput of the serial force
kernel (elements per second). A variant that the solver cannot bring to equilibrium (a
singular tangent: the axial-only network has zero-energy modes; or no convergence) is
recorded as ``fails`` with the solver's message.

The cheapest adequate model of a scene is the variant with the smallest static solve time
among those whose model error is within :data:`TOLERANCE` (relative) of the best spring
variant's error.
"""

from __future__ import annotations

import re
import time
import warnings
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pandas as pd

from springfem.errors import SolverError
from springfem.scene import Scene, parse_scene
from springmodel.options import LMSOptions, SpringOptions

from .cli import SCENES
from .metrics import median_time, relative_l2_error
from .registry import Figure, StudyContext, StudyOutput, Table, study
from .tables import save_figure, write_table

#: Variants in order of the parts they switch on: label -> changes to ``[spring]``.
VARIANTS: dict[str, dict[str, Any]] = {
    "axial": {"torsion": "off", "volume": False},
    "axial+volume": {"torsion": "off", "volume": True},
    "axial+cosine": {"torsion": "cosine", "volume": False},
    "axial+energy": {"torsion": "energy", "volume": False},
    "axial+cosine+volume": {"torsion": "cosine", "volume": True},
    "axial+energy+volume": {"torsion": "energy", "volume": True},
    "+LMS (abs)": {"torsion": "energy", "volume": True, "lms": "abs"},
    "+volume (nnls cal.)": {"torsion": "energy", "volume": True, "calibration": "nnls"},
}
#: Bundled scenes.
SCENE_NAMES = ("cantilever", "stretch-fiber", "stretch-cross", "sag")
#: A variant is adequate when its model error is at most (1 + TOLERANCE) x the best one's.
TOLERANCE = 0.10
#: Solve times within this fraction of the fastest count as a tie (timer noise).
TIME_TIE = 0.25
#: The absolute model-error budget of the second winner column.
MAX_ERROR = 0.10
#: Newton settings shared by every static solve.
NEWTON = {"tol": 1e-8, "max_iter": 25, "max_cutbacks": 4}
#: Dynamic relaxation (LMS variant): residual tolerance and step budget.
DR_TOL = 1e-6


@dataclass(frozen=True)
class Settings:
    """Meshes and step budget of the ablation study.

    Parameters
    ----------
    divisions
        Scene name -> box divisions (``None``: the bundled scene's mesh).
    dr_steps
        Dynamic-relaxation step budget of the LMS variant.
    """

    divisions: dict[str, tuple[int, int, int] | None] = field(
        default_factory=lambda: dict.fromkeys(SCENE_NAMES)
    )
    dr_steps: int = 8000

    @classmethod
    def full(cls) -> Settings:
        """The bundled meshes, 8000 relaxation steps."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """Coarse meshes, 4000 relaxation steps."""
        coarse = {
            "cantilever": (20, 2, 2),
            "stretch-fiber": (3, 3, 3),
            "stretch-cross": (3, 3, 3),
            "sag": (8, 4, 2),
        }
        return cls(divisions=coarse, dr_steps=4000)


# ------------------------------------------------------------------------------ scene


def ablation_scene(name: str, divisions: tuple[int, int, int] | None = None) -> Scene:
    """A bundled scene, optionally on a different box mesh."""
    text = (SCENES / f"{name}.toml").read_text()
    if divisions is not None:
        text = re.sub(r"(?m)^divisions = \[.*\]", f"divisions = {list(divisions)}", text)
    return parse_scene(text)


def variant_options(scene: Scene, variant: str) -> SpringOptions:
    """The scene's spring options with a variant's parts (see :data:`VARIANTS`)."""
    changes = dict(VARIANTS[variant])
    rule = changes.pop("lms", None)
    if rule is not None:
        changes["lms"] = LMSOptions(rule=rule)
    return replace(SpringOptions.of(scene), **changes)


# ------------------------------------------------------------------------------ cases


def _timed(fn, repeat_below: float = 0.5, repeats: int = 3) -> tuple[Any, float]:
    """Result and wall time of ``fn()``; the median of ``repeats`` runs if it is fast."""
    t0 = time.perf_counter()
    out = fn()
    dt = time.perf_counter() - t0
    if dt < repeat_below:
        times = [dt]
        for _ in range(repeats - 1):
            t0 = time.perf_counter()
            out = fn()
            times.append(time.perf_counter() - t0)
        dt = float(np.median(times))
    return out, dt


def fem_case(case: dict[str, Any]) -> dict[str, Any]:
    """FEM P1 reference of a scene: vertex displacements and wall time."""
    import reference_fem

    scene = ablation_scene(case["scene"], case["divisions"])
    try:
        sol, wall = _timed(lambda: reference_fem.solve(scene, order=1))
    except SolverError as exc:
        return {"status": "fails", "message": str(exc)[:200]}
    return {"status": "ok", "u": sol.u_vertices.tolist(), "time": wall, "law": sol.result.law}


def spring_case(case: dict[str, Any]) -> dict[str, Any]:
    """One spring variant on one scene: solution and cost.

    ``case``: ``scene``, ``divisions`` (``None`` = bundled mesh), ``variant`` and
    ``dr_steps`` (dynamic-relaxation budget of the LMS variant). Returns ``status``
    (``ok``/``fails``), ``message``, ``u`` (vertex displacements, nested lists; also the
    last state of a non-converged dynamic relaxation), ``solve_time``, ``build_time``,
    ``kernel_rate`` (elements per second), ``method``, ``iterations`` and, for LMS, the
    median stiffness ratio ``k_ratio_median`` and the share at the upper clamp.
    """
    from springfem.mechanics import explicit_static, static
    from springmodel.model import SpringModel

    scene = ablation_scene(case["scene"], case["divisions"])
    opts = variant_options(scene, case["variant"])
    t0 = time.perf_counter()
    model = SpringModel(scene, opts, parallel=False)
    build = time.perf_counter() - t0
    x0 = model.x0.copy()
    rate = scene.mesh.n_tets / median_time(lambda: model.kernel.forces(x0), repeats=15)
    out: dict[str, Any] = {"build_time": build, "kernel_rate": rate, "tets": scene.mesh.n_tets}

    def solve():
        if opts.lms is None:
            return static(model, **NEWTON, fallback=False)
        fresh = SpringModel(scene, opts, parallel=False)  # LMS state starts at k_s0
        info = explicit_static(
            fresh,
            tol=DR_TOL,
            max_steps=case["dr_steps"],
            dt_safety=0.5 / np.sqrt(opts.lms.k_max),
            raise_on_failure=False,
        )
        info.k_ratio = fresh.elements.k_volume / fresh.elements.k_volume0
        return info

    try:
        # a singular tangent (axial springs only) makes the Krylov fallback divide by zero
        # before the solver reports the failure: silence numpy's warnings, keep the error
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            info, wall = _timed(solve, repeat_below=0.5 if opts.lms is None else 0.0)
    except SolverError as exc:
        return {**out, "status": "fails", "message": str(exc)[:200]}
    out.update(
        status="ok" if info.converged else "fails",
        message="" if info.converged else (info.message or "not converged")[:200],
        u=(info.x - x0).tolist(),
        solve_time=wall,
        method=info.method,
        iterations=int(info.iterations),
        residual=float(info.residual),
    )
    if hasattr(info, "k_ratio"):
        out["k_ratio_median"] = float(np.median(info.k_ratio))
        out["k_ratio_at_max"] = float(np.mean(info.k_ratio >= opts.lms.k_max * (1 - 1e-12)))
    return out


def model_error(case: dict[str, Any], result: dict[str, Any], u_ref: Any) -> tuple[float, float]:
    """Relative L2 error of the vertex displacements and the largest relative probe error
    of a :func:`spring_case` result against ``u_ref`` (NaN when there is no solution)."""
    if "u" not in result:
        return float("nan"), float("nan")
    u, u_ref = np.asarray(result["u"]), np.asarray(u_ref)
    scene = ablation_scene(case["scene"], case["divisions"])
    return relative_l2_error(u, u_ref), _probe_error(scene, u, u_ref)


def _probe_error(scene: Scene, u: np.ndarray, u_ref: np.ndarray) -> float:
    """Largest relative probe error (displacement vector) against the reference."""
    a, b = scene.probe_displacements(u), scene.probe_displacements(u_ref)
    errs = [np.linalg.norm(np.subtract(a[k], b[k])) / np.linalg.norm(b[k]) for k in a]
    return float(max(errs)) if errs else float("nan")


def cheapest_adequate(
    df: pd.DataFrame, tolerance: float = TOLERANCE, max_error: float | None = None
) -> pd.Series | None:
    """The cheapest adequate variant among the ``ok`` rows of one scene.

    Adequate: model error at most ``(1 + tolerance)`` times the smallest error (or, with
    ``max_error``, at most ``max_error``). Cheapest: the smallest ``solve_time``; times
    within :data:`TIME_TIE` of it count as a tie, broken by the order of :data:`VARIANTS`
    (fewer parts first), so timer noise does not pick the winner. ``None`` if no row
    qualifies.
    """
    ok = df[(df.status == "ok") & np.isfinite(df.error)]
    if ok.empty:
        return None
    limit = (1.0 + tolerance) * ok.error.min() if max_error is None else max_error
    adequate = ok[ok.error <= limit]
    if adequate.empty:
        return None
    tied = adequate[adequate.solve_time <= (1.0 + TIME_TIE) * adequate.solve_time.min()]
    order = {v: i for i, v in enumerate(VARIANTS)}
    return tied.loc[tied.variant.map(order).sort_values().index[0]]


# -------------------------------------------------------------------------------- run


@study("ablation", Settings)
def run(ctx: StudyContext, settings: Settings) -> StudyOutput:
    """Run the ablation study (see the module docstring).

    Parameters
    ----------
    ctx
        Output folder, cache and preset.
    settings
        Meshes and step budget.

    Returns
    -------
    StudyOutput
        Findings, the ablation and winners tables, the error-vs-cost figure, headline.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    dr_steps = settings.dr_steps
    out = StudyOutput(name=ctx.name, title="Ablation: model no more than a scene needs")
    rows = []
    fem_times = {}
    for name in SCENE_NAMES:
        d = settings.divisions[name]
        div = list(d) if d is not None else None
        fem = ctx.cache.run(
            [{"scene": name, "divisions": div, "model": "fem-p1"}], fem_case, ctx.progress, name
        )[0]
        if fem["status"] != "ok":
            out.findings.append(f"{name}: the FEM P1 reference fails ({fem['message']}).")
            continue
        fem_times[name] = fem["time"]
        cases = [
            {"scene": name, "divisions": div, "variant": v, "dr_steps": dr_steps} for v in VARIANTS
        ]
        res = ctx.cache.run(cases, spring_case, ctx.progress, name)
        for c, r in zip(cases, res):
            err, perr = model_error(c, r, fem["u"])
            rows.append(
                {
                    "scene": name,
                    "tets": r.get("tets"),
                    "variant": c["variant"],
                    "status": r["status"],
                    "error": err,
                    "probe_error": perr,
                    "solve_time": r.get("solve_time", np.nan),
                    "kernel_Mtets/s": r.get("kernel_rate", np.nan) / 1e6,
                    "method": r.get("method", ""),
                    "iterations": r.get("iterations", np.nan),
                    "message": r.get("message", ""),
                    "k_ratio_median": r.get("k_ratio_median", np.nan),
                }
            )
    df = pd.DataFrame(rows)
    table = df.drop(columns=["k_ratio_median"]).copy()
    table["fem_p1_time"] = table.scene.map(fem_times)
    out.tables.append(
        Table(
            write_table(table, ctx.path("ablation")),
            "Spring-model parts switched on one by one, per scene: status, model error "
            "(relative L2 of vertex displacements against FEM P1 on the same mesh), largest "
            "probe error, static solve wall time (s; the LMS variant: dynamic relaxation), "
            "serial force-kernel throughput (M elements/s), solver method and iterations, and "
            "the FEM P1 solve time for scale.",
        )
    )

    # ---- winners
    wrows = []
    ladder = [v for v in VARIANTS if "nnls" not in v]  # the parts of the spec, analytic cal.
    for name, g in df.groupby("scene", sort=False):
        best = g[g.status == "ok"].sort_values("error")
        win = cheapest_adequate(g)
        if win is None:
            wrows.append({"scene": name, "cheapest adequate": "none (all fail)"})
            continue
        win_ladder = cheapest_adequate(g[g.variant.isin(ladder)])
        win_abs = cheapest_adequate(g, max_error=MAX_ERROR)
        wrows.append(
            {
                "scene": name,
                "best variant": best.variant.iloc[0],
                "best error": best.error.iloc[0],
                "cheapest adequate": win.variant,
                "its error": win.error,
                "its solve time": win.solve_time,
                "cheapest adequate (analytic cal.)": (
                    win_ladder.variant if win_ladder is not None else "none"
                ),
                "its error (analytic cal.)": (
                    win_ladder.error if win_ladder is not None else np.nan
                ),
                f"cheapest with error <= {MAX_ERROR:g}": (
                    win_abs.variant if win_abs is not None else "none"
                ),
                "fails": ", ".join(g[g.status != "ok"].variant) or "none",
            }
        )
        out.headline[f"best_error_{name}"] = round(float(best.error.iloc[0]), 4)
        full = g[g.variant == "axial+energy+volume"]
        if len(full) and full.status.iloc[0] == "ok":
            out.headline[f"full_error_{name}"] = round(float(full.error.iloc[0]), 4)
    winners = pd.DataFrame(wrows)
    out.tables.append(
        Table(
            write_table(winners, ctx.path("winners")),
            f"Per scene: the most accurate spring variant; the cheapest variant (smallest "
            f"static solve time, ties within {TIME_TIE:.0%} broken towards fewer parts) whose "
            f"model error is within {TOLERANCE:.0%} of the best, over all variants and over "
            f"the analytic-calibration ladder of the spec's parts only; the cheapest with a "
            f"model error of at most {MAX_ERROR:.0%}; and the variants that fail.",
        )
    )

    # ---- figure: error against solve time per scene
    names = list(df.scene.unique())
    fig, axes = plt.subplots(1, len(names), figsize=(4.2 * len(names), 4.2), squeeze=False)
    markers = dict(zip(VARIANTS, "o<v^sDP*"))
    colors = dict(zip(VARIANTS, plt.rcParams["axes.prop_cycle"].by_key()["color"]))
    handles = {}
    for ax, name in zip(axes[0], names):
        g = df[df.scene == name]
        for _, r in g.iterrows():
            kw = {"color": colors[r.variant], "ms": 8, "ls": "none"}
            if r.status == "ok":
                (h,) = ax.loglog(r.solve_time, r.error, markers[r.variant], **kw)
                handles.setdefault(r.variant, h)
            elif np.isfinite(r.error) and np.isfinite(r.solve_time):
                (h,) = ax.loglog(r.solve_time, r.error, markers[r.variant], mfc="none", **kw)
                handles.setdefault(r.variant + " (not converged: last state)", h)
        w = winners[winners.scene == name]
        if len(w) and "its error" in w and np.isfinite(w["its error"].iloc[0]):
            (h,) = ax.loglog(
                w["its solve time"].iloc[0],
                w["its error"].iloc[0],
                "o",
                ms=17,
                mfc="none",
                mec="k",
            )
            handles["cheapest adequate"] = h
        if name in fem_times:
            handles["FEM P1 solve time"] = ax.axvline(fem_times[name], color="k", ls=":", lw=1)
        failed = ", ".join(g[(g.status != "ok") & ~np.isfinite(g.error)].variant)
        ax.set_title(f"{name} ({int(g.tets.iloc[0])} tets)", fontsize=10)
        if failed:
            ax.text(0.03, 0.97, f"fails: {failed}", transform=ax.transAxes, fontsize=7, va="top")
        ax.set_xlabel("static solve wall time (s)")
        ax.grid(alpha=0.3, which="both")
    axes[0, 0].set_ylabel("model error vs FEM P1 (relative L2)")
    rank = {v: i for i, v in enumerate(VARIANTS)}
    keys = sorted(handles, key=lambda k: rank.get(k.split(" (not")[0], len(rank)))
    fig.legend(
        [handles[k] for k in keys],
        keys,
        loc="upper center",
        ncol=4,
        fontsize=8,
        bbox_to_anchor=(0.5, -0.02),
    )
    summary = "; ".join(
        f"{w['scene']}: {w['cheapest adequate']}"
        + (f" ({w['its error']:.3g})" if pd.notna(w.get("its error")) else "")
        for _, w in winners.iterrows()
    )
    out.figures.append(
        Figure(
            save_figure(fig, ctx.path("error_vs_cost.png")),
            "Model error against static solve time for each spring variant (hollow: the "
            "last state of a run that did not converge; variants that fail outright are "
            "named in the panel); circled: the cheapest variant within "
            f"{TOLERANCE:.0%} of the best error. Cheapest adequate (error): {summary}.",
        )
    )

    # ---- findings
    for _, w in winners.iterrows():
        g = df[df.scene == w["scene"]].set_index("variant")
        if "best variant" not in w or pd.isna(w.get("best variant")):
            out.findings.append(f"{w['scene']}: every spring variant fails.")
            continue
        errs = ", ".join(
            f"{v} {g.loc[v, 'error']:.3g}" if g.loc[v, "status"] == "ok" else f"{v} fails"
            for v in VARIANTS
        )
        out.findings.append(
            f"{w['scene']}: cheapest within {TOLERANCE:.0%} of the best spring error is "
            f"{w['cheapest adequate']} (error {w['its error']:.3g}, solve "
            f"{w['its solve time']:.2g} s); best is {w['best variant']} "
            f"({w['best error']:.3g}); with the spec's parts on the analytic calibration "
            f"only, {w['cheapest adequate (analytic cal.)']} "
            f"({w['its error (analytic cal.)']:.3g}). Model errors: {errs}."
        )

    def step(name: str, a: str, b: str) -> str:
        g = df[df.scene == name].set_index("variant")
        fmt = [
            f"{g.loc[v, 'error']:.3g}" if g.loc[v, "status"] == "ok" else "fails" for v in (a, b)
        ]
        return f"{name} {fmt[0]} → {fmt[1]}"

    buys = [
        ("torsion (energy)", "axial", "axial+energy"),
        ("volume springs", "axial+energy", "axial+energy+volume"),
        ("LMS (abs)", "axial+energy+volume", "+LMS (abs)"),
        ("nnls calibration", "axial+energy+volume", "+volume (nnls cal.)"),
    ]
    out.findings.insert(
        0,
        "What each part buys (model error before → after): "
        + "; ".join(f"{part}: " + ", ".join(step(n, a, b) for n in names) for part, a, b in buys)
        + ".",
    )
    same = [
        n
        for n in names
        for g in [df[df.scene == n].set_index("variant")]
        if g.loc["axial", "status"] == "ok" == g.loc["axial+energy", "status"]
        and abs(g.loc["axial+energy", "error"] - g.loc["axial", "error"])
        <= 1e-3 * g.loc["axial", "error"]
    ]
    if same:
        g = df.set_index(["scene", "variant"])
        pairs = ", ".join(
            f"{n} {g.loc[(n, 'axial+volume'), 'error']:.3g} vs "
            f"{g.loc[(n, 'axial+energy+volume'), 'error']:.3g}"
            for n in same
        )
        out.findings.append(
            f"Without volume springs, torsion springs change nothing in {', '.join(same)} (a "
            "stretch along the element axes shears no pair of axes); with volume springs they "
            f"are needed all the same: axial+volume against axial+energy+volume errors are "
            f"{pairs}. On these meshes the radial tensor of an element is anisotropic, so "
            "the volume spring couples normal strain to shear, which only torsion resists."
        )
    ax_fail = df[(df.variant == "axial") & (df.status != "ok")].scene.tolist()
    out.findings.append(
        "Axial springs alone carry no shear: "
        + (
            f"the static solve fails on {', '.join(ax_fail)} (singular tangent or no convergence)"
            if ax_fail
            else "they never failed here"
        )
        + "; where they solve, they ignore the material's Poisson coupling."
    )
    lms = df[df.variant == "+LMS (abs)"]
    if len(lms):
        out.findings.append(
            f"LMS needs a dynamic solver: dynamic relaxation from rest (at most {dr_steps} "
            f"steps, residual tolerance {DR_TOL:g}): "
            + "; ".join(
                f"{r.scene} {'converged' if r.status == 'ok' else 'did not converge'} in "
                f"{r.solve_time:.2g} s (error {r.error:.3g}, median k_s/k_s0 "
                f"{r.k_ratio_median:.3g})"
                if np.isfinite(r.solve_time)
                else f"{r.scene} {r.status}"
                for r in lms.itertuples()
            )
            + f" — against {', '.join(f'{k} {v:.2g} s' for k, v in fem_times.items())} for "
            "FEM P1."
        )
    for name in names:
        g = df[df.scene == name]
        out.headline[f"n_fail_{name}"] = float((g.status != "ok").sum())
    return out
