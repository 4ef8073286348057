"""The ``[output]`` scene section: time series of dynamic solves.

A scene's ``[output]`` table sets what a dynamic (timed) solve writes besides its final
state: ``interval`` (simulated seconds between frames of a ParaView series, see
:class:`springfem.series.SeriesWriter`), ``animation`` (``"gif"``, ``"mp4"`` or
``false``) and ``probes_history`` (probe, energy and volume histories, default true).

Examples
--------
>>> OutputOptions.of_table({"interval": 0.01, "animation": "gif"})
OutputOptions(interval=0.01, animation='gif', probes_history=True)
>>> OutputOptions.of_table({"animation": "avi"})
Traceback (most recent call last):
...
springfem.errors.SceneError: <scene>: output.animation: 'avi' is not one of gif, mp4, false
"""

from __future__ import annotations

from dataclasses import dataclass

from .reader import TableReader, _show

ANIMATIONS = ("gif", "mp4")


@dataclass(frozen=True)
class OutputOptions:
    """What a dynamic solve writes (a scene's ``[output]`` section).

    Attributes
    ----------
    interval
        Simulated seconds between frames; ``None``: no series (only the final state).
    animation
        ``gif`` or ``mp4`` (an animation of the frames, pyvista off-screen), or ``None``.
    probes_history
        Write ``history.csv``/``history.png`` (probe displacements, energies, volume).
    """

    interval: float | None = None
    animation: str | None = None
    probes_history: bool = True

    @classmethod
    def of(cls, scene) -> OutputOptions:
        """The ``[output]`` options of ``scene`` (defaults when the section is absent)."""
        return scene.section("output", parse_output)

    @classmethod
    def of_table(cls, table: dict, file: str = "<scene>") -> OutputOptions:
        """Parse a plain ``[output]`` table (see :func:`parse_output`)."""
        return parse_output(TableReader(table, "output", file))


def parse_output(r: TableReader) -> OutputOptions:
    """Validate a scene's ``[output]`` table.

    Parameters
    ----------
    r
        Reader over the table.

    Returns
    -------
    OutputOptions
    """
    interval = r.get("interval", "float", default=None, positive=True)
    animation = None
    if r.has("animation"):
        v = r.t["animation"]
        r.used.add("animation")
        if v is False:
            animation = None
        elif isinstance(v, str) and v in ANIMATIONS:
            animation = v
        else:
            raise r.fail("animation", f"{_show(v)} is not one of gif, mp4, false")
        if animation is not None and interval is None:
            raise r.fail("animation", "needs output.interval (the frames to animate)")
    history = r.get("probes_history", "bool", default=True)
    r.finish()
    return OutputOptions(interval, animation, history)
