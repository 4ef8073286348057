"""Reusable figures: deformed meshes coloured by an error field (pyvista, off-screen) and
small matplotlib helpers (error bars per case, log-log convergence with fitted rates).

The pyvista panels are rendered one by one with the same camera and colour limits and then
composed with matplotlib, which gives one shared colour bar and text labels that never cover
the meshes.

Examples
--------
>>> nice_warp_factor(4e-4, 0.1)
50.0
>>> nice_warp_factor(0.08, 0.08)
1.0
"""

from __future__ import annotations

import ctypes.util
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from springfem.mesh import TetMesh

from .tables import save_figure

VTK_TETRA = 10
CMAP = "viridis"


@dataclass
class Panel:
    """One deformed mesh of an error figure.

    Attributes
    ----------
    label
        Text shown above the panel (model name, summary error).
    u
        Vertex displacement ``(n, 3)`` used to deform the mesh.
    error
        Scalar per vertex ``(n,)`` that colours the mesh.
    """

    label: str
    u: np.ndarray
    error: np.ndarray


def nice_warp_factor(u_max: float, length: float, fraction: float = 0.2) -> float:
    """A round warp factor (1, 2 or 5 times a power of ten) that makes the largest
    displacement about ``fraction`` of ``length``; never below 1 (true scale).
    """
    if not (u_max > 0 and np.isfinite(u_max)):
        return 1.0
    raw = fraction * length / u_max
    if raw <= 1.0:
        return 1.0
    exp = math.floor(math.log10(raw))
    for m in (5.0, 2.0, 1.0):
        if m * 10**exp <= raw:
            return float(m * 10**exp)
    return float(10**exp)  # pragma: no cover - m = 1 always matches


def import_pyvista():
    """pyvista configured for off-screen rendering (EGL when there is no X display)."""
    os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
    if (
        not os.environ.get("DISPLAY")
        and "VTK_DEFAULT_OPENGL_WINDOW" not in os.environ
        and ctypes.util.find_library("EGL")
    ):
        # VTK otherwise tries X first and prints a warning before falling back
        os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = "vtkEGLRenderWindow"
    import pyvista as pv

    pv.OFF_SCREEN = True
    return pv


def surface_grid(mesh: TetMesh, points: np.ndarray, point_data: dict[str, np.ndarray]):
    """The boundary surface of the tet mesh at ``points`` with ``point_data`` attached."""
    pv = import_pyvista()
    cells = np.hstack([np.full((mesh.n_tets, 1), 4), mesh.tets]).ravel()
    grid = pv.UnstructuredGrid(cells, np.full(mesh.n_tets, VTK_TETRA, np.uint8), points)
    for key, value in point_data.items():
        grid.point_data[key] = np.asarray(value)
    return grid.extract_surface(algorithm="dataset_surface")


def _view_direction(extent: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Camera direction and view-up: oblique front view, looking along the thinnest
    horizontal axis of elongated bodies so bending stays visible."""
    direction = np.array([0.45, -1.0, 0.55])
    if extent[1] > 3 * extent[0]:  # long in y: look along x
        direction = np.array([-1.0, 0.45, 0.55])
    return direction / np.linalg.norm(direction), np.array([0.0, 0.0, 1.0])


def render_error_panels(
    mesh: TetMesh,
    panels: Sequence[Panel],
    path: str | os.PathLike,
    warp: float = 1.0,
    clim: tuple[float, float] | None = None,
    scalar_title: str = "|u - u_ref| (m)",
    title: str | None = None,
    panel_pixels: int = 1100,
) -> Path:
    """Render the deformed meshes of ``panels`` side by side with one colour scale.

    Parameters
    ----------
    mesh
        The (shared) tet mesh.
    panels
        Displacement and colouring scalar per panel.
    path
        PNG file to write (atomically).
    warp
        Displacements are multiplied by this factor before drawing (say it in ``title``).
    clim
        Colour limits; default ``(0, max of all panels' errors)``.
    scalar_title
        Colour-bar label.
    title
        Figure title.
    panel_pixels
        Width in pixels of one rendered panel.

    Returns
    -------
    Path
        The PNG path.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import Normalize

    pv = import_pyvista()
    deformed = [mesh.points + warp * np.asarray(p.u).reshape(-1, 3) for p in panels]
    allpts = np.vstack([mesh.points, *deformed])
    lo, hi = allpts.min(axis=0), allpts.max(axis=0)
    extent = np.maximum(hi - lo, 1e-12 * max(np.ptp(allpts), 1.0))
    center = 0.5 * (lo + hi)
    direction, up = _view_direction(extent)
    if clim is None:
        vmax = max(float(np.nanmax(p.error)) if np.size(p.error) else 0.0 for p in panels)
        clim = (0.0, vmax if vmax > 0 else 1.0)

    # panel aspect from the projected bounding box
    right = np.cross(direction, up)
    right /= np.linalg.norm(right)
    view_up = np.cross(right, direction)
    corners = np.array(np.meshgrid(*zip(lo, hi, strict=True), indexing="ij")).reshape(3, -1).T
    proj_w = np.ptp((corners - center) @ right)
    proj_h = np.ptp((corners - center) @ view_up)
    aspect = float(np.clip(proj_h / proj_w, 0.2, 1.2))
    window = (panel_pixels, max(int(panel_pixels * aspect * 1.15), 150))

    rest_edges = surface_grid(mesh, mesh.points, {}).extract_feature_edges(
        boundary_edges=False, non_manifold_edges=False, feature_angle=30.0, manifold_edges=False
    )
    images = []
    for p, pts in zip(panels, deformed, strict=True):
        surf = surface_grid(mesh, pts, {"error": np.asarray(p.error, float)})
        pl = pv.Plotter(off_screen=True, window_size=window)
        pl.set_background("white")
        pl.add_mesh(rest_edges, color="#6e6e6e", line_width=2.0, opacity=0.9)  # the rest shape
        pl.add_mesh(
            surf,
            scalars="error",
            cmap=CMAP,
            clim=clim,
            show_scalar_bar=False,
            ambient=0.25,
            show_edges=mesh.n_tets <= 20_000,
            edge_color="#333333",
            edge_opacity=0.25,
            line_width=0.5,
        )
        pl.enable_anti_aliasing("ssaa")
        pl.enable_parallel_projection()
        pl.camera.focal_point = center
        pl.camera.position = center + 10.0 * np.linalg.norm(extent) * direction
        pl.camera.up = up
        pl.reset_camera(bounds=(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]))
        images.append(pl.screenshot(return_img=True))
        pl.close()

    images = _crop_common(images)
    h, w = images[0].shape[:2]
    n = len(images)
    stack = w / h > 2.0  # long bodies: panels above each other
    rows, cols = (n, 1) if stack else ((n + 2) // 3, min(n, 3))
    fig_w = 9.0 if stack else 4.0 * cols
    img_h = (fig_w / cols) * h / w
    title_h, bar_h = 0.3, 0.75
    fig_h = rows * (img_h + title_h) + bar_h + (0.35 if title else 0.0)
    fig = plt.figure(figsize=(fig_w, fig_h))
    gs = fig.add_gridspec(
        rows + 1,
        cols,
        height_ratios=[img_h + title_h] * rows + [bar_h],
        hspace=0.0,
        wspace=0.02,
        left=0.01,
        right=0.99,
        bottom=0.0,
        top=1.0 - (0.35 / fig_h if title else 0.0),
    )
    for i, (img, p) in enumerate(zip(images, panels, strict=True)):
        ax = fig.add_subplot(gs[i // cols, i % cols])
        ax.imshow(img)
        ax.set_title(p.label, fontsize=9, pad=3)
        ax.axis("off")
    cax = fig.add_subplot(gs[rows, :])
    pos = cax.get_position()
    cax.set_position([pos.x0 + 0.1 * pos.width, pos.y0 + 0.62 * pos.height,
                      0.8 * pos.width, 0.22 * pos.height])  # fmt: skip
    sm = plt.cm.ScalarMappable(norm=Normalize(*clim), cmap=CMAP)
    cbar = fig.colorbar(sm, cax=cax, orientation="horizontal")
    cbar.formatter.set_powerlimits((-2, 3))
    cbar.update_ticks()
    cbar.set_label(scalar_title, fontsize=9)
    cbar.ax.tick_params(labelsize=8)
    if title:
        fig.suptitle(title, fontsize=10, y=1.0 - 0.05 / fig_h, va="top")
    return save_figure(fig, path, dpi=130)


def _crop_common(images: list[np.ndarray], pad: int = 6) -> list[np.ndarray]:
    """Crop all images to the union of their non-white pixels (same crop keeps one scale)."""
    mask = np.zeros(images[0].shape[:2], bool)
    for img in images:
        mask |= (img[..., :3] < 250).any(axis=2)
    if not mask.any():
        return images
    r = np.flatnonzero(mask.any(axis=1))
    c = np.flatnonzero(mask.any(axis=0))
    r0, r1 = max(r[0] - pad, 0), min(r[-1] + pad + 1, mask.shape[0])
    c0, c1 = max(c[0] - pad, 0), min(c[-1] + pad + 1, mask.shape[1])
    return [img[r0:r1, c0:c1] for img in images]


# ------------------------------------------------------------------------- matplotlib


def grouped_bars(
    ax,
    groups: Sequence[str],
    series: dict[str, Sequence[float]],
    ylabel: str,
    log: bool = True,
    fmt: str = "{:.1%}",
) -> None:
    """Bars per group (e.g. scene) and series (e.g. error kind), values written on top."""
    n = len(series)
    width = 0.8 / max(n, 1)
    x = np.arange(len(groups))
    for i, (name, values) in enumerate(series.items()):
        v = np.asarray(values, float)
        shown = np.where(np.isfinite(v) & ((v > 0) | (not log)), v, np.nan)
        bars = ax.bar(x + (i - (n - 1) / 2) * width, shown, width, label=name)
        for b, val in zip(bars, v, strict=True):
            if not np.isfinite(val) or (log and val <= 0):
                continue
            up = val >= 0
            ax.annotate(
                fmt.format(val) if abs(val) >= 5e-4 or log else "0",
                (b.get_x() + b.get_width() / 2, val),
                ha="center",
                va="bottom" if up else "top",
                fontsize=7,
                rotation=90 if n >= 3 else 0,
                xytext=(0, 2 if up else -2),
                textcoords="offset points",
            )
    ax.set_xticks(x, groups)
    if sum(len(str(g)) for g in groups) > 40:  # long names side by side would overlap
        ax.tick_params(axis="x", labelsize=8)
        for label in ax.get_xticklabels():
            label.set(rotation=30, ha="right", rotation_mode="anchor")
    ax.margins(y=0.15)
    ax.set_ylabel(ylabel)
    if log:
        ax.set_yscale("log")
    ax.grid(True, axis="y", which="both", alpha=0.3)
    ax.legend(fontsize=8)


def loglog_rates(
    ax,
    curves: dict[str, tuple[Sequence[float], Sequence[float]]],
    xlabel: str,
    ylabel: str,
    rates: dict[str, float] | None = None,
    xticks: Sequence[float] | None = None,
) -> None:
    """Log-log error curves; the legend gives each curve's fitted rate.

    ``xticks``: put major ticks (labelled ``%.3g``) at these values, e.g. the mesh sizes.
    """
    from matplotlib.ticker import NullFormatter, NullLocator

    markers = "osD^v<>"
    for i, (name, (h, err)) in enumerate(curves.items()):
        label = name
        if rates and name in rates and np.isfinite(rates[name]):
            label = f"{name} (rate {rates[name]:.2f})"
        e = np.asarray(err, float)
        ax.loglog(h, np.where(e > 0, e, np.nan), marker=markers[i % len(markers)], label=label)
    if xticks is not None:
        ax.xaxis.set_minor_locator(NullLocator())
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xticks(list(xticks), [f"{x:.3g}" for x in xticks])
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
