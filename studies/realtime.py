"""Models at a frame rate: which settings fit a frame budget, and how far their motion is
from the dynamic reference's.

For one model on one scene at ``rate`` frames per second, :func:`fit_settings` tries the
model's frame settings cheapest first (:func:`springfem.frames.frames_settings`), times a few
frames of each, and keeps those whose cost per frame fits ``1 / rate``; :func:`frame_run`
runs the scene's load history (its time functions, docs/scenes.rst) frame by frame and
records the probes, the vertex field and the energy; :func:`trajectory_error` compares a run
with the reference's motion at the same times. :func:`weigh` does all three for a model:
the most accurate setting that fits, or the cheapest one as the nearest miss.

The error is the root mean square over the frames of the probe displacement error, relative
to the largest probe displacement of the reference (``probe``), and the same over all
vertices (``field``, relative to the reference field's largest norm). The energy error is
the change over the run of kinetic plus stored energy minus the work of the loads, less
the reference's change of the same, relative to the reference's largest kinetic plus
stored energy: for an undamped scene the reference conserves it, so it is the model's
drift; with damping it is also the difference in what each dissipates.

Examples
--------
>>> import numpy as np
>>> ref = Motion(np.array([0.0, 1.0]), np.array([[[0.0, 0, 0]], [[1.0, 0, 0]]]), None)
>>> run = Motion(np.array([0.0, 1.0]), np.array([[[0.0, 0, 0]], [[0.9, 0, 0]]]), None)
>>> round(trajectory_error(run, ref)["probe"], 4)
0.0707
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from springfem.errors import InputError, SolverError
from springfem.frames import FrameStepper, frame_stepper, frames_settings
from springfem.mechanics.limits import Deadline, SolveStopped, solve_limits
from springfem.scene import Scene

#: Frames timed per setting when searching for the settings that fit (after one warm frame).
TIMED_FRAMES = 3


@dataclass
class Motion:
    """A motion sampled at frame times.

    Attributes
    ----------
    times
        ``(k,)`` seconds.
    probes
        ``(k, p, 3)`` probe displacements.
    field
        ``(k, n, 3)`` vertex displacements, or ``None``.
    energy
        ``(k,)`` kinetic plus stored energy minus the work of the loads, or ``None``.
    scale
        The largest kinetic plus stored energy (the energy error's unit).
    """

    times: np.ndarray
    probes: np.ndarray
    field: np.ndarray | None
    energy: np.ndarray | None = None
    scale: float = float("nan")


@dataclass
class FrameResult:
    """One model at one setting over the scene's run.

    Attributes
    ----------
    model, settings
        The model's name and the settings it ran at.
    seconds_per_frame
        Median wall time of a frame (s).
    stable
        Whether the run stayed finite and bounded.
    motion
        What it recorded (``None`` when it did not run).
    message
        Why it stopped, when it did.
    """

    model: str
    settings: dict[str, Any]
    seconds_per_frame: float
    stable: bool
    motion: Motion | None = None
    message: str = ""
    errors: dict[str, float] = field(default_factory=dict)


def probe_nodes(scene: Scene) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """``(nodes (p, k), weights (p, k), names)`` of the scene's probes (linear in their
    tets), else of the vertex farthest from the supports."""
    if scene.probes:
        nodes = np.array([scene.mesh.tets[p.tet] for p in scene.probes])
        w = np.array([np.asarray(p.bary, dtype=float) for p in scene.probes])
        return nodes, w, [p.name for p in scene.probes]
    X = scene.mesh.points
    fixed = np.unique(np.asarray(scene.dirichlet()[0]) // 3)
    centre = X[fixed].mean(axis=0) if fixed.size else X.mean(axis=0)
    node = int(np.argmax(np.linalg.norm(X - centre, axis=1)))
    return np.array([[node]]), np.array([[1.0]]), [f"node {node}"]


def keep_every(n: int, field_frames: int = 50) -> int:
    """Keep the field every this many of ``n`` frames: the smallest divisor of ``n`` that
    keeps at most about ``field_frames`` (so the kept times are evenly spaced to the end).

    >>> keep_every(600), keep_every(37)
    (12, 1)
    """
    for d in range(max(1, n // field_frames), n + 1):
        if n % d == 0:
            return d
    return n


def _probe(u: np.ndarray, nodes: np.ndarray, w: np.ndarray) -> np.ndarray:
    return np.einsum("pk,pkj->pj", w, u[nodes])


def frame_run(
    stepper: FrameStepper,
    scene: Scene,
    t_end: float,
    scale: Callable[[float], float],
    *,
    model: str = "",
    field_frames: int = 50,
    deadline: float | None = None,
) -> FrameResult:
    """Run ``stepper`` from rest over ``[0, t_end]`` and record its motion.

    Parameters
    ----------
    stepper
        The model's frames.
    scene
        The scene (its probes).
    t_end
        End time (s).
    scale
        The load factor as a function of time.
    model
        Its name, for the result.
    field_frames
        The vertex field is kept at about this many frames.
    deadline
        ``time.monotonic()`` past which the run stops (``None``: none).

    Returns
    -------
    FrameResult
    """
    dt = stepper.frame_dt
    n = max(1, int(round(t_end / dt)))
    nodes, w, _ = probe_nodes(scene)
    x, v = stepper.start()
    X = stepper.x0
    keep = keep_every(n, field_frames)
    times, probes, fields, energy, walls = [0.0], [_probe(x - X, nodes, w)], [x - X], [], []
    e0 = stepper.strain_energy(x)
    has_e = e0 is not None
    force = getattr(scale, "force", None)
    f_prev = force(x, 0.0) if force is not None else None
    work, peak = 0.0, 0.0
    if e0 is not None:
        energy.append(_kinetic(stepper.masses, v) + e0)
    ftimes = [0.0]
    u_prev = x - X
    extent = float(np.ptp(X, axis=0).max())
    stable, message = True, ""
    for k in range(n):
        t0 = time.perf_counter()
        try:
            stepper.frame(x, v, k * dt, scale)
        except (SolverError, SolveStopped, FloatingPointError) as exc:
            stable, message = False, f"frame {k + 1}: {exc}"[:200]
            break
        walls.append(time.perf_counter() - t0)
        u = x - X
        if not np.isfinite(u).all() or float(np.abs(u).max()) > 10 * extent:
            stable, message = False, f"frame {k + 1}: the motion blew up (t = {(k + 1) * dt:.4g} s)"
            break
        times.append((k + 1) * dt)
        probes.append(_probe(u, nodes, w))
        if has_e:
            if force is not None:
                f = force(x, (k + 1) * dt)
                work += 0.5 * float(np.sum((f + f_prev) * (u - u_prev)))
                f_prev = f
            stored = _kinetic(stepper.masses, v) + float(stepper.strain_energy(x) or 0.0)
            peak = max(peak, stored)
            energy.append(stored - work)
        u_prev = u.copy()
        if (k + 1) % keep == 0:
            fields.append(u.copy())
            ftimes.append((k + 1) * dt)
        if deadline is not None and time.monotonic() > deadline:
            stable, message = True, f"stopped at t = {(k + 1) * dt:.4g} s (time cap)"
            break
    spf = float(np.median(walls[1:] if len(walls) > 1 else walls)) if walls else float("nan")
    motion = Motion(
        np.asarray(times),
        np.asarray(probes),
        np.asarray(fields) if len(fields) == len(ftimes) else None,
        np.asarray(energy) if has_e else None,
        peak,
    )
    motion.field_times = np.asarray(ftimes)  # type: ignore[attr-defined]
    return FrameResult(model, dict(stepper.settings), spf, stable, motion, message)


def _kinetic(m: np.ndarray, v: np.ndarray) -> float:
    return 0.5 * float(np.einsum("i,ij,ij->", m, v, v))


def trajectory_error(run: Motion, ref: Motion) -> dict[str, float]:
    """Relative RMS errors of ``run`` against ``ref`` at ``run``'s frame times (the reference
    interpolated linearly in time): ``probe`` and, when both have fields at the same times,
    ``field`` (see the module docstring)."""
    t = run.times
    ref_p = np.stack(
        [np.stack([np.interp(t, ref.times, ref.probes[:, p, j]) for j in range(3)], axis=-1)
         for p in range(ref.probes.shape[1])], axis=1)  # fmt: skip
    scale = float(np.linalg.norm(ref.probes, axis=-1).max()) or 1.0
    err = np.linalg.norm(run.probes - ref_p, axis=-1)
    out = {"probe": float(np.sqrt(np.mean(err**2))) / scale}
    if run.field is not None and ref.field is not None:
        rt = getattr(run, "field_times", None)
        ft = getattr(ref, "field_times", ref.times)
        if rt is not None:
            idx = [int(np.argmin(np.abs(ft - s))) for s in rt]
            close = np.abs(ft[idx] - rt) < 1e-9 + 1e-6 * max(float(rt[-1]), 1.0)
            if close.all():
                R = ref.field[idx]
                fscale = float(np.linalg.norm(R, axis=-1).max()) or 1.0
                d = np.linalg.norm(run.field - R, axis=-1)
                out["field"] = float(np.sqrt(np.mean(d**2))) / fscale
    return out


def energy_error(run: Motion, ref: Motion) -> float:
    """The energy error of ``run`` against ``ref`` (module docstring; NaN when either has no
    energy)."""
    if run.energy is None or ref.energy is None or len(run.energy) < 2:
        return float("nan")
    t = float(run.times[-1])
    d_ref = float(np.interp(t, ref.times, ref.energy) - ref.energy[0])
    d_run = float(run.energy[-1] - run.energy[0])
    unit = ref.scale if np.isfinite(ref.scale) and ref.scale > 0 else 1.0
    return (d_run - d_ref) / unit


def time_frames(
    model: Any,
    scene: Scene,
    frame_dt: float,
    settings: dict[str, Any],
    scale: Callable[[float], float],
    frames: int = TIMED_FRAMES,
) -> tuple[float, FrameStepper | None, str]:
    """Median seconds per frame of ``model`` at ``settings`` over ``frames`` frames after a
    warm one (its kernels compiled); the stepper, or why it has none."""
    try:
        stepper = frame_stepper(model, scene, frame_dt, **settings)
    except (InputError, SolverError, TypeError, ValueError) as exc:
        return float("nan"), None, str(exc)[:200]
    if stepper is None:
        return float("nan"), None, "no dynamics (neither frames nor an explicit form)"
    x, v = stepper.start()
    walls = []
    for k in range(frames + 1):
        t0 = time.perf_counter()
        stepper.frame(x, v, k * frame_dt, scale)
        walls.append(time.perf_counter() - t0)
    return float(np.median(walls[1:])), stepper, ""


def weigh(
    model: Any,
    scene: Scene,
    *,
    rate: float,
    t_end: float,
    scale: Callable[[float], float],
    reference: Motion | None,
    max_runs: int = 3,
    deadline: float | None = None,
) -> FrameResult:
    """The most accurate setting of ``model`` whose frame fits ``1 / rate``, run over the
    scene's history and compared with ``reference``; when none fits, the cheapest setting's
    timing alone (``stable`` then says nothing; ``message`` says it missed)."""
    frame_dt = 1.0 / rate
    timed = []
    for s in frames_settings(model):  # cheapest frame first: stop at the first miss
        spf, stepper, why = time_frames(model, scene, frame_dt, s, scale)
        if stepper is None:
            return FrameResult(model.name, {}, float("nan"), False, message=why)
        timed.append((spf, s, stepper))
        if spf > frame_dt:
            break
    fit = sorted((t for t in timed if t[0] <= frame_dt), key=lambda t: -t[0])[:max_runs]
    if not fit:
        spf, s, stepper = min(timed, key=lambda t: t[0])
        miss = f"misses the frame: {spf * 1e3:.3g} ms > {frame_dt * 1e3:.3g} ms"
        return FrameResult(model.name, dict(stepper.settings), spf, True, message=miss)
    runs = []
    for _, s, _ in fit:
        stepper = frame_stepper(model, scene, frame_dt, **s)
        assert stepper is not None
        r = frame_run(stepper, scene, t_end, scale, model=model.name, deadline=deadline)
        if r.motion is not None and r.stable and reference is not None:
            r.errors = trajectory_error(r.motion, reference)
            r.errors["energy"] = energy_error(r.motion, reference)
        runs.append(r)
    # the runs' own medians (more frames than the search timed) decide what fits
    fitting = [r for r in runs if r.seconds_per_frame <= frame_dt] or runs
    best = fitting[0]
    for r in fitting[1:]:
        if _better(r, best):
            best = r
    return best


def _better(a: FrameResult, b: FrameResult) -> bool:
    if a.stable != b.stable:
        return a.stable
    return a.errors.get("probe", np.inf) < b.errors.get("probe", np.inf)


#: The dynamic reference's time step at most, as a fraction of the run (its error is
#: second order in the step; jumps of the loads are on its grid).
REFERENCE_STEPS = 100
#: A dynamic step's time against a static solve's (a static solve load-steps and starts far
#: from the answer; a time step starts from the predictor a step away): measured 0.2-0.6 on
#: the bundled pull-release (1.5k tets) and organs of 1k and 5k tets.
STEP_OF_STATIC = 0.5
#: Seconds a reference step takes at least (assembly and solve overheads of a small mesh).
STEP_FLOOR = 0.05


def reference_settings(scene: Scene, t_end: float, frame_dt: float) -> dict[str, Any]:
    """The dynamic reference of ``scene``: P2, mixed P2/P1 for a nearly incompressible
    material (ν >= 0.45, as the static verdict's reference); its step is the scene's
    ``[dynamics] dt``, else ``t_end / REFERENCE_STEPS``, made to fit the frames: a whole
    fraction of a frame, or a whole number of frames that divides the field's spacing
    (:func:`keep_every`), so the kept fields fall on its time grid."""
    nu = float(getattr(scene.material, "nu", 0.3) or 0.3)
    mixed = nu >= 0.45 or bool(getattr(scene.material, "incompressible", False))
    given = (scene.raw.get("dynamics") or {}).get("dt")
    target = float(given) if given else t_end / REFERENCE_STEPS
    if target <= frame_dt:
        dt = frame_dt / int(np.ceil(frame_dt / target - 1e-9))
    else:
        keep = keep_every(max(1, int(round(t_end / frame_dt))))
        m = max(d for d in range(1, keep + 1) if keep % d == 0 and d * frame_dt <= target * 1.0001)
        dt = m * frame_dt
    # a release excites mesh modes no step resolves: unless the scene names its integrator,
    # generalised-alpha (its rho_inf, default 0.8) damps them, where the trapezoidal rule
    # keeps them ringing and its Newton can fail after the jump
    given_integrator = (scene.raw.get("dynamics") or {}).get("integrator")
    integrator = given_integrator or "generalized-alpha"
    return {"order": 2, "formulation": "mixed" if mixed else "displacement", "dt": dt,
            "integrator": integrator}  # fmt: skip


def reference_plan(scene: Scene, t_end: float, frame_dt: float) -> tuple[str, float]:
    """One line on the reference, its step and its predicted time, and that time (s; NaN
    when no cost law prices it): per step :data:`STEP_OF_STATIC` of a static solve's cost
    law (:mod:`studies.cost_model`), at least :data:`STEP_FLOOR`."""
    from .cost_model import SolveCosts, read_laws

    s = reference_settings(scene, t_end, frame_dt)
    steps = int(round(t_end / s["dt"]))
    name = "fem-P2-mixed" if s["formulation"] == "mixed" else "P2"
    try:
        p = SolveCosts(read_laws(), tets=scene.mesh.n_tets, law=scene.material.law).predict(name)
        seconds = steps * max(STEP_FLOOR, p.seconds * STEP_OF_STATIC)
        when = f"predicted {seconds:.3g} s"
    except Exception:  # noqa: BLE001 - no law prices it: the plan says so
        seconds, when = float("nan"), "no cost law prices it"
    kind = "P2/P1 mixed" if s["formulation"] == "mixed" else "P2"
    return f"reference: implicit {kind}, {steps} steps of {1e3 * s['dt']:.3g} ms, {when}", seconds


def reference_motion(
    scene: Scene, t_end: float, frame_dt: float, scale: Any = None, max_time: float | None = None
) -> tuple[Motion, str]:
    """The dynamic reference (:func:`reference_fem.dynamics_implicit.run`) from rest over
    ``[0, t_end]``, at the probes of :func:`probe_nodes`, its field at the frames
    :func:`frame_run` keeps (``field_frames`` 50), and its energy; and a description."""
    from reference_fem.dynamics_implicit import run

    s = reference_settings(scene, t_end, frame_dt)
    nodes, w, names = probe_nodes(scene)
    X = scene.mesh.points
    points = {f"p{i}": (w[i] @ X[nodes[i]]).tolist() for i in range(len(names))}
    n = max(1, int(round(t_end / frame_dt)))
    kept = n // keep_every(n) + 1
    t0 = time.perf_counter()
    with solve_limits(max_time=max_time):
        deadline = Deadline()
        deadline.progress = "the dynamic reference's steps"
        try:
            with deadline.watch():
                r = run(scene, t_end=n * frame_dt, dt=s["dt"], order=2,
                        formulation=s["formulation"], probes=points, initial="rest",
                        frames=kept, integrator=s["integrator"])  # fmt: skip
        except KeyboardInterrupt:
            raise deadline.stopped(interrupted=True) from None
    probes = np.stack([r.probes[k] for k in points], axis=1)
    e = r.energies
    stored = e["kinetic"] + e["strain"]
    field = np.asarray(r.frames) if len(r.frames) == kept else None
    motion = Motion(np.asarray(r.times), probes, field, stored - e["external_work"],
                    float(stored.max()))  # fmt: skip
    motion.field_times = np.asarray(r.frame_times)  # type: ignore[attr-defined]
    kind = "P2/P1 mixed" if s["formulation"] == "mixed" else "P2"
    text = (f"implicit {kind} ({r.info.get('integrator', 'trapezoidal')}), {r.steps} steps of "
            f"{1e3 * s['dt']:.3g} ms in {time.perf_counter() - t0:.1f} s")  # fmt: skip
    return motion, text


def load_factor(scene: Scene) -> Any:
    """The scene's load history (:class:`springfem.frames.LoadHistory`)."""
    from springfem.frames import LoadHistory

    return LoadHistory(scene)
