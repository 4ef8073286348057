"""Study ``ablation``: "model no more than a scene needs".

For every scene (the bundled ones, coarse meshes in the quick settings, or the user's
``--scene``) the spring model is solved with its parts switched on one by one
(:data:`ALL_VARIANTS`): axial springs only; + volume springs; + torsion (the spec's cosine
law, eqs 2.44–2.45, or the energy-consistent one); + both; the full model with
sign-consistent LMS (which acts once per time step, so it runs dynamic relaxation from
rest) or with the per-element least-squares (nnls) calibration; and the exact element
(axis-volume, energy torsion, exact calibration) without and with Poisson-coupling springs.

Model error is the relative L2 error of the vertex displacements against FEM P1 (the scene's
law) on the same mesh; total error is the convergence study's business. Cost is the wall
time of the static solve (Newton with the analytic Hessian, a coloured finite-difference
Jacobian for cosine torsion; median of 3 under half a second) and the throughput of the
serial force kernel. A variant the solver cannot bring to equilibrium (a singular tangent:
axial springs alone have zero-energy modes; or no convergence) is recorded as ``fails``.
The cheapest adequate variant of a scene is the fastest whose model error is within
:data:`TOLERANCE` (relative) of the best spring variant's (:func:`cheapest_adequate`).

Examples
--------
>>> list(ALL_VARIANTS)[:2]
['spring-axial', 'spring-axial+volume']
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from springfem.errors import SpringFemError
from springfem.scene import Scene

from . import models
from .metrics import median_time, relative_l2_error
from .registry import StudyContext, StudyOutput, study
from .scenes import COMPARISON_SCENES, StudyScene, case_scene, comparison_scenes
from .tables import pyplot


def _variants(*rows: tuple[str, str, dict]) -> dict[str, models.Model]:
    return {name: models.spring_variant(name, label, **kw) for name, label, kw in rows}


#: The specification's parts, in the order they switch on (ties break towards fewer).
VARIANTS = _variants(
    ("spring-axial", "axial springs only", {"torsion": "off", "volume": False}),
    ("spring-axial+volume", "+ volume springs", {"torsion": "off", "volume": True}),
    ("spring-axial+cosine", "+ cosine torsion", {"torsion": "cosine", "volume": False}),
    ("spring-axial+energy", "+ energy torsion", {"torsion": "energy", "volume": False}),
    ("spring-axial+cosine+volume", "cosine torsion + volume",
     {"torsion": "cosine", "volume": True}),
    ("spring-axial+energy+volume", "energy torsion + volume",
     {"torsion": "energy", "volume": True}),
    ("spring-axial+energy+volume+lms-abs", "+ sign-consistent LMS (dynamic relaxation)",
     {"torsion": "energy", "volume": True, "lms": "abs"}),
    ("spring-axial+energy+volume+nnls", "+ least-squares calibration",
     {"torsion": "energy", "volume": True, "calibration": "nnls"}),
)  # fmt: skip
#: The exact element without and with the Poisson-coupling springs (anisotropic materials).
EXACT_VARIANTS = _variants(
    ("spring-exact-no-coupling", "exact element without coupling", models.EXACT),
    ("spring-exact+coupling", "exact element + coupling", {"coupling": True, **models.EXACT}),
)
ALL_VARIANTS: dict[str, models.Model] = {**VARIANTS, **EXACT_VARIANTS}
#: The headline key of each exact variant's error.
HEADLINE_KEYS = {"spring-exact-no-coupling": "exact", "spring-exact+coupling": "exact_coupling"}
#: A variant is adequate when its model error is at most (1 + TOLERANCE) x the best one's.
TOLERANCE = 0.10
#: Solve times within this fraction of the fastest count as a tie (timer noise).
TIME_TIE = 0.25
#: The default absolute model-error budget (``study ablation --tolerance``).
MAX_ERROR = 0.10
#: Newton settings shared by every static solve; dynamic relaxation's tolerance (LMS).
NEWTON = {"tol": 1e-8, "max_iter": 25, "max_cutbacks": 4}
DR_TOL = 1e-6
VERSION = 2


@dataclass(frozen=True)
class Settings:
    """Meshes and step budget: ``divisions`` (scene name -> box divisions, ``None``: the
    bundled mesh), ``extra`` (the cantilever's other meshes), ``dr_steps`` (the LMS
    variant's dynamic-relaxation budget), ``max_error`` (the winners table names the
    cheapest variant with at most this model error)."""

    divisions: dict[str, tuple[int, int, int] | None] = field(
        default_factory=lambda: dict.fromkeys(COMPARISON_SCENES)
    )
    dr_steps: int = 8000
    max_error: float = MAX_ERROR
    extra: dict[str, tuple[int, int, int]] = field(default_factory=lambda: {
        "cantilever-unstructured": (40, 4, 4), "cantilever-elongated": (20, 4, 4)})  # fmt: skip

    @classmethod
    def full(cls) -> Settings:
        """The bundled meshes, 8000 relaxation steps."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """Coarse meshes, 4000 relaxation steps."""
        coarse: dict[str, tuple[int, int, int] | None] = {
            "cantilever": (20, 2, 2), "stretch-fiber": (3, 3, 3),
            "stretch-cross": (3, 3, 3), "sag": (8, 4, 2)}  # fmt: skip
        extra = {"cantilever-unstructured": (20, 2, 2), "cantilever-elongated": (10, 2, 2)}
        return cls(divisions=coarse, dr_steps=4000, extra=extra)


def bundled_scenes(settings: Settings) -> list[StudyScene]:
    """The bundled scenes on the settings' meshes, then the cantilever's other meshes."""
    return comparison_scenes(settings.divisions, settings.extra)


def _timed(fn, repeat_below: float = 0.5, repeats: int = 3) -> tuple[Any, float]:
    """Result and wall time of ``fn()``; the median of ``repeats`` runs if it is fast."""
    t0 = time.perf_counter()
    out = fn()
    times = [time.perf_counter() - t0]
    while times[0] < repeat_below and len(times) < repeats:
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return out, float(np.median(times))


def reference_model(scene: Scene) -> models.Model:
    """The same-mesh FEM reference: P1 with the scene's law (``P1-NH`` for neo-Hookean)."""
    return models.P1_NH if scene.material.law == "neo-hookean" else models.P1


def fem_case(case: dict[str, Any]) -> dict[str, Any]:
    """The same-mesh FEM reference of a scene: vertex displacements and wall time."""
    scene = case_scene(case)
    got = models.run(scene, reference_model(scene), lambda m, s: _timed(lambda: m.solve(s)))
    if not got.ok:
        return {"status": "fails", "message": got.message[:200]}
    sol, wall = got.solution
    return {"status": "ok", "u": sol.u.tolist(), "time": wall, "law": sol.result.law}


def spring_case(case: dict[str, Any]) -> dict[str, Any]:
    """One spring variant (``variant``) on one scene: ``status`` (``ok``/``fails``),
    ``message``, ``u`` (also the last state of a dynamic relaxation that did not converge),
    ``solve_time``, ``build_time``, ``kernel_rate`` (elements/s), ``method``,
    ``iterations``, ``residual`` and, for LMS, the median stiffness ratio and the share at
    the upper clamp."""
    from springfem.mechanics import explicit_static, static
    from springmodel.model import SpringModel

    scene = case_scene(case)
    opts = ALL_VARIANTS[case["variant"]].spring_options(scene)
    t0 = time.perf_counter()
    try:
        model = SpringModel(scene, opts, parallel=False)
    except SpringFemError as exc:  # a calibration that refuses the material
        return {"status": "fails", "message": str(exc)[:200], "tets": scene.mesh.n_tets}
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
        return info  # fmt: skip

    def timed(m, s):
        # a singular tangent (axial springs only) makes the Krylov fallback divide by zero
        # before the solver reports the failure: silence numpy's warnings, keep the error
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            return _timed(solve, repeat_below=0.5 if opts.lms is None else 0.0)

    got = models.run(scene, case["variant"], solve=timed)
    if not got.ok:
        return {**out, "status": "fails", "message": got.message[:200]}
    info, wall = got.solution
    out.update(status="ok" if info.converged else "fails",
               message="" if info.converged else (info.message or "not converged")[:200],
               u=(info.x - x0).tolist(), solve_time=wall, method=info.method,
               iterations=int(info.iterations), residual=float(info.residual))  # fmt: skip
    if hasattr(info, "k_ratio"):
        out["k_ratio_median"] = float(np.median(info.k_ratio))
        out["k_ratio_at_max"] = float(np.mean(info.k_ratio >= opts.lms.k_max * (1 - 1e-12)))
    return out


def model_error(case: dict[str, Any], result: dict[str, Any], u_ref: Any) -> tuple[float, float]:
    """Relative L2 error of the vertex displacements and the largest relative probe error
    (displacement vector) of a :func:`spring_case` result against ``u_ref`` (NaN: no
    solution)."""
    if "u" not in result:
        return float("nan"), float("nan")
    u, u_ref = np.asarray(result["u"]), np.asarray(u_ref)
    scene = case_scene(case)
    a, b = scene.probe_displacements(u), scene.probe_displacements(u_ref)
    errs = [np.linalg.norm(np.subtract(a[k], b[k])) / np.linalg.norm(b[k]) for k in a]
    return relative_l2_error(u, u_ref), float(max(errs)) if errs else float("nan")


def cheapest_adequate(
    df: pd.DataFrame, tolerance: float = TOLERANCE, max_error: float | None = None
) -> pd.Series | None:
    """The cheapest adequate variant among the ``ok`` rows of one scene, or ``None``.

    Adequate: model error at most ``(1 + tolerance)`` times the smallest (with
    ``max_error``: at most ``max_error``). Cheapest: the smallest ``solve_time``; times within
    :data:`TIME_TIE` of it tie, broken by the order of :data:`ALL_VARIANTS` (fewer parts
    first), so timer noise does not pick the winner.
    """
    ok = df[(df.status == "ok") & np.isfinite(df.error)]
    if ok.empty:
        return None
    adequate = ok[ok.error <= ((1.0 + tolerance) * ok.error.min() if max_error is None
                               else max_error)]  # fmt: skip
    if adequate.empty:
        return None
    tied = adequate[adequate.solve_time <= (1.0 + TIME_TIE) * adequate.solve_time.min()]
    order = {v: i for i, v in enumerate(ALL_VARIANTS)}
    return tied.loc[tied.variant.map(order).sort_values().index[0]]


def _field(row: pd.Series | None, column: str, missing: Any) -> Any:
    return missing if row is None else row[column]


def _winners(df: pd.DataFrame, max_error: float) -> tuple[pd.DataFrame, dict[str, float]]:
    """Per scene: the best variant, the cheapest adequate ones, the cheapest within
    ``max_error`` (the spec's parts, then all variants: ``(with exact)``), the failures; and
    the headline's best, full-model and exact errors."""
    headline: dict[str, float] = {}
    rows = []
    ladder = [v for v in VARIANTS if "nnls" not in v]  # the spec's parts, analytic cal.
    for name, g_all in df.groupby("scene", sort=False):
        g = g_all[g_all.variant.isin(VARIANTS)]
        best = g[g.status == "ok"].sort_values("error")
        win = cheapest_adequate(g)
        if win is None:
            rows.append({"scene": name, "cheapest adequate": "none (all fail)"})
            continue
        win_ladder = cheapest_adequate(g[g.variant.isin(ladder)])
        rows.append({
            "scene": name, "best variant": best.variant.iloc[0], "best error": best.error.iloc[0],
            "cheapest adequate": win.variant, "its error": win.error,
            "its solve time": win.solve_time,
            "cheapest adequate (analytic cal.)": _field(win_ladder, "variant", "none"),
            "its error (analytic cal.)": _field(win_ladder, "error", np.nan),
            f"cheapest with error <= {max_error:g}": _field(
                cheapest_adequate(g, max_error=max_error), "variant", "none"),
            "fails": ", ".join(g[g.status != "ok"].variant) or "none",
        })  # fmt: skip
        if g_all.variant.isin(EXACT_VARIANTS).any():
            win_x = cheapest_adequate(g_all)
            best_x = g_all[g_all.status == "ok"].sort_values("error")
            x_fails = g_all[(g_all.status != "ok") & g_all.variant.isin(EXACT_VARIANTS)]
            rows[-1].update({
                f"cheapest with error <= {max_error:g} (with exact)": _field(
                    cheapest_adequate(g_all, max_error=max_error), "variant", "none"),
                "best (with exact)": best_x.variant.iloc[0],
                "best error (with exact)": best_x.error.iloc[0],
                "cheapest adequate (with exact)": _field(win_x, "variant", "none"),
                "its error (with exact)": _field(win_x, "error", np.nan),
                "its solve time (with exact)": _field(win_x, "solve_time", np.nan),
                "exact fails": ", ".join(x_fails.variant) or "none",
            })  # fmt: skip
            headline[f"best_error_with_exact_{name}"] = round(float(best_x.error.iloc[0]), 4)
            for v in EXACT_VARIANTS:
                row = g_all[g_all.variant == v]
                if len(row) and row.status.iloc[0] == "ok":
                    headline[f"{HEADLINE_KEYS[v]}_error_{name}"] = float(row.error.iloc[0])
        headline[f"best_error_{name}"] = round(float(best.error.iloc[0]), 4)
        full = g[g.variant == "spring-axial+energy+volume"]
        if len(full) and full.status.iloc[0] == "ok":
            headline[f"full_error_{name}"] = round(float(full.error.iloc[0]), 4)
    return pd.DataFrame(rows), headline


def _findings(df, winners, fem_times, dr_steps, notes, headline) -> list[str]:
    """The findings; adds the failed variants per scene to ``headline``."""
    names = list(df.scene.unique())
    by = df.set_index(["scene", "variant"])

    def err(n: str, v: str) -> str:
        return f"{by.loc[(n, v), 'error']:.3g}" if by.loc[(n, v), "status"] == "ok" else "fails"

    buys = [("torsion (energy)", "spring-axial", "spring-axial+energy"),
            ("volume springs", "spring-axial+energy", "spring-axial+energy+volume"),
            ("LMS (abs)", "spring-axial+energy+volume", "spring-axial+energy+volume+lms-abs"),
            ("nnls calibration", "spring-axial+energy+volume", "spring-axial+energy+volume+nnls"),
            ("exact element", "spring-axial+energy+volume", "spring-exact-no-coupling"),
            ("coupling springs", "spring-exact-no-coupling", "spring-exact+coupling")]  # fmt: skip
    findings = [
        "What each part buys (model error before → after): "
        + "; ".join(f"{part}: " + ", ".join(f"{n} {err(n, a)} → {err(n, b)}" for n in names)
                    for part, a, b in buys) + ".",
        *notes,
    ]  # fmt: skip
    for _, w in winners.iterrows():
        n = w["scene"]
        if pd.isna(w.get("best variant")):
            findings.append(f"{n}: every spring variant fails.")
            continue
        findings.append(
            f"{n}: cheapest within {TOLERANCE:.0%} of the best spring error is "
            f"{w['cheapest adequate']} (error {w['its error']:.3g}, solve "
            f"{w['its solve time']:.2g} s); best is {w['best variant']} ({w['best error']:.3g}); "
            f"with the spec's parts on the analytic calibration only, "
            f"{w['cheapest adequate (analytic cal.)']} ({w['its error (analytic cal.)']:.3g}). "
            f"Model errors: {', '.join(f'{v} {err(n, v)}' for v in VARIANTS)}."
        )
        col = next((c for c in w.index if str(c).startswith("cheapest with error <=")
                    and str(c).endswith("(with exact)")), None)  # fmt: skip
        if col is not None and pd.notna(w[col]):
            pick, limit = w[col], str(col).split("<= ")[1].split(" ")[0]
            findings.append(
                f"{n}: the cheapest variant with a model error of at most {limit} "
                + (f"is {pick} (error {by.loc[(n, pick), 'error']:.3g}, solve "
                   f"{by.loc[(n, pick), 'solve_time']:.2g} s)." if (n, pick) in by.index
                   else "is none: no variant qualifies.")
            )  # fmt: skip
    ok, e = by["status"] == "ok", by["error"]
    same = [n for n in names if ok[(n, "spring-axial")] and ok[(n, "spring-axial+energy")]
            and abs(e[(n, "spring-axial+energy")] - e[(n, "spring-axial")])
            <= 1e-3 * e[(n, "spring-axial")]]  # fmt: skip
    if same:
        pairs = ", ".join(
            f"{n} {by.loc[(n, 'spring-axial+volume'), 'error']:.3g} vs "
            f"{by.loc[(n, 'spring-axial+energy+volume'), 'error']:.3g}"
            for n in same
        )
        findings.append(
            f"Without volume springs, torsion springs change nothing in {', '.join(same)} (a "
            "stretch along the element axes shears no pair of axes); with volume springs they "
            f"are needed all the same: axial+volume against axial+energy+volume errors are "
            f"{pairs}. On these meshes the radial tensor of an element is anisotropic, so "
            "the volume spring couples normal strain to shear, which only torsion resists."
        )  # fmt: skip
    ax_fail = df[(df.variant == "spring-axial") & (df.status != "ok")].scene.tolist()
    findings.append(
        "Axial springs alone carry no shear: "
        + (f"the static solve fails on {', '.join(ax_fail)} (singular tangent or no "
           "convergence)" if ax_fail else "they never failed here")
        + "; where they solve, they ignore the material's Poisson coupling."
    )  # fmt: skip
    lms = df[df.variant == "spring-axial+energy+volume+lms-abs"]
    if len(lms):
        runs = "; ".join(
            f"{r.scene} {'converged' if r.status == 'ok' else 'did not converge'} in "
            f"{r.solve_time:.2g} s (error {r.error:.3g}, median k_s/k_s0 {r.k_ratio_median:.3g})"
            if np.isfinite(r.solve_time) else f"{r.scene} {r.status}"
            for r in lms.itertuples()
        )  # fmt: skip
        findings.append(
            f"LMS needs a dynamic solver: dynamic relaxation from rest (at most {dr_steps} "
            f"steps, residual tolerance {DR_TOL:g}): {runs} — against "
            f"{', '.join(f'{k} {v:.2g} s' for k, v in fem_times.items())} for FEM P1."
        )
    for n in names:  # the specification's parts that fail
        g = df[(df.scene == n) & df.variant.isin(VARIANTS)]
        headline[f"n_fail_{n}"] = float((g.status != "ok").sum())
    if "cheapest adequate (with exact)" in winners.columns:
        parts = [
            f"{w['scene']} {w.get('cheapest adequate')} ({w.get('its error', np.nan):.3g}) → "
            f"{w['cheapest adequate (with exact)']} ({w['its error (with exact)']:.3g})"
            + (" (unchanged)" if w["cheapest adequate (with exact)"] == w.get("cheapest adequate")
               else "")
            for _, w in winners.iterrows() if pd.notna(w.get("cheapest adequate (with exact)"))
        ]  # fmt: skip
        if parts:
            findings.append(
                "With the exact element among the candidates the cheapest adequate model "
                f"(error within {TOLERANCE:.0%} of the best) changes: " + "; ".join(parts) + ". "
                "The specification's variants are no longer adequate anywhere: their error is "
                "the calibration's. The reference is P1 with the scene's law: for a linear "
                "material (all scenes but the sag) the exact element's remainder is the "
                "geometric nonlinearity of the finite-strain spring model (the accuracy study "
                "measures it against P1 neo-Hookean: ~1e-5); for a neo-Hookean scene (the "
                "sag) it is the model error proper."
            )
    return findings


def _figure(ctx: StudyContext, df: pd.DataFrame, winners: pd.DataFrame, fem_times: dict):
    """Model error against static solve time, one panel per scene, winners circled, the FEM
    P1 solve time a vertical line."""
    from matplotlib.ticker import LogLocator, NullFormatter

    plt = pyplot()
    names = list(df.scene.unique())
    ncol = min(len(names), 3)
    nrow = -(-len(names) // ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.4 * ncol, 4.0 * nrow + 1.2), squeeze=False,
                             layout="constrained")  # fmt: skip
    markers = dict(zip(ALL_VARIANTS, "o<v^sDP*XH"))
    colors = dict(zip(ALL_VARIANTS, plt.rcParams["axes.prop_cycle"].by_key()["color"]))
    handles: dict[str, Any] = {}
    for ax, name in zip(axes.ravel(), names):
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
        for tag, ms, mec in (("", 17, "k"), (" (with exact)", 21, "r")):  # circle the winners
            col = f"its error{tag}"
            if len(w) and col in w and np.isfinite(w[col].iloc[0]):
                (h,) = ax.loglog(w[f"its solve time{tag}"].iloc[0], w[col].iloc[0], "o", ms=ms,
                                 mfc="none", mec=mec)  # fmt: skip
                handles[f"cheapest adequate{tag}"] = h
        if name in fem_times:
            handles["FEM P1 solve time"] = ax.axvline(fem_times[name], color="k", ls=":", lw=1)
        failed = ", ".join(g[(g.status != "ok") & ~np.isfinite(g.error)].variant)
        title = f"{name} ({int(g.tets.iloc[0])} tets)" + (f"\nfails: {failed}" if failed else "")
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("static solve wall time (s)")
        ax.grid(alpha=0.3, which="both")
        for axis in (ax.xaxis, ax.yaxis):  # decade labels only: no crowded minor labels
            axis.set_minor_formatter(NullFormatter())
        lo, hi = ax.get_ylim()
        if hi / lo < 100:  # under 2 decades: label 1 and 3 of each decade too
            ax.yaxis.set_major_locator(LogLocator(subs=(1.0, 3.0)))
    for ax in axes.ravel()[len(names) :]:
        ax.set_visible(False)
    for row in axes:
        row[0].set_ylabel("model error vs FEM P1 (relative L2)")
    rank = {v: i for i, v in enumerate(ALL_VARIANTS)}
    keys = sorted(handles, key=lambda k: rank.get(k.split(" (not")[0], len(rank)))
    fig.legend([handles[k] for k in keys], keys, loc="outside lower center", ncol=4, fontsize=8)
    summary = "; ".join(f"{w['scene']}: {w['cheapest adequate']}"
                        + (f" ({w['its error']:.3g})" if pd.notna(w.get("its error")) else "")
                        for _, w in winners.iterrows())  # fmt: skip
    return ctx.figure(
        fig,
        "error_vs_cost.png",
        "Model error against static solve time for each spring variant (hollow: the "
        "last state of a run that did not converge; variants that fail outright are "
        "named in the panel); circled: the cheapest variant within "
        f"{TOLERANCE:.0%} of the best error among the specification's parts (black) and with "
        "the exact element included (red). FEM P1 has the scene's law (linear except the "
        f"sag). Cheapest adequate (error): {summary}.",
    )


@study("ablation", Settings, bundled_scenes)
def run(ctx: StudyContext, scenes: list[StudyScene], settings: Settings) -> StudyOutput:
    """Solve every variant on every scene against its same-mesh FEM P1."""
    rows, fem_times, notes = [], {}, []
    for s in scenes:
        name = s.label
        ref = reference_model(s.build()).name
        fem = ctx.cache.run([s.case("ablation", VERSION, model=ref)], fem_case, ctx.progress,
                            name)[0]  # fmt: skip
        if fem["status"] != "ok":
            notes.append(f"{name}: the FEM P1 reference fails ({fem['message']}).")
            continue
        fem_times[name] = fem["time"]
        cases = [s.case("ablation", VERSION, variant=v, dr_steps=settings.dr_steps)
                 for v in ALL_VARIANTS]  # fmt: skip
        for c, r in zip(cases, ctx.cache.run(cases, spring_case, ctx.progress, name)):
            error, probe_error = model_error(c, r, fem["u"])
            rows.append({
                "scene": name, "tets": r.get("tets"), "variant": c["variant"],
                "status": r["status"], "error": error, "probe_error": probe_error,
                "solve_time": r.get("solve_time", np.nan),
                "kernel_Mtets/s": r.get("kernel_rate", np.nan) / 1e6,
                "method": r.get("method", ""), "iterations": r.get("iterations", np.nan),
                "message": r.get("message", ""), "k_ratio_median": r.get("k_ratio_median", np.nan),
            })  # fmt: skip
    df = pd.DataFrame(rows)
    winners, headline = _winners(df, settings.max_error)
    findings = _findings(df, winners, fem_times, settings.dr_steps, notes, headline)
    table = df.drop(columns=["k_ratio_median"]).assign(fem_p1_time=df.scene.map(fem_times))
    tables = [
        ctx.table(table, "ablation", "Spring-model parts switched on one by one, per scene: "
                  "status, model error (relative L2 of vertex displacements against FEM P1 on "
                  "the same mesh), largest probe error, static solve wall time (s; the LMS "
                  "variant: dynamic relaxation), serial force-kernel throughput (M elements/s), "
                  "solver method and iterations, and the FEM P1 solve time for scale."),
        ctx.table(winners, "winners", "Per scene: the most accurate spring variant; the "
                  f"cheapest variant (smallest static solve time, ties within {TIME_TIE:.0%} "
                  f"broken towards fewer parts) whose model error is within {TOLERANCE:.0%} of "
                  "the best, over all variants and over the analytic-calibration ladder of the "
                  "spec's parts only; the cheapest with a model error of at most "
                  f"{settings.max_error:.0%} (the tolerance); and the variants that fail. The "
                  "'(with exact)' columns recompute the best, the cheapest adequate and the "
                  "cheapest within the tolerance with the exact element (axis-volume + energy "
                  "torsion + exact calibration, ± coupling) included."),
    ]  # fmt: skip
    user = f" ({scenes[0].label})" if scenes and scenes[0].user else ""
    return StudyOutput(ctx.name, "Ablation: model no more than a scene needs" + user, findings,
                       tables, [_figure(ctx, df, winners, fem_times)], headline)  # fmt: skip
