"""Land et al. 2015's fibre field of problem 3, in closed form at any point of the wall.

The definition is the one of Land et al.'s own mesh and fibre script (Proc. R. Soc. A 471:
20150641, problem 3) and of FEniCS-pulse's benchmark: a point ``x`` of the wall between the
endocardial ellipsoid ``(r_s, r_l) = (7, 17)`` mm and the epicardial ``(10, 20)`` mm lies on
exactly one ellipsoid of the family

    rho^2 / (r_s(t))^2 + z^2 / (r_l(t))^2 = 1,  r_s(t) = 7 + 3 t,  r_l(t) = 17 + 3 t,

with ``rho^2 = x^2 + y^2`` and ``t`` in ``[0, 1]`` (0 on the endocardium, 1 on the
epicardium). On that ellipsoid, parametrised as ``x = r_s sin u cos v``,
``y = r_s sin u sin v``, ``z = r_l cos u`` (``u`` in ``[-pi, 0]``), the unit tangents are
``e_u = dx/du / |dx/du|`` (along the meridian, from the apex towards the base) and
``e_v = dx/dv / |dx/dv|`` (along the parallel, anticlockwise about ``+z``), and the fibre is

    f = sin(alpha) e_u + cos(alpha) e_v,  alpha = endo_angle + (epi_angle - endo_angle) t,

with ``alpha`` going from +90 degrees on the endocardium to -90 degrees on the epicardium.
The sheet is the ellipsoid's unit normal ``n = grad t / |grad t|`` (transmural, outwards)
and the third axis ``f x n``; ``e_u``, ``e_v`` and ``n`` are orthonormal, so ``f`` is a
unit vector tangent to the ``t`` surface. Frames are rows (fiber, sheet, normal), as in
:mod:`springfem.axes`.

The field is singular on the long axis (``rho = 0``: ``e_v`` is undefined and ``e_u``
turns by 180 degrees across the axis); there the frame takes ``v = 0``. Points a faceted
mesh puts just inside the endocardium or outside the epicardium get ``t`` clamped to
``[0, 1]``. See docs/verification.rst#land-problem-3-fibres for what the field does to the
apex.

Examples
--------
>>> import numpy as np
>>> x = np.array([[7.0, 0.0, 0.0], [0.0, 10.0, 0.0], [0.0, 0.0, -18.5]])
>>> ellipsoid_parameter(x).round(12).tolist()
[0.0, 1.0, 0.5]
>>> frames = land_frames(x)
>>> (frames[0, 0].round(12) + 0.0).tolist()  # equator of the endocardium: alpha = 90, f = e_u
[0.0, 0.0, 1.0]
>>> np.abs(frames[1, 0]).round(12).tolist()  # equator of the epicardium: f = -e_u
[0.0, 0.0, 1.0]
"""

from __future__ import annotations

import numpy as np

from .errors import InputError

#: Land et al. 2015: ``(r_short, r_long)`` of the endocardium and the epicardium, mm.
LAND_ENDO = (7.0, 17.0)
LAND_EPI = (10.0, 20.0)
#: Helix angle (degrees) on the endocardium and the epicardium in the paper's convention.
LAND_ENDO_ANGLE, LAND_EPI_ANGLE = 90.0, -90.0
#: Mesh vertices whose ``t`` lies further than this outside ``[0, 1]`` are not in the wall.
T_TOLERANCE = 0.05


def _level(rho2, z2, t, endo, epi):
    a = endo[0] + (epi[0] - endo[0]) * t
    c = endo[1] + (epi[1] - endo[1]) * t
    return rho2 / a**2 + z2 / c**2 - 1.0


def ellipsoid_parameter(
    points: np.ndarray, endo=LAND_ENDO, epi=LAND_EPI, tolerance: float | None = None
) -> np.ndarray:
    """The transmural parameter ``t`` of each point: the ``t`` surface it lies on.

    ``rho^2 / r_s(t)^2 + z^2 / r_l(t)^2 - 1`` decreases strictly with ``t`` (both radii
    grow), so bisection on a bracket finds the one root to round-off. The result is clamped
    to ``[0, 1]``: a faceted mesh's chords cut into the cavity (deeply at the apex, where
    the endocardium's radius of curvature is ``7^2 / 17 = 2.9`` mm).

    Parameters
    ----------
    points
        ``(..., 3)`` coordinates (the long axis is ``z``).
    endo, epi
        ``(r_short, r_long)`` of the endocardial and epicardial ellipsoids.
    tolerance
        Refuse points whose unclamped ``t`` lies further than this outside ``[0, 1]``
        (``None``: clamp silently); for a mesh's vertices, which lie on the surfaces.

    Returns
    -------
    numpy.ndarray
        ``(...)`` values of ``t`` in ``[0, 1]``.

    Raises
    ------
    InputError
        With ``tolerance``: a point outside the wall (the radii do not fit the mesh).
    """
    x = np.asarray(points, dtype=float)
    rho2 = x[..., 0] ** 2 + x[..., 1] ** 2
    z2 = x[..., 2] ** 2
    # radii stay positive on the bracket; points beyond it end at its ends (then clamped)
    low = -0.9 * min(endo[0] / (epi[0] - endo[0]), endo[1] / (epi[1] - endo[1]))
    lo = np.full(rho2.shape, low)
    hi = np.full(rho2.shape, 3.0)
    for _ in range(64):  # 2^-64 of the bracket: round-off
        mid = 0.5 * (lo + hi)
        above = _level(rho2, z2, mid, endo, epi) > 0
        lo = np.where(above, mid, lo)
        hi = np.where(above, hi, mid)
    t = 0.5 * (lo + hi)
    if tolerance is not None and ((t < -tolerance) | (t > 1 + tolerance)).any():
        worst = float(np.max(np.maximum(-t, t - 1)))
        raise InputError(
            f"land-ellipsoid fibres: mesh points lie {worst:.3g} (in t) outside the wall "
            f"between the ellipsoids {tuple(map(float, endo))} and "
            f"{tuple(map(float, epi))}: do the radii fit the mesh?"
        )
    return np.clip(t, 0.0, 1.0)


def land_basis(points: np.ndarray, endo=LAND_ENDO, epi=LAND_EPI):
    """``t`` and the orthonormal ``e_u``, ``e_v``, ``n`` of the ``t`` ellipsoid at each point.

    Parameters
    ----------
    points
        ``(..., 3)`` coordinates.
    endo, epi
        As for :func:`ellipsoid_parameter`.

    Returns
    -------
    t, e_u, e_v, n
        ``(...)`` and three ``(..., 3)`` unit vectors: meridian (towards the base),
        parallel (anticlockwise about ``+z``) and outward normal.
    """
    x = np.asarray(points, dtype=float)
    t = ellipsoid_parameter(x, endo, epi)
    a = (endo[0] + (epi[0] - endo[0]) * t)[..., None]
    c = (endo[1] + (epi[1] - endo[1]) * t)[..., None]
    rho = np.hypot(x[..., 0], x[..., 1])[..., None]
    on_axis = rho < 1e-12 * c
    safe = np.where(on_axis, 1.0, rho)
    # (cos v, sin v) = -(x, y) / rho for u in [-pi, 0] (sin u = -rho / r_s <= 0); v = 0
    # on the axis
    cos_v = np.where(on_axis, 1.0, -x[..., :1] / safe)
    sin_v = np.where(on_axis, 0.0, -x[..., 1:2] / safe)
    # the point's own (u, v) on its t surface: cos u = z / r_l, sin u = -sqrt(1 - cos^2 u)
    cos_u = np.clip(x[..., 2:3] / c, -1.0, 1.0)
    sin_u = -np.sqrt(1.0 - cos_u**2)
    # dx/du = (r_s cos u cos v, r_s cos u sin v, -r_l sin u),
    # dx/dv = r_s sin u (-sin v, cos v, 0) with sin u <= 0
    du = np.concatenate([a * cos_u * cos_v, a * cos_u * sin_v, -c * sin_u], axis=-1)
    e_u = du / np.linalg.norm(du, axis=-1, keepdims=True)
    e_v = np.concatenate([sin_v, -cos_v, np.zeros_like(cos_v)], axis=-1)
    n = np.cross(e_v, e_u)  # outward (dx/du x dx/dv points into the cavity for sin u <= 0)
    return t, e_u, e_v, n / np.linalg.norm(n, axis=-1, keepdims=True)


def land_frames(
    points: np.ndarray,
    endo_angle: float = LAND_ENDO_ANGLE,
    epi_angle: float = LAND_EPI_ANGLE,
    endo=LAND_ENDO,
    epi=LAND_EPI,
) -> np.ndarray:
    """Frames (rows: fibre, sheet = outward normal, fibre x normal) of Land's rule at points.

    Parameters
    ----------
    points
        ``(..., 3)`` coordinates in the wall (element barycentres, or quadrature points).
    endo_angle, epi_angle
        Helix angle ``alpha`` (degrees) at ``t = 0`` and ``t = 1``; the fibre is
        ``sin(alpha) e_u + cos(alpha) e_v``.
    endo, epi
        As for :func:`ellipsoid_parameter`.

    Returns
    -------
    numpy.ndarray
        ``(..., 3, 3)`` orthonormal frames.

    Examples
    --------
    >>> import numpy as np
    >>> q = land_frames(np.array([[0.0, 8.5, 0.0]]))  # mid-wall (t = 0.5): alpha = 0, f = e_v
    >>> (q[0, 0].round(12) + 0.0).tolist(), bool(np.allclose(q[0] @ q[0].T, np.eye(3)))
    ([-1.0, 0.0, 0.0], True)
    """
    t, e_u, e_v, n = land_basis(points, endo, epi)
    alpha = np.radians(endo_angle + (epi_angle - endo_angle) * t)[..., None]
    f = np.sin(alpha) * e_u + np.cos(alpha) * e_v
    f /= np.linalg.norm(f, axis=-1, keepdims=True)
    return np.stack([f, n, np.cross(f, n)], axis=-2)
