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


def animate_frames(
    frames: list[Path], path: str | os.PathLike, fps: int = 10, warp: float = 1.0
) -> Path:
    """Render each VTU frame warped by its displacement and write an animation.

    Parameters
    ----------
    frames
        VTU files with point data ``displacement``, in time order.
    path
        ``.gif`` (imageio) or ``.mp4`` (imageio-ffmpeg; an :class:`InputError` when absent).
    fps
        Frames per second.
    warp
        Displacement magnification.

    Returns
    -------
    pathlib.Path
        The animation file.
    """
    os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
    import imageio.v2 as imageio
    import pyvista as pv

    path = Path(path)
    if path.suffix == ".mp4" and video_backend() is None:
        raise InputError(
            f"cannot write the animation {path}: mp4 needs the imageio-ffmpeg or av package"
            " (gif needs neither)"
        )
    meshes = [pv.read(str(f)) for f in frames]
    mags = [np.linalg.norm(m.point_data["displacement"], axis=1) for m in meshes]
    clim = [0.0, max(float(max(m.max() for m in mags)), 1e-300)]
    bounds = None
    images = []
    for mesh, mag in zip(meshes, mags, strict=True):
        warped = mesh.warp_by_vector("displacement", factor=warp)
        warped.point_data["|u| (m)"] = mag
        plotter = pv.Plotter(off_screen=True, window_size=WINDOW)
        plotter.add_mesh(warped, scalars="|u| (m)", clim=clim, show_edges=False)
        if bounds is None:
            plotter.view_isometric()
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
