"""Study ``volume_drift``: how well each volume treatment holds volume.

A nearly incompressible block (ν = 0.49, E = 5 kPa) in uniaxial stress along z (the base
slides freely, one point and one edge pinned against rigid motion) is compressed and pulled,
and the bundled ``sag`` scene (ν = 0.45, neo-Hookean, clamped at one end) sags under its own
weight. The spring model runs with

* ``volume off``: axial + torsion (energy) springs only,
* ``volume on``: + barycentric volume springs (2.76–2.77, gradient form),
* ``LMS spec``: + adaptive volume stiffness, eq. 2.81 as written (``k += mu dV sum|xi|``),
* ``LMS abs``: + the sign-consistent rule (``k += mu |dV| sum|xi|``),
* ``volume on (nnls)``: volume springs with the per-element least-squares calibration,

through explicit dynamics (:func:`springfem.mechanics.solvers.explicit`, LMS applied by the model's
``post_step`` once per step): a suddenly applied load (drift against time) and a slow load
ramp (drift against load factor). The FEM reference (P1, linear and neo-Hookean, static) and
the small-strain analytic volume change ``tr eps = (1 - 2 nu) sigma / E`` give what the
material itself does.

All explicit runs of one scene use the same time step, ``0.5 dt_crit / sqrt(k_max)`` with
``dt_crit`` of the ``volume on`` model: LMS may stiffen a volume spring up to ``k_max`` times,
which raises ``omega_max`` by up to ``sqrt(k_max)``.

Drift measures: ``|dV|/V0`` of the whole body, and the element drift
``sum_k |V_k - V0_k| / V0`` (in bending, compressed and stretched elements cancel in the
total). ``|dL|/L0`` is the mean relative change of the radial sums ``sum_j |xi_j|``, the
quantity a volume spring actually restores.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import pandas as pd

from springfem.errors import SolverError
from springfem.scene import Scene, parse_scene
from springmodel.options import LMSOptions, SpringOptions

from .cli import SCENES
from .registry import Figure, StudyContext, StudyOutput, Table, study
from .tables import save_figure, write_table

#: A cube in uniaxial stress along z: the base slides (u_z = 0), the origin is pinned in x, y
#: and the corner (L, 0, 0) in y, so only rigid motion is removed.
CUBE = """
name = "drift-cube"
[mesh]
generator = "box"
size = [{L}, {L}, {L}]
divisions = [{n}, {n}, {n}]
split = "six"
[material]
law = "{law}"
E = {E}
nu = {nu}
density = {rho}
[axes]
fiber = [1.0, 0.0, 0.0]
sheet = [0.0, 1.0, 0.0]
[[boundary]]
region = "z_min"
fix = ["z"]
[[boundary]]
region = {{ point = [0.0, 0.0, 0.0] }}
fix = ["x", "y"]
[[boundary]]
region = {{ point = [{L}, 0.0, 0.0] }}
fix = ["y"]
[[load]]
type = "traction"
region = "z_max"
value = [0.0, 0.0, {stress}]
[spring]
torsion = "energy"
"""

CUBE_L = 0.01
CUBE_E = 5.0e3
CUBE_RHO = 1000.0
#: Peak uniaxial stress of the cube: 10 % of E (strains of ~10 %).
CUBE_STRESS = 0.1 * CUBE_E

#: Spring-model variants: label -> changes to the scene's ``[spring]`` options.
VARIANTS: dict[str, dict[str, Any]] = {
    "volume off": {"volume": False},
    "volume on": {"volume": True},
    "LMS spec": {"volume": True, "lms": "spec"},
    "LMS abs": {"volume": True, "lms": "abs"},
    "volume on (nnls)": {"volume": True, "calibration": "nnls"},
}
#: Clamp of the LMS stiffness ratio (the :class:`LMSOptions` defaults).
K_MIN, K_MAX = LMSOptions().k_min, LMSOptions().k_max
#: Element drift above which a run counts as diverged and is stopped.
DIVERGED = 1.0
COLORS = {
    "volume off": "tab:gray",
    "volume on": "tab:blue",
    "LMS spec": "tab:red",
    "LMS abs": "tab:green",
    "volume on (nnls)": "tab:purple",
}


# ------------------------------------------------------------------------------ scenes


def cube_scene(
    n: int = 3, nu: float = 0.49, stress: float = -CUBE_STRESS, law: str = "linear"
) -> Scene:
    """The block in uniaxial stress ``stress`` (Pa, negative = compression) along z."""
    return parse_scene(
        CUBE.format(L=CUBE_L, n=n, law=law, E=CUBE_E, nu=nu, rho=CUBE_RHO, stress=stress)
    )


def sag_scene(divisions: tuple[int, int, int] = (16, 8, 4)) -> Scene:
    """The bundled ``sag`` scene on a ``divisions`` box mesh."""
    text = (SCENES / "sag.toml").read_text()
    text = re.sub(r"divisions = \[.*\]", f"divisions = {list(divisions)}", text)
    return parse_scene(text)


def case_scene(case: dict[str, Any], law: str = "linear") -> Scene:
    """The scene a case describes (``scene`` = ``cube`` or ``sag``)."""
    if case["scene"] == "cube":
        return cube_scene(case["n"], case["nu"], case["stress"], law)
    return sag_scene(tuple(case["divisions"]))


def spring_options(scene: Scene, variant: str) -> SpringOptions:
    """The scene's spring options with a variant's changes (see :data:`VARIANTS`)."""
    changes = dict(VARIANTS[variant])
    rule = changes.pop("lms", None)
    if rule is not None:
        changes["lms"] = LMSOptions(rule=rule, k_min=K_MIN, k_max=K_MAX)
    return replace(SpringOptions.of(scene), **changes)


def first_period(scene: Scene) -> float:
    """Time scale of the slowest motion that sets the run lengths and damping: for the cube
    the period of a quarter-wave rod of its height (from E and the density); for the sag
    scene a fixed 0.5 s (the block swings down and back in roughly that time, see the
    drift-against-time figure)."""
    mat = scene.material
    c = np.sqrt(mat.E / mat.density)
    if scene.name == "drift-cube":
        return 4.0 * CUBE_L / c
    return 0.5


# ----------------------------------------------------------------------------- metrics


def drift_measures(scene: Scene, x: np.ndarray) -> dict[str, float]:
    """Total and element volume drift and radial-sum change at positions ``x``."""
    V0 = scene.mesh.volumes()
    V = scene.mesh.volumes(x)
    X, X0 = x[scene.mesh.tets], scene.mesh.points[scene.mesh.tets]
    L = np.linalg.norm(X - X.mean(axis=1, keepdims=True), axis=-1).sum(axis=1)
    L0 = np.linalg.norm(X0 - X0.mean(axis=1, keepdims=True), axis=-1).sum(axis=1)
    return {
        "dV": float((V.sum() - V0.sum()) / V0.sum()),
        "element_drift": float(np.abs(V - V0).sum() / V0.sum()),
        "dL": float(np.mean(np.abs(L - L0) / L0)),
        "inverted": int((V <= 0).sum()),
    }


def common_time_step(scene: Scene) -> float:
    """``0.5 dt_crit / sqrt(k_max)`` of the scene's ``volume on`` model (all variants)."""
    from springfem.mechanics import stable_time_step
    from springmodel.model import SpringModel

    model = SpringModel(scene, spring_options(scene, "volume on"), parallel=False)
    dt_crit, _ = stable_time_step(model)
    return 0.5 * dt_crit / np.sqrt(K_MAX)


# ------------------------------------------------------------------------------ cases


def dynamic_case(case: dict[str, Any]) -> dict[str, Any]:
    """One explicit run of a spring variant, recording drift over time.

    ``case``: ``scene`` (``cube`` with ``n``, ``nu``, ``stress``; or ``sag`` with
    ``divisions``), ``variant`` (a key of :data:`VARIANTS`), ``periods`` (run length in
    units of :func:`first_period`), ``ramp`` (periods of a linear load ramp, 0 = load
    applied suddenly), ``damping`` (mass damping as a fraction of ``2 pi / period``) and
    ``records`` (number of samples).

    Returns lists ``t``, ``load`` (load factor), ``dV``, ``element_drift``, ``dL``,
    ``k_median``, ``k_min``, ``k_max`` (LMS stiffness ratio ``k_s/k_s0``) and the final
    values; ``status`` is ``ok``, ``inverted`` (ended with inverted elements), ``diverged``
    (element drift above :data:`DIVERGED`: the run is stopped there) or ``blew up`` (the
    solver's numerical blow-up test); ``message`` says where and when.
    """
    from springfem.mechanics import explicit
    from springmodel.model import SpringModel

    scene = case_scene(case)
    opts = spring_options(scene, case["variant"])
    model = SpringModel(scene, opts, parallel=False)
    period = first_period(scene)
    dt = common_time_step(scene)
    steps = int(np.ceil(case["periods"] * period / dt))
    every = max(1, steps // int(case["records"]))
    t_ramp = case["ramp"] * period

    def load(t: float) -> float:
        return 1.0 if t_ramp <= 0 else min(1.0, t / t_ramp)

    rec: dict[str, list[float]] = {
        k: [] for k in ("t", "load", "dV", "element_drift", "dL", "k_median", "k_min", "k_max")
    }

    first_inverted: list[float] = []

    def sample(t: float, x: np.ndarray) -> bool:
        """Record one sample; ``True`` when the body has diverged (stop the run)."""
        m = drift_measures(scene, x)
        ratio = model.elements.k_volume / np.where(
            model.elements.k_volume0 > 0, model.elements.k_volume0, 1.0
        )
        if not opts.volume:
            ratio = np.zeros(1)
        rec["t"].append(t)
        rec["load"].append(load(t))
        for key in ("dV", "element_drift", "dL"):
            rec[key].append(m[key])
        rec["k_median"].append(float(np.median(ratio)))
        rec["k_min"].append(float(ratio.min()))
        rec["k_max"].append(float(ratio.max()))
        if m["inverted"] and not first_inverted:
            first_inverted.append(t)
        return not np.isfinite(m["element_drift"]) or m["element_drift"] > DIVERGED

    sample(0.0, model.x0)

    def callback(k: int, t: float, x: np.ndarray, v: np.ndarray) -> bool:
        return k % every == 0 and sample(t, x)

    status, message = "ok", ""
    x_end = None
    try:
        traj = explicit(
            model,
            dt=dt,
            steps=steps,
            mass_damping=case["damping"] * 2.0 * np.pi / period,
            scale=load,
            record_every=steps,
            callback=callback,
        )
        x_end = traj.x
        if traj.steps < steps:
            status = "diverged"
            message = (
                f"element drift above {DIVERGED:g} at t = {rec['t'][-1]:.4g} s (first inverted "
                f"element at t = {first_inverted[0]:.4g} s); run stopped"
            )
    except SolverError as exc:
        status, message = "blew up", str(exc)[:200]
    out: dict[str, Any] = {
        **rec,
        "status": status,
        "message": message,
        "dt": dt,
        "steps": steps,
        "first_inverted": first_inverted[0] if first_inverted else None,
    }
    if x_end is not None:
        out["final"] = drift_measures(scene, x_end)
        if status == "ok" and out["final"]["inverted"]:
            status = out["status"] = "inverted"
            out["message"] = f"{out['final']['inverted']} inverted elements at the end"
        out["final"]["k_median"] = rec["k_median"][-1]
        out["final"]["k_min"] = rec["k_min"][-1]
        out["final"]["k_max"] = rec["k_max"][-1]
        out["final"]["peak_dV"] = float(np.abs(rec["dV"]).max())
        out["final"]["peak_element_drift"] = float(np.max(rec["element_drift"]))
    return out


def static_case(case: dict[str, Any]) -> dict[str, Any]:
    """Static equilibrium of the cube at load factor ``load``: a spring variant without
    LMS (Newton, ``model = "spring"``) or FEM (``model = "fem"``, ``law``, ``order``).

    Returns the drift measures and ``status`` (``ok`` or ``fails`` with ``message``).
    """
    scene = cube_scene(case["n"], case["nu"], case["stress"] * case["load"])
    try:
        if case["model"] == "spring":
            from springfem.mechanics import static
            from springmodel.model import SpringModel

            model = SpringModel(scene, spring_options(scene, case["variant"]), parallel=False)
            x = static(model, tol=1e-9, max_iter=30, fallback=False).x
        else:
            import reference_fem

            sol = reference_fem.solve(scene, order=case["order"], law=case["law"])
            x = scene.mesh.points + sol.u_vertices
    except SolverError as exc:
        return {"status": "fails", "message": str(exc)[:200]}
    return {**drift_measures(scene, x), "status": "ok"}


def sag_fem_case(case: dict[str, Any]) -> dict[str, Any]:
    """Static neo-Hookean P1 equilibrium of the sag scene (the material's own drift)."""
    import reference_fem

    scene = sag_scene(tuple(case["divisions"]))
    try:
        sol = reference_fem.solve(scene, order=1, law="neo-hookean")
    except SolverError as exc:
        return {"status": "fails", "message": str(exc)[:200]}
    return {**drift_measures(scene, scene.mesh.points + sol.u_vertices), "status": "ok"}


def analytic_drift(nu: float, stress: float, E: float = CUBE_E) -> float:
    """Small-strain volume change of uniaxial stress, ``tr eps = (1 - 2 nu) sigma / E``."""
    return (1.0 - 2.0 * nu) * stress / E


# -------------------------------------------------------------------------------- run


@dataclass(frozen=True)
class Settings:
    """Meshes, run lengths and loads of the volume-drift study.

    Parameters
    ----------
    n
        Divisions per side of the cube.
    sag
        Divisions of the sag scene (``None``: no sag runs).
    periods
        Length of the step-load runs in first periods.
    ramp_periods
        Ramp length of the slow-ramp runs in first periods.
    records
        Samples recorded per run.
    loads
        Fractions of the full stress of the static series.
    """

    n: int = 4
    sag: tuple[int, int, int] | None = (12, 6, 3)
    periods: float = 5.0
    ramp_periods: float = 6.0
    records: int = 120
    loads: tuple[float, ...] = (0.25, 0.5, 0.75, 1.0)

    @classmethod
    def full(cls) -> Settings:
        """4³ cube and the sag scene."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """2³ cube, no sag, shorter runs."""
        return cls(n=2, sag=None, periods=4.0, ramp_periods=5.0, records=60, loads=(0.5, 1.0))


@study("volume_drift", Settings)
def run(ctx: StudyContext, s: Settings) -> StudyOutput:
    """Run the volume-drift study (see the module docstring).

    Parameters
    ----------
    ctx
        Output folder, cache and preset.
    s
        Meshes, run lengths and loads.

    Returns
    -------
    StudyOutput
        Findings, drift tables, the drift figures, headline drifts.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    nu = 0.49
    out = StudyOutput(name=ctx.name, title="Volume drift: volume springs, LMS rules and FEM")
    cube = {"scene": "cube", "n": s.n, "nu": nu}

    # 1. dynamic runs: sudden load (against time) and slow ramp (against load factor)
    runs = []
    for sign, label in ((-1.0, "compressed"), (1.0, "pulled")):
        for kind, ramp, periods, damping in (
            ("step", 0.0, s.periods, 0.3),
            ("ramp", s.ramp_periods, s.ramp_periods + 1.0, 0.5),
        ):
            for v in VARIANTS:
                runs.append(
                    (
                        {
                            **cube,
                            "stress": sign * CUBE_STRESS,
                            "variant": v,
                            "ramp": ramp,
                            "periods": periods,
                            "damping": damping,
                            "records": s.records,
                        },
                        label,
                        kind,
                    )
                )
    if s.sag:
        for v in VARIANTS:
            runs.append(
                (
                    {
                        "scene": "sag",
                        "divisions": list(s.sag),
                        "variant": v,
                        "ramp": 0.0,
                        "periods": 2.0,
                        "damping": 0.4,
                        "records": s.records,
                    },
                    "sag",
                    "step",
                )
            )
    res = ctx.cache.run([r[0] for r in runs], dynamic_case, ctx.progress, "dynamic runs")
    dyn = [(c, label, kind, r) for (c, label, kind), r in zip(runs, res)]

    # 2. statics: spring (no LMS) and FEM against load factor, cube
    stat_cases = []
    for sign in (-1.0, 1.0):
        for f in s.loads:
            base = {**cube, "stress": sign * CUBE_STRESS, "load": f}
            for law in ("linear", "neo-hookean"):
                stat_cases.append({**base, "model": "fem", "law": law, "order": 1})
            if f == 1.0:
                for v in ("volume off", "volume on", "volume on (nnls)"):
                    stat_cases.append({**base, "model": "spring", "variant": v})
    stat_res = ctx.cache.run(stat_cases, static_case, ctx.progress, "statics")
    stat = pd.DataFrame(
        [
            {
                "model": (f"FEM P1 {c['law']}" if c["model"] == "fem" else c["variant"]),
                "load": np.sign(c["stress"]) * c["load"],
                **{k: r.get(k, np.nan) for k in ("dV", "element_drift", "dL")},
                "status": r["status"],
            }
            for c, r in zip(stat_cases, stat_res)
        ]
    )
    sag_ref = None
    if s.sag:
        sag_ref = ctx.cache.run(
            [{"scene": "sag", "divisions": list(s.sag), "model": "fem-neo-hookean"}],
            sag_fem_case,
            ctx.progress,
            "sag FEM",
        )[0]

    # ---- table of final drifts
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
    out.tables.append(
        Table(
            write_table(final, ctx.path("final_drift")),
            f"Volume drift at the end of each explicit run ({mesh_note}; peak cube stress "
            f"±{CUBE_STRESS / CUBE_E:.0%} of E) with the references: dV/V0 signed total change, "
            "element drift Σ|ΔV_k|/V0, |dL|/L0 mean change of the radial sums Σ|ξ_j| that the "
            "volume springs restore, and the LMS stiffness ratio k_s/k_s0 (clamp "
            f"[{K_MIN:g}, {K_MAX:g}]).",
        )
    )
    out.tables.append(
        Table(
            write_table(stat, ctx.path("static_drift")),
            "Static equilibria of the cube against signed load factor (−1 = full compression): "
            "FEM P1 linear and neo-Hookean, and the spring variants without LMS (Newton) at "
            "full load, which check that the slow ramps of the dynamic runs are quasi-static.",
        )
    )

    # ---- figure 1: drift against time
    panels = [("compressed", "step"), ("pulled", "step")] + ([("sag", "step")] if s.sag else [])
    fig, axes = plt.subplots(3, len(panels), figsize=(4.6 * len(panels), 9.5), squeeze=False)
    for j, (label, kind) in enumerate(panels):
        for c, lab, knd, r in dyn:
            if lab != label or knd != kind:
                continue
            v = c["variant"]
            t = np.asarray(r["t"]) * 1e3
            tag = f" ({r['status']})" if r["status"] != "ok" else ""
            kw = {"color": COLORS[v], "label": v + tag}
            axes[0, j].semilogy(t, np.abs(r["dV"]) + 1e-12, **kw)
            axes[1, j].semilogy(t, np.asarray(r["element_drift"]) + 1e-12, **kw)
            if "LMS" in v:
                axes[2, j].plot(t, r["k_median"], **kw)
                axes[2, j].fill_between(t, r["k_min"], r["k_max"], color=COLORS[v], alpha=0.15)
        if label != "sag":
            a = abs(analytic_drift(nu, CUBE_STRESS))
            for i in (0, 1):
                axes[i, j].axhline(a, color="k", ls="--", lw=1, label="analytic (static)")
            title = f"cube {label} (sudden ±{CUBE_STRESS:g} Pa)"
        else:
            if sag_ref is not None and sag_ref["status"] == "ok":
                axes[0, j].axhline(
                    abs(sag_ref["dV"]),
                    color="k",
                    ls="--",
                    lw=1,
                    label="FEM P1 neo-Hookean (static)",
                )
                axes[1, j].axhline(
                    sag_ref["element_drift"],
                    color="k",
                    ls="--",
                    lw=1,
                    label="FEM P1 neo-Hookean (static)",
                )
            title = "sag under gravity (sudden)"
        axes[0, j].set_title(title)
        axes[0, j].set_ylabel("|ΔV| / V0 (total)")
        axes[1, j].set_ylabel("Σ|ΔV_k| / V0 (elements)")
        axes[2, j].set_ylabel("LMS k_s/k_s0 (median, band min–max)")
        axes[2, j].set_yscale("log")
        axes[2, j].set_xlabel("time (ms)")
        for i in range(3):
            axes[i, j].grid(alpha=0.3, which="both")
        for i in (0, 1):
            axes[i, j].set_ylim(1e-4, 1.0)
        axes[0, j].legend(fontsize=7)
        axes[2, j].legend(fontsize=7)

    def fin(label: str, kind: str, variant: str, key: str = "dV") -> float:
        for c, lab, knd, r in dyn:
            if lab == label and knd == kind and c["variant"] == variant:
                return float(r.get("final", {}).get(key, np.nan))
        return float("nan")

    comp = {v: abs(fin("compressed", "step", v)) for v in VARIANTS}
    pull = {v: abs(fin("pulled", "step", v)) for v in VARIANTS}
    a_cube = abs(analytic_drift(nu, CUBE_STRESS))
    k_spec = fin("compressed", "step", "LMS spec", "k_median")
    k_abs = fin("compressed", "step", "LMS abs", "k_median")
    out.figures.append(
        Figure(
            save_figure(fig, ctx.path("drift_vs_time.png")),
            "Volume drift against time after a suddenly applied load (top: whole-body "
            "|ΔV|/V0; middle: element drift; bottom: LMS stiffness ratio, median and min–max "
            "band). The compressed cube ends at |ΔV|/V0 = "
            + ", ".join(f"{comp[v]:.3g} ({v})" for v in VARIANTS)
            + f" against {a_cube:.2g} for the material (dashed). In compression the spec "
            f"rule ends with median k_s/k_s0 = {k_spec:.3g} and the abs rule with {k_abs:.3g}: "
            f"relative to fixed volume springs, spec ends at "
            f"{_compare(comp['LMS spec'], comp['volume on'])} and abs at "
            f"{_compare(comp['LMS abs'], comp['volume on'])}." + _sag_caption(dyn),
        )
    )

    # ---- figure 2: drift against load factor
    fig, ax = plt.subplots(figsize=(7.5, 6.5))
    for v in VARIANTS:
        for label, sign in (("compressed", -1.0), ("pulled", 1.0)):
            for c, lab, knd, r in dyn:
                if lab == label and knd == "ramp" and c["variant"] == v and r["t"]:
                    load = sign * np.asarray(r["load"])
                    ax.semilogy(
                        load,
                        np.abs(r["dV"]) + 1e-12,
                        color=COLORS[v],
                        label=f"spring {v} (slow ramp)" if sign < 0 else None,
                    )
    for v, mk in (("volume off", "s"), ("volume on", "s"), ("volume on (nnls)", "s")):
        g = stat[(stat.model == v) & (stat.status == "ok")]
        ax.semilogy(
            g.load,
            np.abs(g.dV),
            mk,
            color=COLORS[v],
            mfc="none",
            ms=9,
            label=f"spring {v} (static Newton)",
        )
    for law, mk in (("linear", "o-"), ("neo-hookean", "^-")):
        g = stat[(stat.model == f"FEM P1 {law}") & (stat.status == "ok")].sort_values("load")
        for sign in (-1.0, 1.0):
            h = g[np.sign(g.load) == sign]
            ax.semilogy(
                h.load,
                np.abs(h.dV),
                mk,
                color="k",
                ms=5,
                lw=1,
                label=f"FEM P1 {law} (static)" if sign < 0 else None,
            )
    lf = np.linspace(-1, 1, 201)
    ax.semilogy(
        lf,
        np.abs(analytic_drift(nu, lf * CUBE_STRESS)) + 1e-12,
        "k--",
        lw=0.8,
        label="analytic (1−2ν)σ/E",
    )
    ax.set_xlabel(f"signed load factor (σ / {CUBE_STRESS:g} Pa; negative = compression)")
    ax.set_ylabel("|ΔV| / V0")
    ax.set_ylim(1e-4, 1.0)
    ax.set_title(f"Cube, ν = {nu}: volume change against load")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, ncol=2, loc="upper center", bbox_to_anchor=(0.5, -0.12))

    def ramp_end(label: str, v: str) -> float:
        return abs(fin(label, "ramp", v))

    fem_c = stat[(stat.model == "FEM P1 neo-hookean") & (stat.load == -1.0)]
    fem_c = abs(float(fem_c.dV.iloc[0])) if len(fem_c) else float("nan")
    out.figures.append(
        Figure(
            save_figure(fig, ctx.path("drift_vs_load.png")),
            "Whole-body |ΔV|/V0 of the cube against signed load factor: spring variants "
            "along slow quasi-static load ramps (lines; squares: Newton equilibria without "
            "LMS), FEM P1 linear and neo-Hookean (static), and the small-strain analytic "
            f"value. At full compression FEM neo-Hookean changes the volume by {fem_c:.2g}; "
            f"the spring model with volume springs by {ramp_end('compressed', 'volume on'):.2g}"
            f" ({ramp_end('compressed', 'volume on') / fem_c:.0f}× the material), with LMS "
            f"spec {ramp_end('compressed', 'LMS spec'):.2g}, LMS abs "
            f"{ramp_end('compressed', 'LMS abs'):.2g}, nnls calibration "
            f"{ramp_end('compressed', 'volume on (nnls)'):.2g}.",
        )
    )

    # ---- findings and headline
    ramp_c = {v: ramp_end("compressed", v) for v in VARIANTS}
    ramp_p = {v: ramp_end("pulled", v) for v in VARIANTS}
    fem_p = stat[(stat.model == "FEM P1 neo-hookean") & (stat.load == 1.0)]
    fem_p = abs(float(fem_p.dV.iloc[0])) if len(fem_p) else float("nan")
    dl_on = fin("compressed", "ramp", "volume on", "dL")
    dl_fem = stat[(stat.model == "FEM P1 neo-hookean") & (stat.load == -1.0)]
    dl_fem = float(dl_fem.dL.iloc[0]) if len(dl_fem) else float("nan")
    out.findings.append(
        f"Cube at ν = {nu}, uniaxial stress ±{CUBE_STRESS / CUBE_E:.0%}·E, at full load "
        f"(slow ramp): |ΔV|/V0 in compression = {ramp_c['volume off']:.3g} with volume "
        f"springs off, {ramp_c['volume on']:.3g} on, {ramp_c['LMS spec']:.3g} with LMS as "
        f"written (spec), {ramp_c['LMS abs']:.3g} with the sign-consistent LMS (abs), "
        f"{ramp_c['volume on (nnls)']:.3g} with volume springs on the nnls calibration; the "
        f"material (FEM P1 neo-Hookean) changes by {fem_c:.2g}. Volume springs cut the drift "
        f"{ramp_c['volume off'] / ramp_c['volume on']:.1f}× but leave it "
        f"{ramp_c['volume on'] / fem_c:.0f}× the material's."
    )
    out.findings.append(
        f"LMS as written (eq. 2.81) drives compressed elements to the lower clamp (median "
        f"k_s/k_s0 = {k_spec:.3g}) and ends at "
        f"{_compare(ramp_c['LMS spec'], ramp_c['volume on'])} of fixed volume springs in "
        f"compression ({ramp_c['LMS spec']:.3g} vs {ramp_c['volume on']:.3g}); the abs rule "
        f"stiffens them (median {k_abs:.3g}) and ends at "
        f"{_compare(ramp_c['LMS abs'], ramp_c['volume on'])} ({ramp_c['LMS abs']:.3g}). In "
        f"tension both rules stiffen and end at {ramp_p['LMS spec']:.3g} / "
        f"{ramp_p['LMS abs']:.3g} against {ramp_p['volume on']:.3g} without LMS. After the "
        f"sudden load (dynamic overshoot) the compressed cube ends at {comp['LMS spec']:.3g} "
        f"(spec), {comp['LMS abs']:.3g} (abs), {comp['volume on']:.3g} (no LMS)."
    )
    out.findings.append(
        f"Why a stiffer volume spring barely helps: it restores the radial sum Σ|ξ_j|, not "
        f"the volume. With volume springs on, the mean |ΔL|/L0 at full compression is "
        f"{dl_on:.2g} while |ΔV|/V0 is {ramp_c['volume on']:.2g}; the material itself "
        f"(FEM neo-Hookean) changes Σ|ξ_j| by {dl_fem:.2g} at |ΔV|/V0 = {fem_c:.2g}. The "
        f"volume spring fights a quantity the incompressible material does change, and "
        f"leaves free the modes that lose volume at constant Σ|ξ_j|. The calibration matters "
        f"more than LMS: nnls ends at {ramp_c['volume on (nnls)']:.3g} "
        f"({ramp_c['volume on'] / max(ramp_c['volume on (nnls)'], 1e-300):.1f}× less than the "
        "analytic calibration)."
    )
    out.findings.append(
        "FEM P1 linear is not a volume reference at 10 % strain: its small-strain field has "
        f"tr ε = {a_cube:.2g} but the deformed mesh changes volume by "
        + ", ".join(
            f"{abs(float(g.dV.iloc[0])):.2g} ({'compressed' if sg < 0 else 'pulled'})"
            for sg in (-1.0, 1.0)
            for g in [stat[(stat.model == "FEM P1 linear") & (stat.load == sg)]]
            if len(g)
        )
        + f" (second-order terms of det F); neo-Hookean gives {fem_c:.2g} / {fem_p:.2g}."
    )
    if s.sag:
        sag = {c["variant"]: r for c, lab, knd, r in dyn if lab == "sag"}
        ref = sag_ref.get("element_drift", np.nan) if sag_ref else np.nan

        def describe(v: str) -> str:
            r = sag[v]
            if r["status"] == "diverged":
                return (
                    f"{v} diverged (first inverted element at "
                    f"{1e3 * r['first_inverted']:.0f} ms, run stopped)"
                )
            tag = f", {r['final']['inverted']} inverted" if r["final"]["inverted"] else ""
            return f"{v} {r['final']['element_drift']:.3g}{tag}"

        out.findings.append(
            "Sagging block (ν = 0.45, large rotation), element drift Σ|ΔV_k|/V0 at the end of "
            "the run after the sudden gravity load: "
            + "; ".join(describe(v) for v in VARIANTS)
            + f"; FEM P1 neo-Hookean (static) {ref:.3g}."
        )
        for v in VARIANTS:  # diverged runs have no meaningful final drift: no headline
            if sag[v]["status"] in ("ok", "inverted"):
                out.headline[f"sag_element_drift_{_key(v)}"] = round(
                    sag[v]["final"]["element_drift"], 4
                )
        out.headline["sag_diverged_variants"] = float(
            sum(r["status"] == "diverged" for r in sag.values())
        )
    out.findings.append(
        "LMS adapts per time step, not per unit time (mu multiplies |ΔV/V0| once per step), "
        f"so its rate depends on dt; and raising k_s up to {K_MAX:g}× forces a "
        f"{np.sqrt(K_MAX):.2g}× smaller explicit step (used here for every variant)."
    )
    for v in VARIANTS:
        out.headline[f"cube_compressed_dV_{_key(v)}"] = round(comp[v], 5)
        out.headline[f"cube_pulled_dV_{_key(v)}"] = round(pull[v], 5)
    out.headline["cube_analytic_dV"] = round(a_cube, 5)
    out.headline["fem_neohookean_compressed_dV"] = round(fem_c, 5)
    for v in VARIANTS:
        out.headline[f"cube_ramp_compressed_dV_{_key(v)}"] = round(ramp_c[v], 5)
    return out


def _compare(x: float, ref: float) -> str:
    """``"1.15× the drift (more)"`` for the findings."""
    r = x / ref if ref else float("nan")
    if not np.isfinite(r):
        return "an incomparable drift"
    if abs(r - 1.0) < 0.02:
        return f"{r:.2f}× the drift (about the same)"
    return f"{r:.2f}× the drift ({'more' if r > 1 else 'less'})"


def _key(variant: str) -> str:
    return re.sub(r"[^a-z0-9]+", "_", variant.lower()).strip("_")


def _sag_caption(dyn: list) -> str:
    """The sag panel's sentence of the time-figure caption (empty without a sag run)."""
    sag = {c["variant"]: r for c, label, kind, r in dyn if label == "sag"}
    if not sag:
        return ""
    inverted = [v for v, r in sag.items() if r["status"] in ("inverted", "diverged")]
    diverged = [v for v, r in sag.items() if r["status"] == "diverged"]
    text = f" In the sagging block {len(inverted)} of {len(sag)} spring variants invert elements"
    if diverged:
        text += f" and {', '.join(diverged)} diverges (stopped when the element drift exceeds 1)"
    return text + "; the dashed line is the static neo-Hookean FEM drift."
