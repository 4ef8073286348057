"""Study ``dynamics``: the spring elements and the fast peers against explicit P1 FEM of the
same law, in undamped dynamics of an anisotropic tissue scene and of its isotropic twin.

Every model starts from its own static equilibrium under the scene's loads and is released
(loads off): undamped symplectic Euler at half its own critical step (:mod:`.work`). The
models are the tissue spring element (``spring-tissue``: the law's own energy per
element), the stiffened exact element (``spring-stiffened``: one exponent per element) and
the exact small-strain element (``spring-exact``), against explicit P1 of the scene's law
on the same mesh (:class:`reference_fem.explicit.ExplicitFem`), and the plug-in models
that apply: those with an explicit form (co-rotational P1, the mass-spring network) the
same way, those with their own time integration (XPBD) by their ``release_run``
(:class:`springfem.model_api.ModelPlugin`); a plug-in that does not apply has a row saying
why. Reported: the probe error over time (relative L2 over the run, max: ``sqrt(sum |u -
u_ref|^2 / sum |u_ref|^2)``, ``max |u - u_ref| / max |u_ref|``), each model's energy
balance (``max |E(t) - E(0)| / E(0)`` of kinetic + strain − work), its stable step, and the
median cost of one step of every model, interleaved in one process after a warm-up.

Bundled: Land's beam (Land et al. 2015, problem 1: Guccione, fibres along the beam) made
compressible for explicit dynamics (``kappa = 50 C``, 1000 kg/m³ in mm-kPa units, Land's
0.004 kPa as a dead traction on the bottom face), and the same beam in compressible
neo-Hookean (``land-beam-nh``: ``E = C b_f``, ``nu = 0.45``), where the isotropic peers
apply; the run length is in Rayleigh periods of the reference's static deflection.
``--scene FILE`` runs it on a user's compressible scene with a load (its first
``[[probe]]``, else the node farthest from the fixed nodes).

Examples
--------
>>> [s.label for s in bundled_scenes(Settings.quick())]
['land-beam', 'land-beam-nh']
>>> t = [0.0, 1.0, 2.0]
>>> ref = {"status": "ok", "t": t, "u": [[0, 0, 1.0], [0, 0, -1.0], [0, 0, 1.0]]}
>>> m = {"status": "ok", "t": t, "u": [[0, 0, 1.0], [0, 0, -0.9], [0, 0, 1.0]]}
>>> l2, mx = probe_errors(m, ref)
>>> round(l2, 4), round(mx, 4), round(energy_drift({"energy": [2.0, 2.1, 1.98]}), 12)
(0.0577, 0.1, 0.05)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from springfem.errors import InputError
from springfem.scene import Scene

from .. import models
from ..registry import Figure, StudyContext, StudyOutput, study
from ..scenes import StudyScene, require
from ..tables import pyplot
from .work import WORK, own_integrator

__all__ = ["Settings", "bundled_scenes", "run"]

STUDY, VERSION = "dynamics", 2

#: The spring elements compared with explicit P1 of the same law: the tissue element (the
#: law's own energy per element), the stiffened exact element (one exponent per element)
#: and the exact small-strain element (linear springs, P1's small-strain tangent).
SPRINGS = ("spring-tissue", "spring-stiffened", "spring-exact")
#: Line colours of the models (the reference is black).
COLORS = {"spring-tissue": "tab:orange", "spring-stiffened": "tab:blue",
          "spring-exact": "tab:green", "spring-spec": "tab:purple",
          "corotational": "goldenrod", "xpbd": "tab:red", "mass-spring": "tab:brown"}  # fmt: skip
#: The isotropic beam: neo-Hookean, ``E`` = Guccione's small-strain fibre modulus ``C b_f``.
NH_NU = 0.45
#: Land's beam, made compressible: ``kappa`` = this × ``C`` (as the explicit kernels' test).
KAPPA_PER_C = 50.0
#: Density of the bundled beam: 1000 kg/m³ in the scene's mm-kPa units (kg/mm³; forces in
#: mN = kg mm/s², so time is in seconds).
BEAM_DENSITY = 1.0e-6
#: Land's load (0.004 kPa on the bottom face), here a dead traction.
BEAM_TRACTION = 0.004


@dataclass(frozen=True)
class Settings:
    """Mesh, load, run length and timing of the dynamics study: the bundled ``beam``'s
    divisions, the ``load`` factor on Land's 0.004 kPa, the run length in Rayleigh
    ``periods`` of the reference's static deflection, the ``samples`` of the common time
    grid, every model's step as ``safety`` × its own critical step (the smaller at rest and
    loaded), the spring ``models``, and ``rounds`` interleaved rounds of ``steps`` steps per
    model for the cost per step."""

    beam: tuple[int, int, int] = (30, 3, 3)
    load: float = 1.0
    periods: float = 1.5
    samples: int = 400
    safety: float = 0.5
    models: tuple[str, ...] = SPRINGS
    rounds: int = 5
    steps: int = 200

    @classmethod
    def full(cls) -> Settings:
        """Land's 30×3×3 beam (1,620 tets), 1.5 periods."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """A 10×2×2 beam, one period, fewer timed steps."""
        return cls(beam=(10, 2, 2), periods=1.0, samples=200, rounds=3, steps=100)


def beam_table(divisions: tuple[int, int, int], load: float = 1.0) -> StudyScene:
    """Land's beam made compressible for explicit dynamics: ``kappa = 50 C``, density
    1000 kg/m³, P1 in the displacement formulation, the 0.004 kPa pressure as a dead
    traction (× ``load``) on the bottom face.

    Examples
    --------
    >>> sc = beam_table((10, 1, 1))
    >>> m = sc.build().material
    >>> m.incompressible, m.parameters["kappa"], m.density
    (False, 100.0, 1e-06)
    >>> sc.table["load"][0]["value"]
    [0.0, 0.0, 0.004]
    """
    C = float(StudyScene.bundled("land-beam").table["material"]["C"])
    sets = {
        "material.incompressible": False,
        "material.kappa": KAPPA_PER_C * C,
        "material.density": BEAM_DENSITY,
        "mesh.divisions": list(divisions),
        "fem.order": 1,
        "fem.formulation": "displacement",
    }
    sc = StudyScene.bundled("land-beam", sets, label="land-beam")
    table = dict(sc.table)
    value = [0.0, 0.0, BEAM_TRACTION * load]
    table["load"] = [{"type": "traction", "region": "z_min", "value": value}]
    return StudyScene(sc.label, table, roles=("release",))


def isotropic_beam(divisions: tuple[int, int, int], load: float = 1.0) -> StudyScene:
    """Land's beam of :func:`beam_table`, isotropic: compressible neo-Hookean with ``E`` the
    Guccione law's small-strain fibre modulus ``C b_f`` and ``nu`` = :data:`NH_NU`, so that
    the models of isotropic laws (co-rotational P1, XPBD, the mass-spring network) apply.

    Examples
    --------
    >>> m = isotropic_beam((4, 1, 1)).build().material
    >>> m.law, round(m.E, 6), m.nu
    ('neo-hookean', 16.0, 0.45)
    """
    sc = beam_table(divisions, load)
    g = sc.table["material"]
    table = dict(sc.table)
    table["material"] = {"law": "neo-hookean", "E": float(g["C"]) * float(g["b_f"]),
                         "nu": NH_NU, "density": g["density"]}  # fmt: skip
    table.pop("axes", None)
    return StudyScene("land-beam-nh", table, roles=("release",))


def bundled_scenes(s: Settings) -> list[StudyScene]:
    """The compressible Guccione beam (Land's problem 1 made compressible) and its isotropic
    neo-Hookean twin (:func:`isotropic_beam`).

    Examples
    --------
    >>> [x.label for x in bundled_scenes(Settings.quick())]
    ['land-beam', 'land-beam-nh']
    """
    return [beam_table(s.beam, s.load), isotropic_beam(s.beam, s.load)]


def reference_model(scene: Scene) -> str:
    """The explicit P1 of the scene's law: ``P1`` (its own law, or small-strain linear),
    ``P1-NH`` for a neo-Hookean material.

    Examples
    --------
    >>> reference_model(beam_table((4, 1, 1)).build())
    'P1'
    """
    return "P1-NH" if scene.material.law == "neo-hookean" else "P1"


def check_scene(sc: StudyScene) -> Scene:
    """The built scene, or a one-line refusal: an incompressible material (explicit P1 has
    no pressure unknown), no load to release from."""
    scene = sc.build()
    if scene.material.incompressible:
        raise InputError(
            f"study dynamics: scene {sc.label} is incompressible; explicit P1 needs a "
            "volumetric penalty: give [material] kappa instead of incompressible = true"
        )
    if not scene.loads:
        raise InputError(f"study dynamics: scene {sc.label} has no [[load]] to release from")
    return scene


def spring_models(scene: Scene, s: Settings) -> list[str]:
    """The settings' spring models that apply to the scene (the tissue element needs a tissue
    law, the stiffened one a modulus to stiffen by), then the plug-in models with an
    explicit form on it (:func:`studies.models.plugins`:
    ``corotational`` on a linear or neo-Hookean scene)."""
    own = [m for m in s.models if models.get(m).applies(scene) is None and _builds(m, scene)]
    return own + [m for m in models.plugins(scene, explicit=True) if m not in own]


def _builds(model: str, scene: Scene) -> bool:
    """Whether the model's mechanical system builds on the scene (the stiffened element
    needs a stiffening modulus a neo-Hookean law does not give)."""
    try:
        models.get(model).system(scene)
    except InputError:
        return False
    return True


def own_dynamics(scene: Scene) -> list[str]:
    """The plug-in models weighed by default that apply to the scene and bring their own
    time integration (:func:`own_integrator`)."""
    return [m for m in models.plugins(scene) if own_integrator(m) is not None]


def not_applicable(scene: Scene) -> list[str]:
    """The plug-in models weighed by default that do not apply to the scene (a row each in
    the table, with the model's reason)."""
    return [m for m in models.plugins() if models.get(m).applies(scene) is not None]


def period_case(sc: StudyScene) -> dict[str, Any]:
    """The reference's static solve (for the run length)."""
    scene = check_scene(sc)
    return sc.case(STUDY, VERSION, kind="period", model=reference_model(scene))


def release_cases(sc: StudyScene, s: Settings, t_end: float) -> list[dict[str, Any]]:
    """The reference, every spring model and XPBD, released from its static state for
    ``t_end`` seconds, and a case for each plug-in model that does not apply (its row says
    why)."""
    scene = sc.build()
    names = [reference_model(scene), *spring_models(scene, s), *own_dynamics(scene),
             *not_applicable(scene)]  # fmt: skip
    run = {"t_end": t_end, "samples": s.samples, "safety": s.safety}
    return [sc.case(STUDY, VERSION, kind="release", model=m, **run) for m in names]


def cost_case(sc: StudyScene, s: Settings) -> dict[str, Any]:
    """Every model's cost per step (XPBD: per substep), interleaved in one process."""
    scene = sc.build()
    names = [reference_model(scene), *spring_models(scene, s), *own_dynamics(scene)]
    return sc.case(STUDY, VERSION, kind="cost", models=names, rounds=s.rounds, steps=s.steps,
                   safety=s.safety)  # fmt: skip


def probe_errors(run: dict[str, Any], ref: dict[str, Any]) -> tuple[float, float]:
    """Relative L2 and max probe error of ``run`` against ``ref`` over the common grid
    (``nan`` when either did not finish)."""
    if run.get("status") != "ok" or ref.get("status") != "ok":
        return float("nan"), float("nan")
    u, r = np.asarray(run["u"]), np.asarray(ref["u"])
    d = np.linalg.norm(u - r, axis=1)
    n = np.linalg.norm(r, axis=1)
    return float(np.sqrt(np.sum(d**2) / np.sum(n**2))), float(d.max() / n.max())


def energy_drift(run: dict[str, Any]) -> float:
    """``max |E(t) - E(0)| / E(0)`` of the recorded balance (``nan`` without one)."""
    E = np.asarray(run.get("energy", []), dtype=float)
    if E.size < 2 or not np.all(np.isfinite(E)) or E[0] == 0:
        return float("nan")
    return float(np.abs(E - E[0]).max() / abs(E[0]))


def energy_change(run: dict[str, Any]) -> float:
    """``(E(end) - E(0)) / E(0)`` of the recorded balance (``nan`` without one): its sign
    tells dissipation from gain."""
    E = np.asarray(run.get("energy", []), dtype=float)
    if E.size < 2 or not np.all(np.isfinite(E)) or E[0] == 0:
        return float("nan")
    return float((E[-1] - E[0]) / abs(E[0]))


def dominant(u: list[float]) -> int:
    """The component of the largest static probe displacement."""
    return int(np.argmax(np.abs(np.asarray(u))))


def result_frame(
    runs: list[tuple[dict, dict]], costs: dict[str, dict[str, float]], refs: dict[str, str]
) -> pd.DataFrame:
    """One row per (scene, model) of ``runs`` (``(case, result)`` of every release run):
    status, static probe error, errors over time, energy drift, critical and used steps,
    cost per step (``costs``: scene -> model -> median seconds) and per simulated second."""
    by = {(c["scene"], c["model"]): r for c, r in runs}
    rows = []
    for c, r in runs:
        scene, m = c["scene"], c["model"]
        ref = by.get((scene, refs[scene]), {})
        l2, mx = probe_errors(r, ref)
        step = costs.get(scene, {}).get(m, np.nan)
        u0, r0 = np.asarray(r.get("u", [[np.nan] * 3])[0]), np.asarray(ref.get("u", [[0] * 3])[0])
        rows.append(
            {
                "scene": scene,
                "model": m,
                "status": r["status"],
                "static error": float(np.linalg.norm(u0 - r0) / np.linalg.norm(r0)),
                "L2 error (run)": l2,
                "max error": mx,
                "energy drift": energy_drift(r),
                "energy change (end)": energy_change(r),
                "dt_crit rest (s)": r.get("dt_crit_rest", np.nan),
                "dt_crit loaded (s)": r.get("dt_crit_loaded", np.nan),
                "dt (s)": r.get("dt", np.nan),
                "steps": r.get("steps", np.nan),
                "step (µs)": step * 1e6,
                "cost / P1 step": step / costs.get(scene, {}).get(refs[scene], np.nan),
                "cost per simulated ms (s)": step / r.get("dt", np.nan) * 1e-3,
                "message": r.get("message", ""),
            }
        )
    return pd.DataFrame(rows)


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


@study("dynamics", Settings, bundled_scenes)
def run(ctx: StudyContext, scenes: list[StudyScene], s: Settings) -> StudyOutput:
    """Release runs of each model against explicit P1 of the same law.

    Headline per scene and spring model: ``<scene>_<model>_{l2_error, max_error,
    energy_drift, cost_ratio}`` (3 significant digits), and the reference's
    ``<scene>_<ref>_energy_drift`` and ``<scene>_<ref>_step_us``.
    """
    require(scenes, ctx.name)
    periods = ctx.cache.run([period_case(sc) for sc in scenes], WORK["period"][0], ctx.progress,
                            WORK["period"][1])  # fmt: skip
    t_end = {sc.label: s.periods * p["period"] for sc, p in zip(scenes, periods, strict=True)}
    cases = [c for sc in scenes for c in release_cases(sc, s, t_end[sc.label])]
    runs = list(zip(cases, ctx.cache.run(cases, WORK["release"][0], ctx.progress,
                                         WORK["release"][1]), strict=True))  # fmt: skip
    cost = ctx.cache.run([cost_case(sc, s) for sc in scenes], WORK["cost"][0], ctx.progress,
                         WORK["cost"][1])  # fmt: skip
    costs = {sc.label: c["step_seconds"] for sc, c in zip(scenes, cost, strict=True)}
    refs = {sc.label: reference_model(sc.build()) for sc in scenes}
    df = result_frame(runs, costs, refs)

    def pct(x: float) -> str:
        return "n/a" if not np.isfinite(x) else f"{x:.2g}" if x < 1e-4 else f"{100 * x:.2g}%"

    findings: list[str] = []
    head: dict[str, float] = {}
    for scene, g in df.groupby("scene", sort=False):
        ref = refs[scene]
        r0 = g[g.model == ref].iloc[0]
        parts = []
        for _, r in g[g.model != ref].iterrows():
            if r.status != "ok":
                parts.append(f"{r.model}: {r.status} ({r.message})")
                continue
            parts.append(
                f"{r.model}: probe L2 error {pct(r['L2 error (run)'])} over the run (max "
                f"{pct(r['max error'])}, static {pct(r['static error'])})"
            )
            for key, col in HEADLINE.items():
                v = float(r[col])
                head[f"{scene}_{r.model}_{key}"] = float(f"{v:.3g}") if np.isfinite(v) else v
        findings.append(
            f"{scene}{' (quick preset)' if ctx.quick else ''}: released from the static state "
            f"and run {t_end[scene] * 1e3:.3g} ms against explicit {ref} of the same law on "
            "the same mesh, " + "; ".join(parts) + "."
        )
        ok = g[g.status == "ok"]
        drift = ", ".join(f"{r.model} {r['energy drift']:.2g}" for _, r in ok.iterrows())
        findings.append(
            f"{scene}: undamped, every model keeps its own energy balance (kinetic + strain − "
            f"work) within a relative {ok['energy drift'].max():.2g} of its initial energy "
            f"({drift}): the symplectic step's O((ω dt)²) oscillation, no drift."
            if np.all(ok["energy drift"] < 1e-3)
            else f"{scene}: energy drift relative to the initial energy: {drift}."
        )
        for _, r in ok.iterrows():  # a plug-in with its own (undamped) time integration
            if (own := own_integrator(r.model)) is not None:
                conf = float(getattr(own, "setting_step", np.nan))
                over = conf / min(r["dt_crit rest (s)"], r["dt_crit loaded (s)"])
                findings.append(
                    f"{r.scene}: {r.model} runs its own undamped steps at h = {r['dt (s)']:.3g} "
                    f"s (the explicit models' rule; its configured step {conf:.3g} s is "
                    f"{over:.3g}× the 2/ω_max of its energy here; the stability study measures "
                    "how far past that bound it survives) and its energy changes by "
                    f"{r['energy change (end)']:.2g} of the initial energy over the run: the "
                    "position projection dissipates, where the symplectic explicit steps only "
                    "oscillate."
                )
        for _, r in ok[ok.model == "mass-spring"].iterrows():
            findings.append(
                f"{r.scene}: the mass-spring network's probe error ({pct(r['static error'])} "
                "static) is its material's, not its time integration's: an edge network obeys "
                "the Cauchy relations (its ν is not the scene's: 1/4 if isotropic, 5/31 along "
                "an axis on the six-tet box lattice), so no spring stiffness fits the scene's "
                "material (docs/peers.rst)."
            )
        others = ", ".join(f"{r.model} {r['step (µs)']:.3g} µs ({r['cost / P1 step']:.2f}× P1) "
                         f"at dt {r['dt (s)']:.3g} s" for _, r in ok.iterrows()
                         if r.model != ref)  # fmt: skip
        spread = float(np.ptp(ok["dt (s)"]) / ok["dt (s)"].max())
        above = float(ok["dt (s)"].max() / ok["dt (s)"].min() - 1.0)
        findings.append(
            f"{scene}: one step of explicit {ref} costs {r0['step (µs)']:.3g} µs at dt "
            f"{r0['dt (s)']:.3g} s; {others} (median over the steps, interleaved in one process, "
            "warm; XPBD: one substep)."
            + (f" The stable steps agree within {spread:.2g} (relative): the spring elements' "
               "small-strain tangent is P1's, so none buys a larger step." if spread < 0.01
               else f" The largest stable step is {ok.loc[ok['dt (s)'].idxmax()].model}'s, "
               f"{above:.1%} above the smallest.")
        )  # fmt: skip
        head[f"{scene}_{ref}_energy_drift"] = float(f"{r0['energy drift']:.3g}")
        head[f"{scene}_{ref}_step_us"] = float(f"{r0['step (µs)']:.3g}")

    caption = (
        "Each model released from its own static state under the scene's loads (undamped "
        "symplectic Euler, "
        + ", ".join(f"{x}: {t * 1e3:.3g} ms" for x, t in t_end.items())
        + "), probe displacement against explicit P1 of the same law on the same mesh: static "
        "error, relative L2 error over the run and max error; energy drift max |E(t) - E(0)| "
        "/ E(0) of kinetic + strain - work and its change at the end; critical step 2/ω_max "
        "at rest and loaded, the step used; median wall time of one step (interleaved, one "
        "process, warm) and its ratio to P1's. XPBD integrates by its own undamped substeps "
        "(the step is its substep, at most the safety times 2/ω_max of its own energy; the "
        "static state its run to rest); a plug-in model that does not apply to the scene has "
        "a row saying why (not applicable), no numbers."
    )
    return StudyOutput(
        name=ctx.name,
        title="Dynamics: spring elements against explicit P1 of the same law "
        f"({', '.join(sc.label for sc in scenes)})",
        findings=findings,
        tables=[ctx.table(df, "dynamics", caption)],
        figures=[probe_figure(ctx, runs, refs), energy_figure(ctx, runs, refs)],
        headline=head,
    )


#: Headline key -> table column, per spring model.
HEADLINE = {"l2_error": "L2 error (run)", "max_error": "max error",
            "energy_drift": "energy drift", "cost_ratio": "cost / P1 step"}  # fmt: skip
