"""Animations of a time series: pyvista off-screen screenshots of the frames → GIF or MP4.

Examples
--------
>>> animation_path("out/sag/series", "gif").name
'animation.gif'
>>> [n % 16 for n in WINDOW]   # an MP4 frame is the window, not resized by the encoder
[0, 0]
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from springfem.errors import InputError

#: The frame size in pixels (width, height): both multiples of 16, the macro-block size of
#: the H.264 encoder, so an MP4 keeps the exact frame size (ffmpeg would resize otherwise).
WINDOW = (480, 368)


def video_backend() -> str | None:
    """The installed package that writes MP4 for imageio (``imageio_ffmpeg`` or ``av``).

    Returns
    -------
    str or None
        The module name, or ``None`` when neither is installed (GIF needs neither).
    """
    import importlib.util

    for name in ("imageio_ffmpeg", "av"):
        if importlib.util.find_spec(name) is not None:
            return name
    return None


def animation_path(folder: str | os.PathLike, fmt: str) -> Path:
    """``<folder>/animation.<fmt>``.

    Parameters
    ----------
    folder
        The series folder.
    fmt
        ``gif`` or ``mp4``.

    Returns
    -------
    pathlib.Path
    """
    return Path(folder) / f"animation.{fmt}"


def frame_times(frames: list[Path]) -> list[float] | None:
    """The times of ``frames`` from the ``.pvd`` file beside them (``None`` without one).

    Parameters
    ----------
    frames
        VTU files of one series.

    Returns
    -------
    list of float or None
    """
    import xml.etree.ElementTree as ET

    if not frames:
        return None
    for pvd in sorted(Path(frames[0]).parent.glob("*.pvd")):
        try:
            sets = ET.parse(pvd).getroot().iter("DataSet")
            by_file = {d.get("file"): float(d.get("timestep", "nan")) for d in sets}
        except (ET.ParseError, ValueError):
            continue
        if all(Path(f).name in by_file for f in frames):
            return [by_file[Path(f).name] for f in frames]
    return None


def animate_frames(
    frames: list[Path],
    path: str | os.PathLike,
    fps: int = 10,
    warp: float | None = None,
    times: list[float] | None = None,
) -> Path:
    """Render each VTU frame warped by its displacement and write an animation.

    Every frame shows its time and the displacement magnification; the colour bar (``|u|``
    one scale for the whole run) has three labels.

    Parameters
    ----------
    frames
        VTU files with point data ``displacement``, in time order.
    path
        ``.gif`` (imageio) or ``.mp4`` (imageio-ffmpeg; an :class:`InputError` when absent).
    fps
        Frames per second.
    warp
        Displacement magnification (default: a round factor that makes the largest
        displacement about a fifth of the body, :func:`studies.plots.nice_warp_factor`;
        never below 1).
    times
        The frames' times (s); default read from the series' ``.pvd`` (:func:`frame_times`).

    Returns
    -------
    pathlib.Path
        The animation file.
    """
    import imageio.v2 as imageio

    from .plots import import_pyvista, nice_warp_factor

    pv = import_pyvista()  # off-screen through EGL: no X-server messages
    path = Path(path)
    if path.suffix == ".mp4" and video_backend() is None:
        raise InputError(
            f"cannot write the animation {path}: mp4 needs the imageio-ffmpeg or av package"
            " (gif needs neither)"
        )
    meshes = [pv.read(str(f)) for f in frames]
    mags = [np.linalg.norm(m.point_data["displacement"], axis=1) for m in meshes]
    u_max = max(float(max(m.max() for m in mags)), 1e-300)
    clim = [0.0, u_max]
    if warp is None:
        lo, hi = np.asarray(meshes[0].bounds).reshape(3, 2).T
        warp = nice_warp_factor(u_max, float(np.linalg.norm(hi - lo)))
    times = times if times is not None else frame_times(frames)
    bar = {"title": "displacement (m)", "n_labels": 3, "fmt": "%.2g", "title_font_size": 12,
           "label_font_size": 11, "vertical": True, "position_x": 0.84, "position_y": 0.2,
           "width": 0.07, "height": 0.6, "color": "black"}  # fmt: skip
    bounds = None
    images = []
    for k, (mesh, mag) in enumerate(zip(meshes, mags, strict=True)):
        warped = mesh.warp_by_vector("displacement", factor=warp)
        warped.point_data["|u| (m)"] = mag
        plotter = pv.Plotter(off_screen=True, window_size=WINDOW)
        plotter.set_background("white")
        plotter.add_mesh(warped, scalars="|u| (m)", clim=clim, show_edges=False,
                         scalar_bar_args=bar)  # fmt: skip
        stamp = f"t = {times[k]:.4g} s" if times is not None else f"frame {k}"
        scale = "true scale" if warp == 1.0 else f"displacements x{warp:g}"
        plotter.add_text(f"{stamp}   ({scale})", position="upper_left", font_size=9,
                         color="black")  # fmt: skip
        if bounds is None:
            plotter.view_isometric()
            plotter.camera.zoom(0.8)  # room for the time stamp and the colour bar
            bounds = plotter.camera_position
        plotter.camera_position = bounds
        images.append(plotter.screenshot(return_img=True))
        plotter.close()
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp{path.suffix}")
    try:
        if path.suffix == ".gif":
            imageio.mimsave(tmp, images, duration=1.0 / fps, loop=0)
        else:
            imageio.mimsave(tmp, images, fps=fps)
    except (ValueError, RuntimeError, ImportError) as exc:
        tmp.unlink(missing_ok=True)
        why = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise InputError(f"cannot write the animation {path}: {why}") from None
    os.replace(tmp, path)
    return path
