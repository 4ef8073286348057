"""Time series of a dynamic solve: VTU frames in a ParaView collection (PVD) and histories.

A :class:`SeriesWriter` is a solver callback ``writer(step, t, x, v)`` (the signature of
the ``callback`` of :func:`springfem.mechanics.explicit` and ``implicit``). It
writes a frame every ``interval`` seconds of simulated time (``<stem>_00000.vtu`` … with
point data ``displacement`` and ``velocity``) and rewrites ``<stem>.pvd`` atomically after
each frame, so a run killed mid-way leaves a valid series of the frames it reached. It
samples histories every ``history_interval``: probe displacements, kinetic, potential and
total energy, relative volume change. :meth:`SeriesWriter.close` writes the final frame,
``history.csv`` and ``history.png`` and says whether the run reached rest.

Examples
--------
>>> import tempfile
>>> from springfem.mesh import box_mesh
>>> mesh = box_mesh((1.0, 1.0, 1.0), (1, 1, 1))
>>> w = SeriesWriter(tempfile.mkdtemp(), mesh, interval=0.5, masses=np.ones(8))
>>> for k in range(1, 11):  # a rigid drift at 1 m/s along x
...     t = 0.1 * k
...     _ = w(k, t, mesh.points + [t, 0, 0], np.tile([1.0, 0, 0], (8, 1)))
>>> s = w.close()
>>> s.times, s.frames[-1].name, float(s.history["kinetic"].iloc[-1])
([0.0, 0.5, 1.0], 'frame_00002.vtu', 4.0)
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from .files import atomic_write_text, remove_stale_temp_files
from .mesh import TetMesh, write_vtu

REST_WINDOW = 0.1  # the last 10% of the run decides whether it is at rest
REST_TOL = 1e-6  # ... kinetic energy below this fraction of the run's largest


def pvd_text(entries: list[tuple[float, str]]) -> str:
    """A ParaView collection file listing ``(time, file)`` datasets.

    Parameters
    ----------
    entries
        ``(time, file name)`` pairs (s, relative to the ``.pvd`` file), in time order.

    Returns
    -------
    str
        The ``.pvd`` XML text.

    Examples
    --------
    >>> print(pvd_text([(0.0, "f_0.vtu")]))  # doctest: +NORMALIZE_WHITESPACE
    <?xml version="1.0"?>
    <VTKFile type="Collection" version="0.1" byte_order="LittleEndian">
    <Collection>
    <DataSet timestep="0" group="" part="0" file="f_0.vtu"/>
    </Collection>
    </VTKFile>
    """
    rows = [
        f'    <DataSet timestep="{t:.17g}" group="" part="0" file={quoteattr(f)}/>'
        for t, f in entries
    ]
    head = '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1" '
    head += 'byte_order="LittleEndian">\n  <Collection>\n'
    return head + "\n".join(rows) + "\n  </Collection>\n</VTKFile>\n"


def reached_rest(kinetic: np.ndarray, window: float = REST_WINDOW, tol: float = REST_TOL) -> bool:
    """Whether the kinetic energy stayed below ``tol`` × its maximum over the run's last part.

    A single sample near zero is not rest (an undamped oscillation passes through zero
    kinetic energy twice a period); the whole last ``window`` of the samples must be quiet.

    Parameters
    ----------
    kinetic
        Kinetic energy history, in time order.
    window, tol
        Fraction of the run examined, and the threshold relative to the run's peak.

    Returns
    -------
    bool
        ``False`` for fewer than 2 samples; ``True`` for a run that never moved.

    Examples
    --------
    >>> t = np.linspace(0, 10, 1001)
    >>> reached_rest(np.cos(3 * t) ** 2), reached_rest(np.exp(-4 * t) * np.cos(3 * t) ** 2)
    (False, True)
    """
    ke = np.asarray(kinetic, float)
    if ke.size < 2:
        return False
    peak = float(np.max(ke))
    if peak <= 0:
        return True
    tail = ke[int(np.floor((1 - window) * (ke.size - 1))) :]
    return bool(np.max(tail) <= tol * peak)


@dataclass
class SeriesSummary:
    """What a :class:`SeriesWriter` wrote.

    Attributes
    ----------
    pvd
        The collection file; ``frames`` and ``times`` its datasets.
    history
        The sampled histories (a pandas DataFrame, also ``history.csv``).
    files
        Every file written besides the frames (PVD, CSV, PNG).
    end_time, steps
        Simulated time and step count of the last callback.
    at_rest
        :func:`reached_rest` of the kinetic energy history (``None`` without masses).
    """

    pvd: Path
    frames: list[Path]
    times: list[float]
    history: object
    files: list[Path] = field(default_factory=list)
    end_time: float = 0.0
    steps: int = 0
    at_rest: bool | None = None

    def status_line(self) -> str:
        """``end of run at t = …`` and whether it reached rest (not "converged")."""
        rest = {True: "at rest", False: "still moving", None: "rest unknown (no masses)"}
        return (
            f"end of run at t = {self.end_time:.6g} s after {self.steps} steps: "
            + rest[self.at_rest]
        )


class SeriesWriter:
    """Solver callback writing frames and histories (see the module docstring).

    Parameters
    ----------
    folder
        Output folder (created).
    mesh
        The mesh; frames hold ``displacement = x - mesh.points``.
    interval
        Simulated seconds between frames (> 0).
    history_interval
        Seconds between history samples (default ``interval / 10``; 0: every step).
    masses
        Lumped nodal masses ``(n,)``: enables the kinetic energy and the rest test.
    potential
        ``potential(x) -> float | None``: the potential energy (e.g. a system's ``energy``).
    probes
        ``probes(u) -> {name: [ux, uy, uz]}`` (e.g. ``Scene.probe_displacements``).
    x0, v0
        Initial state written as frame 0 (default: rest, zero velocity).
    stem
        File name stem of the frames and the PVD.
    """

    def __init__(
        self,
        folder: str | os.PathLike,
        mesh: TetMesh,
        interval: float,
        history_interval: float | None = None,
        masses: np.ndarray | None = None,
        potential: Callable[[np.ndarray], float | None] | None = None,
        probes: Callable[[np.ndarray], dict[str, list[float]]] | None = None,
        x0: np.ndarray | None = None,
        v0: np.ndarray | None = None,
        stem: str = "frame",
    ):
        if not interval > 0:
            raise ValueError(f"output interval must be positive, got {interval}")
        self.dir = Path(folder)
        self.dir.mkdir(parents=True, exist_ok=True)
        remove_stale_temp_files(self.dir)
        self.mesh, self.interval, self.stem = mesh, float(interval), stem
        self.history_interval = interval / 10 if history_interval is None else history_interval
        self.masses = None if masses is None else np.asarray(masses, float).reshape(-1)
        self.potential, self.probes = potential, probes
        self.v_rest = float(mesh.volumes().sum())
        self.frames: list[Path] = []
        self.times: list[float] = []
        self.rows: list[dict[str, float]] = []
        self._eps = 1e-9 * self.interval
        self.last: tuple[int, float, np.ndarray, np.ndarray] | None = None
        x = mesh.points if x0 is None else np.asarray(x0, float).reshape(-1, 3)
        v = np.zeros_like(x) if v0 is None else np.asarray(v0, float).reshape(-1, 3)
        self._next_frame = self._next_sample = 0.0
        self(0, 0.0, x, v)

    def __call__(self, step: int, t: float, x: np.ndarray, v: np.ndarray) -> None:
        """Record the state after ``step`` at time ``t``; never asks the solver to stop."""
        x, v = np.asarray(x, float).reshape(-1, 3), np.asarray(v, float).reshape(-1, 3)
        self.last = (step, t, x, v)
        if t >= self._next_sample - self._eps:
            self._sample(step, t, x, v)
            self._next_sample = _next_after(t, self.history_interval, self._eps)
        if t >= self._next_frame - self._eps:
            self._frame(t, x, v)
            self._next_frame = _next_after(t, self.interval, self._eps)
        return None

    def _sample(self, step: int, t: float, x: np.ndarray, v: np.ndarray) -> None:
        row: dict[str, float] = {"t": float(t), "step": int(step)}
        if self.masses is not None:
            row["kinetic"] = 0.5 * float(np.sum(self.masses * np.sum(v * v, axis=1)))
        if self.potential is not None:
            e = self.potential(x)
            row["potential"] = float("nan") if e is None else float(e)
            if "kinetic" in row:
                row["total"] = row["kinetic"] + row["potential"]
        row["volume_change"] = float(self.mesh.volumes(x).sum()) / self.v_rest - 1.0
        if self.probes is not None:
            for name, u in self.probes(x - self.mesh.points).items():
                for c, value in zip("xyz", u, strict=True):
                    row[f"probe:{name}:u{c}"] = float(value)
        self.rows.append(row)

    def _frame(self, t: float, x: np.ndarray, v: np.ndarray) -> None:
        path = self.dir / f"{self.stem}_{len(self.frames):05d}.vtu"
        write_vtu(path, self.mesh, point_data={"displacement": x - self.mesh.points, "velocity": v})
        self.frames.append(path)
        self.times.append(float(t))
        entries = [(tt, p.name) for tt, p in zip(self.times, self.frames, strict=True)]
        atomic_write_text(self.dir / f"{self.stem}.pvd", pvd_text(entries))

    def close(self, plot: bool = True) -> SeriesSummary:
        """Write the final state (if not just written), ``history.csv`` and ``history.png``.

        Returns
        -------
        SeriesSummary
        """
        import pandas as pd

        step, t, x, v = self.last  # type: ignore[misc]
        if not self.rows or self.rows[-1]["t"] < t:
            self._sample(step, t, x, v)
        if self.times[-1] < t:
            self._frame(t, x, v)
        hist = pd.DataFrame(self.rows)
        csv = self.dir / "history.csv"
        atomic_write_text(csv, hist.to_csv(index=False))
        files = [self.dir / f"{self.stem}.pvd", csv]
        if plot:
            files.append(history_figure(hist, self.dir / "history.png"))
        rest = reached_rest(hist["kinetic"].to_numpy()) if "kinetic" in hist else None
        return SeriesSummary(files[0], list(self.frames), list(self.times), hist, files, t, step,
                             rest)  # fmt: skip


def _next_after(t: float, interval: float, eps: float) -> float:
    """The first multiple of ``interval`` after ``t`` (a coarse step skips missed ones)."""
    if interval <= 0:
        return t
    return (np.floor((t + eps) / interval) + 1) * interval


def history_figure(hist, path: Path) -> Path:
    """Probe displacements, energies and volume change against time (one panel each).

    Parameters
    ----------
    hist
        The history table (pandas DataFrame): column ``t`` (s) and any of ``probe:*``
        (m), ``kinetic``/``potential``/``total`` (J), ``volume_change``.
    path
        The PNG to write (atomically).

    Returns
    -------
    Path
        ``path``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def drawn(c: str) -> bool:  # a series with no finite value is left out, with a note
        return c in hist.columns and bool(np.isfinite(np.asarray(hist[c], float)).any())

    probe_cols = [c for c in hist.columns if c.startswith("probe:") and drawn(c)]
    energy_cols = [c for c in ("kinetic", "potential", "total") if drawn(c)]
    missing = [c for c in ("potential", "total") if c in hist.columns and not drawn(c)]
    volume_cols = ["volume_change"] if drawn("volume_change") else []
    panels = [p for p in (probe_cols, energy_cols, volume_cols) if p]
    if not panels:  # nothing finite to draw: an empty energy panel that says so
        panels, energy_cols = [[]], []
        energy_cols = panels[0]
    fig, axes = plt.subplots(
        len(panels), 1, figsize=(6, 2.2 * len(panels)), sharex=True, layout="constrained"
    )
    axes = np.atleast_1d(axes)
    labels = {0: "displacement (m)", 1: "energy (J)", 2: "relative volume change"}
    for ax, cols in zip(axes, panels, strict=True):
        for c in cols:
            ax.plot(hist["t"], hist[c], label=c, lw=1)
        kind = 0 if cols is probe_cols else 1 if cols is energy_cols else 2
        ax.set_ylabel(labels[kind], fontsize=8)
        ax.grid(True, alpha=0.3)
        if cols:
            ax.legend(fontsize=7, loc="best")
        if cols is energy_cols and missing:
            ax.set_title(
                f"{' and '.join(missing)} energy not drawn: undefined under a follower "
                "pressure (it has no potential)",
                fontsize=8,
            )
    axes[-1].set_xlabel("time (s)")
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp.png")
    fig.savefig(tmp, dpi=110, bbox_inches="tight")
    plt.close(fig)
    os.replace(tmp, path)
    return path
