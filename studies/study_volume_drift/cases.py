"""Cases of the volume-drift study: the scenes, drift measures, one explicit or static run.

The cube scene is built as a table (:func:`cube_table`) and validated by
:func:`springfem.scene.scene_from_dict`; the sag scene is the bundled one with other
divisions.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from springfem.errors import SolverError
from springfem.scene import Scene, scene_from_dict
from springmodel.options import LMSOptions, SpringOptions

from ..compare import bundled_scene

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
    # the exact element of issue 10: the volume term on J = det[zeta] / det[zeta0]
    "axis-volume (exact)": {"volume": "axes", "torsion": "energy", "calibration": "exact"},
}
#: The seed model's variants (the headline counts stay over these).
SEED_VARIANTS = tuple(v for v in VARIANTS if "exact" not in v)
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
    "axis-volume (exact)": "tab:orange",
}


# ------------------------------------------------------------------------------ scenes


def cube_table(
    n: int = 3, nu: float = 0.49, stress: float = -CUBE_STRESS, law: str = "linear"
) -> dict[str, Any]:
    """The scene table of the block in uniaxial stress along z.

    The base slides (``u_z = 0``), the origin is pinned in x, y and the corner ``(L, 0, 0)``
    in y, so only rigid motion is removed.

    Parameters
    ----------
    n
        Divisions per side.
    nu
        Poisson's ratio.
    stress
        Traction on the top face (Pa, negative = compression).
    law
        Material law.

    Returns
    -------
    dict
        The table for :func:`springfem.scene.scene_from_dict`.

    Examples
    --------
    >>> cube_table(2)["mesh"]["divisions"]
    [2, 2, 2]
    """
    return {
        "name": "drift-cube",
        "mesh": {
            "generator": "box",
            "size": [CUBE_L] * 3,
            "divisions": [n] * 3,
            "split": "six",
        },
        "material": {"law": law, "E": CUBE_E, "nu": nu, "density": CUBE_RHO},
        "axes": {"fiber": [1.0, 0.0, 0.0], "sheet": [0.0, 1.0, 0.0]},
        "boundary": [
            {"region": "z_min", "fix": ["z"]},
            {"region": {"point": [0.0, 0.0, 0.0]}, "fix": ["x", "y"]},
            {"region": {"point": [CUBE_L, 0.0, 0.0]}, "fix": ["y"]},
        ],
        "load": [{"type": "traction", "region": "z_max", "value": [0.0, 0.0, stress]}],
        "spring": {"torsion": "energy"},
    }


def cube_scene(
    n: int = 3, nu: float = 0.49, stress: float = -CUBE_STRESS, law: str = "linear"
) -> Scene:
    """The block in uniaxial stress ``stress`` (Pa, negative = compression) along z.

    Parameters
    ----------
    n, nu, stress, law
        As for :func:`cube_table`.

    Returns
    -------
    Scene
        The validated scene.
    """
    return scene_from_dict(cube_table(n, nu, stress, law))


def sag_scene(divisions: tuple[int, int, int] = (16, 8, 4)) -> Scene:
    """The bundled ``sag`` scene on a ``divisions`` box mesh."""
    return scene_from_dict(bundled_scene("sag", divisions))


def case_scene(case: dict[str, Any], law: str = "linear") -> Scene:
    """The scene a case describes (``scene`` = ``cube``, ``sag`` or ``user``)."""
    if case["scene"] == "user":  # study volume-drift --scene FILE (see .scene)
        from ..user_scene import case_scene as user_scene

        return user_scene(case)
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


def first_period(scene: Scene, user: bool = False) -> float:
    """Time scale of the slowest motion that sets the run lengths and damping: for the cube
    the period of a quarter-wave rod of its height (from E and the density); for the sag
    scene a fixed 0.5 s (the block swings down and back in roughly that time, see the
    drift-against-time figure); for a user scene see :func:`.scene.user_period`."""
    if user:
        from .scene import user_period  # lazy: .scene imports this module

        return user_period(scene)
    c = np.sqrt(scene.material.E / scene.material.density)
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
    period = first_period(scene, user=case["scene"] == "user")
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
    scene, scene_path
        A user scene table and its file (``study volume-drift --scene``; see :mod:`.scene`).
    """

    n: int = 4
    sag: tuple[int, int, int] | None = (12, 6, 3)
    periods: float = 5.0
    ramp_periods: float = 6.0
    records: int = 120
    loads: tuple[float, ...] = (0.25, 0.5, 0.75, 1.0)
    scene: dict | None = None
    scene_path: str | None = None

    @classmethod
    def full(cls) -> Settings:
        """4³ cube and the sag scene."""
        return cls()

    @classmethod
    def for_scene(cls, table: dict, path: str | None = None, quick: bool = False) -> Settings:
        """Statics and sudden-load explicit runs on a user scene (see :mod:`.scene`).

        Parameters
        ----------
        table, path
            The scene table and its file.
        quick
            Shorter runs (3 periods instead of 5), fewer samples.

        Returns
        -------
        Settings
        """
        short = {"periods": 3.0, "records": 30} if quick else {}
        return cls(**short, scene=table, scene_path=path)

    @classmethod
    def quick(cls) -> Settings:
        """2³ cube, no sag, shorter runs."""
        return cls(n=2, sag=None, periods=4.0, ramp_periods=5.0, records=60, loads=(0.5, 1.0))


def variant_key(variant: str) -> str:
    """``"volume on (nnls)"`` -> ``"volume_on_nnls"`` (headline keys)."""
    return re.sub(r"[^a-z0-9]+", "_", variant.lower()).strip("_")
